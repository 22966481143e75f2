"""Mass and momentum conservation over 1000 lattice updates from random
populations in a periodic box (all three collision models): the relative
change of the total mass and of each momentum component (scaled by the mass
times a lattice speed) must stay below 1e-12 (round-off). With a uniform
ext_force_density f the momentum grows by exactly f V tau per update
(relative 1e-12). With bounce-back walls the mass is still conserved
(1e-12); with moving walls too (tangential motion)."""
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes

W = np.array([1 / 3] + [1 / 18] * 6 + [1 / 36] * 12)


def make(collision, shape=(6, 5, 7), agrid=0.5, tau=0.2, ext=(0, 0, 0), seed=5):
    system = lbmd.System(box_l=np.array(shape) * agrid)
    system.time_step = tau / 2
    lbf = lbmd.lb.LBFluid(agrid=agrid, dens=1.3, visc=0.2 * agrid ** 2 / tau, tau=tau,
                          collision=collision, ext_force_density=list(ext))
    system.actors.add(lbf)
    rng = np.random.default_rng(seed)
    pops = 1.3 * W * (1 + 0.3 * rng.uniform(-1, 1, size=tuple(shape) + (19,)))
    lbf[:, :, :].population = pops
    return system, lbf


class Conservation(unittest.TestCase):

    def test_random_populations(self):
        for collision in ("MRT", "TRT", "BGK"):
            system, lbf = make(collision)
            m0, p0 = lbf.total_mass(), lbf.total_momentum()
            scale = m0 * lbf.agrid / lbf.tau
            self.assertGreater(np.linalg.norm(p0), 1e-3 * scale)  # the state is not trivial
            system.integrator.run(2000)  # 1000 lattice updates
            self.assertEqual(lbf._core.n_updates, 1000)
            self.assertLess(abs(lbf.total_mass() - m0) / m0, 1e-12, collision)
            np.testing.assert_allclose(lbf.total_momentum(), p0, rtol=0, atol=1e-12 * scale,
                                       err_msg=collision)
            # and the state did relax (the collision acted)
            pops = lbf[:, :, :].population
            self.assertLess(np.std(pops[..., 0]), 0.05 * 1.3 / 3 * 0.3)

    def test_external_force(self):
        ext = np.array([1e-4, -2e-4, 5e-5])
        system, lbf = make("MRT", ext=ext)
        p0 = lbf.total_momentum()
        system.integrator.run(2000)
        expected = p0 + ext * np.prod(system.box_l) * lbf.tau * 1000
        scale = lbf.total_mass() * lbf.agrid / lbf.tau
        np.testing.assert_allclose(lbf.total_momentum(), expected, rtol=0, atol=1e-12 * scale)

    def test_walls_conserve_mass(self):
        system, lbf = make("MRT", shape=(8, 5, 6))
        system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[1, 0, 0], dist=0.5)))
        system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[-1, 0, 0], dist=-3.5), velocity=[0, 0.1, 0.05]))
        m0 = lbf.total_mass()
        system.integrator.run(2000)
        self.assertLess(abs(lbf.total_mass() - m0) / m0, 1e-12)


if __name__ == "__main__":
    unittest.main()
