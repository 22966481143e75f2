"""LBFluid / LBBoundary API: every parameter's bad input gives a clear
ValueError or TypeError naming it; actor add/remove; node access and slices;
set/get round trips (exact to 1e-12); VTK output read back with Debian's
python3-vtk9 (values equal to 1e-12); instability stops the run with
lbmd.SimulationInstability naming the node and the lattice update."""
import os
import tempfile
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes

GOOD = dict(agrid=1.0, dens=1.0, visc=1.0, tau=0.1)


def system(box=(4.0, 5.0, 6.0), dt=0.05):
    s = lbmd.System(box_l=list(box))
    s.time_step = dt
    return s


class BadInput(unittest.TestCase):

    def check(self, exc, name, **changes):
        kwargs = dict(GOOD, **changes)
        with self.assertRaisesRegex(exc, name):
            lbmd.lb.LBFluid(**kwargs)

    def test_constructor(self):
        for name, bad in (("agrid", 0.0), ("agrid", -1.0), ("dens", 0.0), ("dens", -2.0),
                          ("visc", 0.0), ("visc", -1.0), ("tau", 0.0), ("tau", -0.1),
                          ("bulk_visc", 0.0), ("bulk_visc", -1.0), ("kT", -1.0),
                          ("seed", -1), ("n_threads", -1), ("agrid", float("nan")),
                          ("visc", float("inf")), ("collision", "LBGK"),
                          ("ext_force_density", [1.0, 2.0]),
                          ("ext_force_density", [0, 0, float("nan")])):
            self.check(ValueError, name, **{name: bad})
        for name, bad in (("agrid", "1"), ("dens", None), ("seed", 1.5), ("collision", 3),
                          ("ext_force_density", "abc")):
            self.check(TypeError, name, **{name: bad})
        with self.assertRaisesRegex(TypeError, "missing required parameter 'visc'"):
            lbmd.lb.LBFluid(agrid=1.0, dens=1.0, tau=0.1)
        with self.assertRaisesRegex(TypeError, "unknown parameter"):
            lbmd.lb.LBFluid(viscosity=1.0, **GOOD)
        with self.assertRaisesRegex(ValueError, "seed"):
            lbmd.lb.LBFluid(kT=1.0, **GOOD)

    def test_relaxation_rate_and_geometry(self):
        s = system()
        # MRT bulk relaxation rate 2 / (9 nu_b + 1) -> 2 when bulk_visc -> 0
        with self.assertRaisesRegex(ValueError, r"bulk_visc.*relaxation rate.*\(0, 2\)"):
            s.actors.add(lbmd.lb.LBFluid(bulk_visc=1e-30, **GOOD))
        with self.assertRaisesRegex(ValueError, r"visc.*relaxation rate.*\(0, 2\)"):
            s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1e-30, tau=0.1))
        with self.assertRaisesRegex(ValueError, "agrid.*does not divide the box"):
            s.actors.add(lbmd.lb.LBFluid(agrid=0.7, dens=1.0, visc=1.0, tau=0.1))
        with self.assertRaisesRegex(ValueError, "tau.*integer multiple of the time_step"):
            s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.12))
        self.assertEqual(len(s.actors), 0)
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        with self.assertRaisesRegex(ValueError, "time_step"):
            s.time_step = 0.03
        with self.assertRaisesRegex(ValueError, "already"):
            s.actors.add(lbf)
        with self.assertRaisesRegex(ValueError, "already has"):
            s.actors.add(lbmd.lb.LBFluid(**GOOD))
        s2 = lbmd.System(box_l=[4, 4, 4])
        with self.assertRaisesRegex(ValueError, "time_step"):
            s2.actors.add(lbmd.lb.LBFluid(**GOOD))

    def test_boundary(self):
        with self.assertRaisesRegex(TypeError, "shape"):
            lbmd.lbboundaries.LBBoundary(shape="wall")
        with self.assertRaisesRegex(TypeError, "missing required parameter 'shape'"):
            lbmd.lbboundaries.LBBoundary(velocity=[0, 0, 0])
        wall = lbmd.shapes.Wall(normal=[1, 0, 0], dist=1.0)
        with self.assertRaisesRegex(ValueError, "velocity"):
            lbmd.lbboundaries.LBBoundary(shape=wall, velocity=[1, 2])
        with self.assertRaisesRegex(ValueError, "velocity"):
            lbmd.lbboundaries.LBBoundary(shape=wall, velocity=[1, 2, float("nan")])
        with self.assertRaisesRegex(TypeError, "unknown parameter"):
            lbmd.lbboundaries.LBBoundary(shape=wall, speed=1.0)
        s = system()
        with self.assertRaisesRegex(TypeError, "LBBoundary"):
            s.lbboundaries.add(wall)
        b = lbmd.lbboundaries.LBBoundary(shape=wall)
        with self.assertRaisesRegex(RuntimeError, "add it"):
            b.get_force()
        s.lbboundaries.add(b)
        with self.assertRaisesRegex(RuntimeError, "no lattice-Boltzmann fluid"):
            b.get_force()
        with self.assertRaisesRegex(ValueError, "already"):
            s.lbboundaries.add(b)
        with self.assertRaisesRegex(ValueError, "not added"):
            s.lbboundaries.remove(lbmd.lbboundaries.LBBoundary(shape=wall))

    def test_node_access_errors(self):
        s = system()
        lbf = lbmd.lb.LBFluid(**GOOD)
        with self.assertRaisesRegex(RuntimeError, "add the fluid"):
            lbf[0, 0, 0].velocity
        s.actors.add(lbf)
        for key in ((4, 0, 0), (0, -1, 0), (0, 0), (0.5, 0, 0)):
            with self.assertRaises(IndexError):
                lbf[key].velocity
        with self.assertRaisesRegex(ValueError, "density"):
            lbf[0, 0, 0].density = -1.0
        with self.assertRaisesRegex(ValueError, "does not fit"):
            lbf[:, 0, 0].velocity = np.zeros((3, 3))
        with self.assertRaisesRegex(ValueError, "finite"):
            lbf[0, 0, 0].population = [np.nan] * 19
        with self.assertRaises(AttributeError):
            lbf[0, 0, 0].boundary = 1
        with self.assertRaisesRegex(AttributeError, "cannot be set"):
            lbf.visc = 2.0
        with self.assertRaisesRegex(TypeError, "path"):
            lbf.write_vtk_velocity(3)
        with self.assertRaisesRegex(ValueError, "cannot open"):
            lbf.write_vtk_velocity("/nonexistent/dir/v.vtk")
        with self.assertRaisesRegex(ValueError, "NUL"):  # C would cut the name there
            lbf.write_vtk_velocity("/tmp/v\0x.vtk")
        # a misspelt property was stored on the temporary node object (before)
        with self.assertRaisesRegex(AttributeError, "no property 'vel'"):
            lbf[0, 0, 0].vel = [0.01, 0, 0]
        with self.assertRaisesRegex(AttributeError, "no property 'densiy'"):
            lbf[:, :, :].densiy = 2.0
        with self.assertRaisesRegex(ValueError, "add up to a density > 0"):
            lbf[0, 0, 0].population = [-1.0] * 19
        np.testing.assert_allclose(lbf[0, 0, 0].density, 1.0)

    def test_numbers_beyond_the_engine_types(self):
        for name, value in (("seed", 2**70), ("n_threads", 2**40), ("n_threads", 10**4)):
            with self.assertRaisesRegex(ValueError, f"'{name}'"):
                lbmd.lb.LBFluid(**GOOD, **{name: value})
        s = system()
        with self.assertRaisesRegex(ValueError, "'seed'"):
            s.thermostat.set_langevin(kT=1.0, gamma=1.0, seed=2**64)
        with self.assertRaisesRegex(ValueError, "'steps'"):
            s.integrator.run(2**31)

    def test_whole_box_boundary_refused(self):
        """A boundary that leaves no fluid node: refused, naming the
        boundaries, at the first use of the fluid (the flagging is lazy);
        removed, the fluid is as before (before: accepted, the fluid had zero
        mass but read density 1)."""
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        wall = lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=0.6))
        s.lbboundaries.add(wall)
        mass = lbf.total_mass()
        everything = s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=100.0)))
        with self.assertRaisesRegex(ValueError, r"\(0: Wall, 1: Wall\) cover every lattice node, "
                                                "no fluid is left"):
            lbf.total_mass()
        with self.assertRaisesRegex(ValueError, "no fluid is left"):
            s.integrator.run(1)
        s.lbboundaries.remove(everything)
        self.assertEqual(len(s.lbboundaries), 1)
        self.assertEqual(lbf.total_mass(), mass)
        self.assertEqual(lbf[0, 0, 0].boundary, 1)
        self.assertEqual(lbf[0, 0, 1].boundary, 0)

    def test_lattice_too_large(self):
        s = lbmd.System(box_l=[32.768] * 3)  # 32768^3 nodes
        s.time_step = 1e-6
        with self.assertRaisesRegex(ValueError, "2\\^50 bytes"):
            s.actors.add(lbmd.lb.LBFluid(agrid=1e-3, dens=1.0, visc=1e-6, tau=1e-6))

    def test_vtk_device_refused(self):
        """A device is never replaced by the write-then-rename output."""
        import os
        import stat
        if not os.path.exists("/dev/full") or not stat.S_ISCHR(os.stat("/dev/full").st_mode):
            self.skipTest("no /dev/full")
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        # files are written under a temporary name and renamed over the
        # target: a device is refused before anything is written
        with self.assertRaisesRegex(ValueError, "not a regular file"):
            lbf.write_vtk_velocity("/dev/full")
        self.assertTrue(stat.S_ISCHR(os.stat("/dev/full").st_mode))


