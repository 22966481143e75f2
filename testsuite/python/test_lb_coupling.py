"""Particle-fluid coupling (model eq. 1), through system.thermostat.set_lb.

- Relaxation: a particle of mass m launched with v0 into a heavy fluid at
  rest slows as v0 exp(-gamma t / m) (the fluid it drags along is ~1000
  times heavier): the relaxation time fitted over t < 1.5 m / gamma must be
  within 2 % of m / gamma, and the speed at t = m / gamma within 2 % of v0/e.
- Momentum: particle + fluid momentum (system.analysis.linear_momentum) is
  conserved to round-off (1e-12 of m v0) after every MD step, with
  tau = 5 time steps (the fluid gets the impulse at its next update) and the
  particle crossing the periodic boundary at a corner, and forces recomputed
  without a time step every third step; also with kT > 0
  (fluid and coupling noise both conserve it). A boundary added while
  coupling impulses wait for the next update (a run that ended between
  two updates) keeps them: the momentum stays exact (1e-12).
- Deposits reach the populations: with particles spread over a box of many
  force-field chunks (64 nodes each; an update applies only the chunks that
  received a deposit) and tau = time step, the momentum of the populations
  after each update (the sum of density * velocity over the nodes, no force
  field involved) equals what the particles gave: p0 - P - dt/2 sum F (the
  fluid has the whole impulse of the last coupling force F, the particles
  only half of it so far), to 1e-12 of p0.
- The coupling force is gamma (u(x) - v) with u the fluid velocity at the
  particle from lbf.get_interpolated_velocity (1e-12 of gamma |u - v|),
  for 26 particles in a swirling flow checked after every 10 of 300 steps,
  as they cross many lattice cells (the coupling keeps its node numbering
  from step to step and renumbers every 64 steps).
- The interpolated velocity is trilinear: in a linear velocity field set on
  the nodes it is exact away from the periodic seam (1e-12).
- A run split into calls is the run in one call: 40 steps as
  integrator.run(40) and as 40 x integrator.run(1) (tau = 5 time steps, so
  calls also end between lattice updates; with and without thermal noise)
  give identical positions and velocities, bit for bit (a call must not
  recompute the forces of the last step against the fluid updated since).
  But when the fluid is changed between two calls (a node's velocity or
  density, ext_force_density),
  the next call starts from coupling forces against the changed fluid:
  the same, bit for bit, as with recalc_forces=True, and different from
  the forces of the last step.
"""
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes


def make(kT=0.0, dens=50.0, box=(8.0, 8.0, 8.0), time_step=0.01, visc=3.0, tau=0.05, gamma=2.0,
         periodicity=(True, True, True)):
    """A system with a fluid (agrid 1) coupled to its particles."""
    system = lbmd.System(box_l=list(box), periodicity=list(periodicity))
    system.time_step = time_step
    lbf = lbmd.lb.LBFluid(agrid=1.0, dens=dens, visc=visc, tau=tau, kT=kT, seed=3)
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma, seed=7)
    return system, lbf


