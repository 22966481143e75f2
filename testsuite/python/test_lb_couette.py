"""Couette flow: fluid between a fixed wall (x = x0) and a wall moving with
velocity V along z (x = x1), halfway bounce-back with the moving-wall term.

Steady state: u_z(x) = V (x - x0) / H, H = x1 - x0 (walls midway between the
last fluid and the first solid node). A linear profile is reproduced exactly
by bounce-back with BGK and TRT (any relaxation rate): relative error at the
nodes < 1e-8. MRT relaxes the even ghost modes at a rate of its own, which
bounce-back couples to the wall shear: a slip of order 1e-5 of V at the
moving wall remains, so MRT gets a tolerance of 1e-4 (profile and force).
Wall shear stress eta V / H times the wall area A: LBBoundary.get_force()
must give -eta V A / H along z on the moving wall and +eta V A / H on the
fixed one, relative error < 1e-6 (BGK, TRT), and no normal or y component (< 1e-8 of it).
"""
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes


class Couette(unittest.TestCase):

    def run_couette(self, collision, rtol=1e-8, ftol=1e-6):
        agrid, tau, dens, n = 0.5, 0.1, 1.5, 10
        visc = 0.3 * agrid ** 2 / tau  # nu_lattice 0.3
        length = (n + 2) * agrid
        system = lbmd.System(box_l=[length, 3 * agrid, 4 * agrid])
        system.time_step = tau
        lbf = lbmd.lb.LBFluid(agrid=agrid, dens=dens, visc=visc, tau=tau, collision=collision)
        system.actors.add(lbf)
        v_wall = 0.05 * agrid / tau
        fixed = lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[1, 0, 0], dist=agrid))
        moving = lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[-1, 0, 0], dist=-(length - agrid)),
            velocity=[0, 0, v_wall])
        system.lbboundaries.add(fixed)
        system.lbboundaries.add(moving)
        self.assertEqual(len(system.lbboundaries), 2)
        system.integrator.run(int(30 * n ** 2 / 0.3))
        height = n * agrid
        x = (np.arange(n) + 1.5) * agrid
        u = lbf[1:n + 1, 1, 2].velocity
        expected = v_wall * (x - agrid) / height
        np.testing.assert_allclose(u[:, 2], expected, rtol=rtol, atol=1e-12 * v_wall)
        np.testing.assert_allclose(u[:, :2], 0.0, atol=1e-12 * v_wall)
        # boundary nodes report the wall velocity
        np.testing.assert_allclose(lbf[n + 1, 0, 0].velocity, [0, 0, v_wall])
        self.assertEqual(lbf[n + 1, 0, 0].boundary, 2)
        self.assertEqual(lbf[0, 0, 0].boundary, 1)
        self.assertEqual(lbf[3, 0, 0].boundary, 0)
        area = system.box_l[1] * system.box_l[2]
        stress = dens * visc * v_wall / height
        f_moving, f_fixed = moving.get_force(), fixed.get_force()
        np.testing.assert_allclose(f_moving[2], -stress * area, rtol=ftol)
        np.testing.assert_allclose(f_fixed[2], stress * area, rtol=ftol)
        # normal components: the wall pressure acts on both walls, opposite
        np.testing.assert_allclose(f_moving[0], -f_fixed[0], rtol=1e-10)
        self.assertLess(abs(f_moving[1]), 1e-8 * stress * area)

    def test_mrt(self):
        self.run_couette("MRT", rtol=1e-4, ftol=1e-4)

    def test_trt(self):
        self.run_couette("TRT")

    def test_bgk(self):
        self.run_couette("BGK")


if __name__ == "__main__":
    unittest.main()