class Access(unittest.TestCase):

    def test_round_trips_and_slices(self):
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD, ext_force_density=[0.01, 0, 0]))
        self.assertEqual(lbf.shape, (4, 5, 6))
        self.assertAlmostEqual(lbf.total_mass(), 120.0, delta=1e-12 * 120)
        lbf[1, 2, 3].velocity = [0.1, -0.2, 0.05]
        np.testing.assert_allclose(lbf[1, 2, 3].velocity, [0.1, -0.2, 0.05], rtol=1e-12)
        lbf[1, 2, 3].density = 1.2
        self.assertAlmostEqual(lbf[1, 2, 3].density, 1.2, delta=1e-12)
        np.testing.assert_allclose(lbf[1, 2, 3].velocity, [0.1, -0.2, 0.05], rtol=1e-12)
        pops = np.linspace(0.01, 0.1, 19)
        lbf[0, 0, 0].population = pops
        np.testing.assert_allclose(lbf[0, 0, 0].population, pops, rtol=1e-15)
        self.assertEqual(lbf[:, :, 5].velocity.shape, (4, 5, 3))
        self.assertEqual(lbf[:, 1, :].density.shape, (4, 6))
        self.assertEqual(lbf[::2, 1:4, -1:].population.shape, (2, 3, 1, 19))
        self.assertEqual(lbf[0, 0, 0].pressure_tensor.shape, (3, 3))
        # pressure tensor at rest: rho c_s^2 I in MD units (agrid / tau)^2
        np.testing.assert_allclose(lbf[2, 2, 2].pressure_tensor,
                                   np.eye(3) / 3 * (1.0 / 0.1) ** 2, rtol=1e-12)
        v = np.random.default_rng(2).uniform(-0.1, 0.1, (4, 5, 3))
        lbf[:, :, 4].velocity = v
        np.testing.assert_allclose(lbf[:, :, 4].velocity, v, rtol=1e-12, atol=1e-15)
        s.actors.remove(lbf)
        self.assertEqual(len(s.actors), 0)
        np.testing.assert_allclose(s.analysis.linear_momentum(), 0.0)

    def test_vtk_read_back(self):
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
        s = system(box=(3.0, 4.0, 5.0))
        lbf = s.actors.add(lbmd.lb.LBFluid(agrid=0.5, dens=1.0, visc=1.0, tau=0.1))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[0, 1, 0], dist=1.0)))
        lbf[:, 3:, :].velocity = np.random.default_rng(3).uniform(-0.2, 0.2, (6, 5, 10, 3))
        with tempfile.TemporaryDirectory() as d:
            for what in ("velocity", "boundary"):
                path = os.path.join(d, f"{what}.vtk")
                getattr(lbf, f"write_vtk_{what}")(path)
                reader = vtk.vtkStructuredPointsReader()
                reader.SetFileName(path)
                reader.Update()
                data = reader.GetOutput()
                self.assertEqual(data.GetDimensions(), (6, 8, 10))
                np.testing.assert_allclose(data.GetSpacing(), [0.5] * 3)
                np.testing.assert_allclose(data.GetOrigin(), [0.25] * 3)
                arr = vtk_to_numpy(data.GetPointData().GetArray(what))
                # VTK point order: x fastest
                ours = getattr(lbf[:, :, :], what)
                ours = np.asarray(ours, dtype=float).transpose(2, 1, 0, *range(3, np.ndim(ours)))
                np.testing.assert_allclose(arr.reshape(ours.shape), ours, rtol=1e-12, atol=1e-15)
        self.assertEqual(lbf[0, 1, 0].boundary, 1)
        self.assertEqual(lbf[0, 2, 0].boundary, 0)

    def test_boundaries_before_fluid_and_removal(self):
        s = system(box=(4.0, 6.0, 4.0))
        wall = lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 1, 0], dist=2.0))
        s.lbboundaries.add(wall)
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        np.testing.assert_array_equal(lbf[0, :, 0].boundary, [1, 1, 0, 0, 0, 0])
        self.assertEqual(lbf._core.n_fluid_nodes, 4 * 4 * 4)
        self.assertAlmostEqual(lbf.total_mass(), 64.0, delta=1e-12 * 64)
        s.lbboundaries.remove(wall)
        np.testing.assert_array_equal(lbf[0, :, 0].boundary, [0] * 6)
        # freed nodes restart at rest at dens
        self.assertAlmostEqual(lbf.total_mass(), 96.0, delta=1e-12 * 96)
        np.testing.assert_allclose(lbf[0, 0, 0].velocity, 0.0, atol=1e-15)
        s.lbboundaries.add(wall)
        s.lbboundaries.clear()
        self.assertEqual(len(s.lbboundaries), 0)
        s.prepare()  # the fluid's plain attributes never flag (doc/engine.md)
        self.assertEqual(lbf._core.n_fluid_nodes, 96)