class Coupling(unittest.TestCase):

    def test_relaxation_time(self):
        system, lbf = make()
        m, gamma, v0 = 1.0, 2.0, 0.1
        p = system.part.add(pos=[3.3, 4.1, 2.7], v=[v0, 0, 0], mass=m)
        times, speeds = [], []
        for step in range(1, 151):
            system.integrator.run(1)
            times.append(step * system.time_step)
            speeds.append(p.v[0])
        times, speeds = np.array(times), np.array(speeds)
        t_relax = -1.0 / np.polyfit(times, np.log(speeds), 1)[0]
        self.assertAlmostEqual(t_relax / (m / gamma), 1.0, delta=0.02)
        self.assertAlmostEqual(speeds[49] / (v0 / np.e), 1.0, delta=0.02)  # t = 0.5 = m/gamma

    def check_momentum(self, kT):
        system, lbf = make(kT=kT, dens=1.0)
        m, v0 = 1.0, np.array([2.0, 1.5, -1.0])
        system.part.add(pos=[7.9, 7.95, 0.05], v=v0, mass=m)
        system.part.add(pos=[1.0, 2.0, 3.0], v=[0.0, 0.3, 0.0], mass=2.0)
        p0 = system.analysis.linear_momentum()
        crossed = False
        for step in range(60):
            system.integrator.run(1)
            if step % 3 == 0:  # a recomputation takes back the in-flight half first
                system.integrator.run(0, recalc_forces=True)
            np.testing.assert_allclose(system.analysis.linear_momentum(), p0, rtol=0,
                                       atol=1e-12 * m * np.linalg.norm(v0))
            crossed |= bool(np.any(system.part.by_id(0).pos > 8.0))
        self.assertTrue(crossed)
        # the fluid did take momentum
        self.assertGreater(np.linalg.norm(lbf.total_momentum()), 0.1 * m * np.linalg.norm(v0))

    def test_momentum_conservation(self):
        self.check_momentum(0.0)

    def test_split_run_equals_one_run(self):
        for kT in (0.0, 1e-4):
            states = []
            for calls in (1, 40):
                system, lbf = make(kT=kT, dens=1.0)
                system.part.add(pos=[[1.2, 3.4, 5.6], [6.5, 4.3, 2.1], [7.9, 0.1, 4.0]],
                                v=[[0.3, -0.2, 0.1], [0.0, 0.4, -0.3], [-0.5, 0.0, 0.2]])
                for _ in range(calls):
                    system.integrator.run(40 // calls)
                states.append(np.concatenate([system.part.all().pos, system.part.all().v]))
            np.testing.assert_array_equal(states[0], states[1])
            self.assertGreater(np.abs(states[0][3:] - [[0.3, -0.2, 0.1], [0.0, 0.4, -0.3],
                                                       [-0.5, 0.0, 0.2]]).max(), 1e-3)

    def test_fluid_changed_between_runs(self):
        def set_velocity(lbf):
            lbf[3, 3, 3].velocity = [0.0, 0.5, 0.0]

        def set_density(lbf):
            lbf[3, 3, 3].density = 1.3

        def set_ext_force(lbf):
            lbf.ext_force_density = [0.0, 0.02, 0.0]

        for change in (set_velocity, set_density, set_ext_force):
            states = []
            for recalc in (False, True, None):  # None: the fluid left as it is
                system, lbf = make(dens=1.0)
                p = system.part.add(pos=[3.3, 3.6, 3.2], v=[0.1, 0.0, 0.0])
                system.integrator.run(7)
                if recalc is not None:
                    change(lbf)
                system.integrator.run(3, recalc_forces=bool(recalc))
                states.append(np.concatenate([p.pos, p.v]))
            np.testing.assert_array_equal(states[0], states[1], err_msg=change.__name__)
            # the change reached the particle
            self.assertGreater(np.abs(states[0] - states[2]).max(), 1e-6, msg=change.__name__)

    def test_boundaries_changed_between_updates(self):
        # tau = 5 time steps: a run that stops between two lattice updates
        # leaves the coupling impulses of its last steps waiting in the force
        # field; a boundary added then must not drop them. The new solid node
        # is in a corner the particle's disturbance cannot reach in the two
        # updates of the test, so particle + fluid momentum stays exact.
        system, lbf = make(dens=1.0, box=(12.0, 12.0, 12.0))
        m, v0 = 1.0, np.array([0.2, -0.1, 0.05])
        system.part.add(pos=[6.2, 5.9, 6.1], v=v0, mass=m)
        p0 = system.analysis.linear_momentum()
        system.integrator.run(7)  # updates after step 5; steps 6, 7 wait for the next
        system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Sphere(center=[0.5, 0.5, 0.5], radius=0.6)))
        self.assertEqual(lbf[0, 0, 0].boundary, 1)
        system.integrator.run(3)  # the next update (step 10) applies them
        np.testing.assert_allclose(system.analysis.linear_momentum(), p0, rtol=0,
                                   atol=1e-12 * m * np.linalg.norm(v0))
        self.assertGreater(np.linalg.norm(lbf.total_momentum()), 0.05 * m * np.linalg.norm(v0))

    def test_momentum_conservation_thermal(self):
        self.check_momentum(1e-3)

    def test_deposits_reach_populations(self):
        system, lbf = make(dens=1.0, box=(12.0, 10.0, 8.0), time_step=0.05, visc=1.0, gamma=1.0)
        rng = np.random.default_rng(5)
        for _ in range(25):
            system.part.add(pos=rng.uniform(0.0, 1.0, 3) * system.box_l, v=rng.normal(0.0, 0.5, 3))
        system.part.add(pos=[11.9, 9.95, 0.05], v=[1.0, 0.5, -0.5])  # across the periodic corner
        p0 = np.sum(system.part.all().v, axis=0)
        for _ in range(8):
            system.integrator.run(5)
            populations = np.sum(lbf[:, :, :].density[..., None] * lbf[:, :, :].velocity,
                                 axis=(0, 1, 2))
            particles = np.sum(system.part.all().v, axis=0)
            # the fluid got -F dt of the last coupling force F, the particles F dt / 2 so far
            in_flight = -0.5 * system.time_step * np.sum(system.part.all().f, axis=0)
            np.testing.assert_allclose(populations, p0 - particles + in_flight, rtol=0,
                                       atol=1e-12 * np.linalg.norm(p0))
        self.assertGreater(np.linalg.norm(populations), 0.3 * np.linalg.norm(p0))

    def test_force_uses_interpolated_velocity(self):
        gamma = 1.5
        system, lbf = make(dens=1.0, box=(12.0, 10.0, 8.0), time_step=0.05, visc=1.0, gamma=gamma)
        x, y, z = (np.indices((12, 10, 8)) + 0.5)
        lbf[:, :, :].velocity = np.stack([0.9 * np.sin(2 * np.pi * y / 10), 0.6 * np.cos(2 * np.pi * z / 8),
                                          0.75 * np.sin(2 * np.pi * x / 12)], axis=-1)
        rng = np.random.default_rng(11)
        for _ in range(25):
            system.part.add(pos=rng.uniform(0.0, 1.0, 3) * system.box_l, v=rng.normal(0.0, 0.5, 3))
        system.part.add(pos=[11.9, 9.95, 0.05], v=[1.0, 0.5, -0.5])  # across the periodic corner
        start = np.array(system.part.all().pos)
        for _ in range(30):
            system.integrator.run(10)
            system.integrator.run(0, recalc_forces=True)  # forces from this fluid state
            for p in system.part.all():
                expected = gamma * (lbf.get_interpolated_velocity(p.pos) - p.v)
                np.testing.assert_allclose(p.f, expected, rtol=0, atol=1e-12 * np.linalg.norm(expected))
        travelled = np.linalg.norm(np.array(system.part.all().pos) - start, axis=1)
        self.assertGreater(np.median(travelled), 2.0)  # across many stencils

    def test_trilinear_interpolation(self):
        system, lbf = make()
        grad = np.array([[0.01, 0.0, 0.02], [0.0, -0.01, 0.0], [0.005, 0.0, 0.0]])
        nodes = (np.indices((8, 8, 8)).transpose(1, 2, 3, 0) + 0.5)
        lbf[:, :, :].velocity = nodes @ grad.T
        for pos in ([1.2, 3.7, 5.1], [4.0, 4.0, 4.0], [0.5, 6.9, 2.25]):
            np.testing.assert_allclose(lbf.get_interpolated_velocity(pos), grad @ np.array(pos),
                                       rtol=1e-12, atol=1e-14)

    def test_particle_outside_a_non_periodic_axis(self):
        """Between walls at z = 0.5 and 7.5 of a box non-periodic in z, a
        particle at z = 12.7 coupled to the fluid on the wrapped side
        (before); now the run stops naming it, and once it is moved back the
        coupling goes on from a consistent node list."""
        system, lbf = make(dens=1.0, time_step=0.1, visc=1.0, tau=0.1, gamma=1.0,
                           periodicity=(True, True, False))
        for normal, dist in (([0, 0, 1], 0.5), ([0, 0, -1], -7.5)):
            system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
                shape=lbmd.shapes.Wall(normal=normal, dist=dist)))
        system.part.add(pos=[[2.0, 2.0, 3.0], [4.0, 4.0, 4.0]])
        system.integrator.run(3)
        p = system.part.add(pos=[3.0, 3.0, 4.0], v=[0.01, 0, 0])  # (add refuses a position outside)
        p.pos = [3.0, 3.0, 12.7]
        with self.assertRaisesRegex(lbmd.SimulationInstability,
                                    r"particle 2 at 12.7 along the non-periodic axis 2 left the box"):
            system.integrator.run(1)
        p.pos = [3.0, 3.0, 4.0]
        system.integrator.run(70)  # a renumbering of the node list included
        self.assertTrue(np.all(np.isfinite(system.part.all().v)))
        self.assertLess(np.linalg.norm(p.v), 0.01)  # damped by the fluid


if __name__ == "__main__":
    unittest.main()
