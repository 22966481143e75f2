"""Single precision: LBFluid(single_precision=True).

The populations are stored as float deviations g_q = f_q - w_q rho0 from
the rest state at the reference density rho0 = dens, and the collision
computes in float on them (Skordos, Phys. Rev. E 48, 4823 (1993)); reading
a population adds w_q rho0 back in double. The rounding (relative 6e-8)
thus falls on the deviations, which are small near rest, and is carried
along by the flow until viscosity damps it. Measured (this file's scenes):

- Poiseuille between bounce-back walls (the helper of test_lb_poiseuille.py),
  default MRT, H = 20 nodes, peak speed 0.02 lattice units: max relative
  error 2.9e-6 at nu = 1/6 and 8.8e-6 at nu = 1 (double: 2.8e-8 and
  7.7e-6); magic TRT, 12 nodes, exact in double (1e-13): 1.9e-6. Bound
  2e-4: a lost or mis-rounded population per update would exceed it.
- Mass: a nonuniform periodic fluid with a body force, 1000 updates: the
  total mass drifts by 1.1e-9 relative (bound 1e-6; double 5e-14); the
  force accelerates the fluid to 0.2 lattice units, the deviations grow
  with it, and so does the drift: 1.5e-6 after 20000 updates.
- The same scene in float and in double, 400 updates: the velocities
  differ by 6.9e-6 of the peak speed (required: between 1e-9 and 1e-4), and
  the deviations read back (population - w_q dens) are floats (the double
  run's are not): the storage really is float.
- Thermal fluctuations: in test_lb_thermal.py (kT within 2 %, measured
  -0.4 %; total momentum zero to float round-off, 1e-4 of mass sqrt(kT),
  measured 7e-8).
- Particle coupling: particle + fluid momentum conserved to 2e-5 relative
  over 60 steps (measured 2.3e-7: the populations' rounding; double:
  1e-12), and the fluid takes it.
- Couette flow with a moving wall: linear profile to 1e-4 of the wall
  speed (measured 3.4e-7), wall force to 1e-3 (measured 3.2e-6).
- Node access, VTK output, instability detection work as in double.
The MPI decomposition in float (halo as MPI_FLOAT) is bit for bit the
serial run: scene "boundaries_single" of test_mpi_equality.py.
"""
import os
import tempfile
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes
from test_lb_poiseuille import poiseuille

# D3Q19 weights in the lattice's order: rest, 6 faces, 12 edges
WEIGHTS = np.array([1.0 / 3.0] + [1.0 / 18.0] * 6 + [1.0 / 36.0] * 12)


def as_float(x):
    return np.asarray(x).astype(np.float32).astype(float)


def periodic_fluid(single_precision, box=(10.0, 8.0, 6.0), seed=4, **kwargs):
    system = lbmd.System(box_l=list(box))
    system.time_step = 0.1
    params = dict(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, ext_force_density=[1e-3, -5e-4, 2e-4])
    params.update(kwargs)
    lbf = lbmd.lb.LBFluid(single_precision=single_precision, **params)
    system.actors.add(lbf)
    rng = np.random.default_rng(seed)
    shape = lbf.shape
    x = 2 * np.pi * (np.arange(shape[0]) + 0.5) / shape[0]
    lbf[:, :, :].velocity = (0.05 * np.sin(x)[:, None, None, None] * np.array([0.0, 1.0, 0.5])
                             + 0.01 * rng.uniform(-1, 1, tuple(shape) + (3,)))
    return system, lbf