class InPlaceLayout(unittest.TestCase):
    """The lattice is updated in place (AA pattern): after an odd number of
    updates populations live in swapped places. Node access, totals and a
    geometry change must not see it: a fluid copied node by node into a fresh
    fluid (normal layout) after 3 updates must evolve identically, with a wall
    added after the copy, to round-off (1e-15 relative)."""

    def make(self):
        s = system(box=(6.0, 5.0, 4.0))
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD, ext_force_density=[0.01, 0.002, 0]))
        return s, lbf

    def test_swapped_state_is_invisible(self):
        s, lbf = self.make()
        lbf[:, :, :].velocity = np.random.default_rng(5).uniform(-0.3, 0.3, (6, 5, 4, 3))
        s.integrator.run(6)  # 3 lattice updates: swapped layout
        self.assertEqual(lbf._core.n_updates % 2, 1)
        pops = lbf[:, :, :].population
        self.assertAlmostEqual(lbf.total_mass(), pops.sum(), delta=1e-12 * pops.sum())
        # round trip at a corner node, whose populations sit in ghost places
        p0 = np.linspace(0.02, 0.08, 19)
        lbf[0, 0, 0].population = p0
        np.testing.assert_allclose(lbf[0, 0, 0].population, p0, rtol=1e-15)
        lbf[0, 0, 0].population = pops[0, 0, 0]
        s2, copy = self.make()
        for i in range(6):
            for j in range(5):
                for k in range(4):
                    copy[i, j, k].population = pops[i, j, k]
        wall = lambda: lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[0, 1, 0], dist=1.0), velocity=[0.05, 0, 0])
        s.lbboundaries.add(wall())
        s2.lbboundaries.add(wall())
        np.testing.assert_allclose(lbf[:, 1:, :].population, pops[:, 1:], rtol=1e-15)
        s.integrator.run(10)
        s2.integrator.run(10)
        np.testing.assert_allclose(lbf[:, :, :].population, copy[:, :, :].population,
                                   rtol=1e-15, atol=1e-17)
        np.testing.assert_allclose(s.lbboundaries[0].get_force(), s2.lbboundaries[0].get_force(),
                                   rtol=1e-13)


    def test_threads_agree_with_serial(self):
        """In place and in parallel: every node reads and writes only its own
        19 places, so 2 and 3 threads give bit for bit the serial result
        (walls, a moving wall, a sphere, coupled particles, odd and even
        update counts)."""
        results = []
        for threads in (1, 2, 3):
            s = system(box=(14.0, 9.0, 8.0))
            lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD, ext_force_density=[0.01, 0, 0.003],
                                               n_threads=threads))
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
                shape=lbmd.shapes.Wall(normal=[0, 1, 0], dist=1.0), velocity=[0.2, 0, 0]))
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
                shape=lbmd.shapes.Sphere(center=[7, 5, 4], radius=2.2)))
            rng = np.random.default_rng(8)
            s.part.add(pos=rng.uniform(0, 1, (30, 3)) * [14, 9, 8], v=rng.normal(0, 0.1, (30, 3)))
            if lbf._core.n_threads != threads:
                self.skipTest("built without OpenMP")
            s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
            out = []
            for n in (6, 4):  # 3 then 5 lattice updates
                s.integrator.run(n)
                out.append(lbf[:, :, :].population.copy())
            out.append(s.part.all().pos.copy())
            results.append(out)
        for other in results[1:]:
            for a, b in zip(results[0], other):
                np.testing.assert_array_equal(a, b)


class Instability(unittest.TestCase):

    def test_supersonic_node(self):
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        p = s.part.add(pos=[1.0, 1.0, 1.0], v=[0.1, 0, 0])
        s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
        lbf[2, 3, 4].velocity = [0.0, 0.65 * 1.0 / 0.1, 0.0]  # 0.65 lattice units > c_s
        with self.assertRaisesRegex(lbmd.SimulationInstability,
                                    r"node \(2, 3, 4\) in lattice update 0"):
            s.integrator.run(2)
        # the failed update stopped half way: the fluid takes no more updates
        # (its populations mix two time levels) and a run is refused before
        # anything moves; the fields can still be read
        time, pos, v = s.time, np.copy(p.pos), np.copy(p.v)
        for steps in (2, 0):
            with self.assertRaisesRegex(lbmd.SimulationInstability,
                                        r"not usable: an earlier update failed .*node \(2, 3, 4\) "
                                        r"in lattice update 0.*create a new fluid"):
                s.integrator.run(steps)
        self.assertEqual(s.time, time)
        np.testing.assert_array_equal(p.pos, pos)
        np.testing.assert_array_equal(p.v, v)
        # away from the bad node the fluid did not move yet (one half update)
        np.testing.assert_allclose(lbf[3, 0, 5].velocity, [0, 0, 0], atol=1e-12)

    def test_stiff_coupling_named(self):
        """gamma dt / m = 5: the coupled particle and node overshoot and the
        fluid blows up; the message names the coupling, not only the fluid."""
        s = system(dt=0.1)
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        s.part.add(pos=[2.0, 2.5, 3.0], v=[1.0, 0, 0])
        s.thermostat.set_lb(LB_fluid=lbf, gamma=50.0)
        with self.assertRaisesRegex(lbmd.SimulationInstability,
                                    r"gamma \* time_step / mass = 5\b.*lower gamma"):
            s.integrator.run(200)

    def test_supersonic_node_odd_update(self):
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        s.integrator.run(2)  # one update: the next one reads from neighbours
        lbf[0, 4, 5].velocity = [0.0, 0.0, -0.7 / 0.1]
        with self.assertRaisesRegex(lbmd.SimulationInstability,
                                    r"node \(0, 4, 5\) in lattice update 1: density 1"):
            s.integrator.run(2)

    def test_relaxation_rate_near_two(self):
        # omega_s = 1.99 (nu_lattice = 0.0017) with a strong driving force:
        # the run blows up; it must stop with the exception, never return NaN
        s = system(box=(16.0, 16.0, 16.0), dt=1.0)
        lbf = s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=(1 / 1.99 - 0.5) / 3,
                                           tau=1.0, ext_force_density=[0.02, 0, 0]))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Sphere(center=[8, 8, 8], radius=4)))
        with self.assertRaisesRegex(lbmd.SimulationInstability,
                                    r"node \(\d+, \d+, \d+\) in lattice update \d+"):
            for _ in range(200):
                s.integrator.run(10)
                self.assertTrue(np.all(np.isfinite(lbf[:, :, 8].velocity)))


if __name__ == "__main__":
    unittest.main()