class SinglePrecision(unittest.TestCase):

    def test_parameter(self):
        s = lbmd.System(box_l=[4.0, 4.0, 4.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1)
        self.assertFalse(lbf.single_precision)
        s.actors.add(lbf)
        self.assertFalse(lbf._core.single_precision)
        s.actors.clear()
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, single_precision=True)
        s.actors.add(lbf)
        self.assertTrue(lbf.single_precision)
        self.assertTrue(lbf._core.single_precision)
        with self.assertRaisesRegex(TypeError, "single_precision' must be True or False"):
            lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, single_precision="yes")
        with self.assertRaisesRegex(AttributeError, "cannot be set after creation"):
            lbf.single_precision = False

    def test_poiseuille(self):
        for nu, bound in ((1.0 / 6.0, 2e-4), (1.0, 2e-4)):
            _, linf = poiseuille(20, None, nu_lattice=nu, height=20.0, unit_lattice=True,
                                 single_precision=True)
            self.assertLess(linf, bound, f"default MRT, nu_lattice={nu}")
        # exact in double (1e-13): what remains is the float storage
        _, linf = poiseuille(12, "TRT", single_precision=True)
        self.assertLess(linf, 2e-4)
        self.assertGreater(linf, 1e-9, "no float round-off: is the storage float?")

    def test_mass_conservation(self):
        system, lbf = periodic_fluid(True)
        m0 = lbf.total_mass()
        drift = 0.0
        for _ in range(10):
            system.integrator.run(100)
            drift = max(drift, abs(lbf.total_mass() / m0 - 1.0))
        self.assertLess(drift, 1e-6)
        self.assertGreater(drift, 0.0, "mass exact to the last bit: float storage unused?")

    def test_float_against_double(self):
        results = {}
        for sp in (False, True):
            system, lbf = periodic_fluid(sp)
            system.integrator.run(400)
            pop = lbf[:, :, :].population
            results[sp] = (lbf[:, :, :].velocity, pop)
        u_double, pop_double = results[False]
        u_single, pop_single = results[True]
        scale = np.abs(u_double).max()
        diff = np.abs(u_single - u_double).max() / scale
        self.assertGreater(diff, 1e-9, "float and double runs agree too well: float storage unused?")
        self.assertLess(diff, 1e-4)
        # every stored deviation from w_q dens (dens = 1) is a float; in
        # double almost none is (a deviation below 2^-29 of w_q could lose
        # bits in the sum read back: allow 1 %)
        dev_single, dev_double = pop_single - WEIGHTS, pop_double - WEIGHTS
        self.assertGreater(np.mean(as_float(dev_single) == dev_single), 0.99)
        self.assertLess(np.mean(as_float(dev_double) == dev_double), 0.01)

    def test_node_access(self):
        system, lbf = periodic_fluid(True)
        pop = np.array(lbf[1, 2, 3].population)
        new = pop * (1.0 + 1e-3 * np.arange(19) / 19)
        lbf[1, 2, 3].population = new
        # the deviation from w_q dens (dens = 1) rounded to float, nothing else
        np.testing.assert_array_equal(lbf[1, 2, 3].population, as_float(new - WEIGHTS) + WEIGHTS)
        lbf[4, 5, 0].velocity = [0.01, -0.02, 0.03]
        np.testing.assert_allclose(lbf[4, 5, 0].velocity, [0.01, -0.02, 0.03], rtol=1e-5)
        lbf[4, 5, 0].density = 1.3
        self.assertAlmostEqual(lbf[4, 5, 0].density, 1.3, delta=1e-6)

    def test_coupling_momentum(self):
        system = lbmd.System(box_l=[8.0, 8.0, 8.0])
        system.time_step = 0.01
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=3.0, tau=0.05, single_precision=True)
        system.actors.add(lbf)
        system.thermostat.set_lb(LB_fluid=lbf, gamma=2.0)
        v0 = np.array([2.0, 1.5, -1.0])
        system.part.add(pos=[7.9, 7.95, 0.05], v=v0, mass=1.0)
        p0 = system.analysis.linear_momentum()
        for _ in range(60):
            system.integrator.run(1)
            np.testing.assert_allclose(system.analysis.linear_momentum(), p0, rtol=0,
                                       atol=2e-5 * np.linalg.norm(v0))
        self.assertGreater(np.linalg.norm(lbf.total_momentum()), 0.1 * np.linalg.norm(v0))

    def test_moving_wall_and_boundary_force(self):
        # Couette flow: the top wall moves at u_w along x; steady profile
        # linear between the walls (midway links), wall force = shear stress
        system = lbmd.System(box_l=[4.0, 4.0, 12.0])
        system.time_step = 1.0
        u_w, nu = 0.01, 1.0 / 6.0 + 0.2
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=nu, tau=1.0, single_precision=True)
        system.actors.add(lbf)
        system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0)))
        top = lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 0, -1], dist=-11.0),
                                           velocity=[u_w, 0, 0])
        system.lbboundaries.add(top)
        system.integrator.run(3000)
        z = np.arange(1, 11) + 0.5
        expected = u_w * (z - 1.0) / 10.0
        np.testing.assert_allclose(lbf[0, 0, 1:11].velocity[:, 0], expected, atol=1e-4 * u_w)
        # the fluid drags the moving wall back: F = -rho nu u_w / h * area
        np.testing.assert_allclose(top.get_force()[0], -nu * u_w / 10.0 * 16.0, rtol=1e-3)

    def test_vtk(self):
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
        system, lbf = periodic_fluid(True, box=(3.0, 4.0, 5.0))
        system.integrator.run(5)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "velocity.vtk")
            lbf.write_vtk_velocity(path)
            reader = vtk.vtkStructuredPointsReader()
            reader.SetFileName(path)
            reader.Update()
            arr = vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("velocity"))
        ours = lbf[:, :, :].velocity.transpose(2, 1, 0, 3)
        np.testing.assert_allclose(arr.reshape(ours.shape), ours, rtol=1e-12, atol=1e-15)

    def test_instability(self):
        s = lbmd.System(box_l=[5.0, 6.0, 7.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, single_precision=True)
        s.actors.add(lbf)
        lbf[2, 3, 4].velocity = [0.0, 0.65 / 0.1, 0.0]  # 0.65 lattice units > c_s
        with self.assertRaisesRegex(lbmd.SimulationInstability, r"node \(2, 3, 4\) in lattice update 0"):
            s.integrator.run(2)


if __name__ == "__main__":
    unittest.main()
