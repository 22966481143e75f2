"""A cell in Poiseuille flow (lattice-Boltzmann fluid between two walls,
body-force driven): it moves with the flow, migrates away from the nearer
wall (wall-induced lift on a deformable cell), and keeps its volume within
1 %. The cell is a soft spherical capsule (sphere mesh): an RBC tumbles in
the shear, and its tumbling moves its centre by more than the slow lift in
a run this short."""
import unittest

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

H_BOX = 18.0
WALL = 1.0
R = 3.0


class TestCellInPoiseuilleFlow(unittest.TestCase):

    def test_moves_with_flow_and_migrates(self):
        system = lbmd.System(box_l=[24.0, 16.0, H_BOX])
        system.time_step = 0.1
        system.cell_system.skin = 0.3
        visc, dens = 1.5, 1.0
        height = H_BOX - 2 * WALL
        u_max = 0.15
        force = 8.0 * dens * visc * u_max / height ** 2  # Poiseuille: u_max = f h^2 / (8 rho nu)
        lbf = lb.LBFluid(agrid=1.0, dens=dens, visc=visc, tau=0.1, ext_force_density=[force, 0.0, 0.0])
        system.actors.add(lbf)
        walls = [shapes.Wall(normal=[0, 0, 1], dist=WALL), shapes.Wall(normal=[0, 0, -1], dist=-(H_BOX - WALL))]
        for w in walls:
            system.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
        # let the flow develop (viscous time h^2/nu ~ 170) before the cell enters
        system.integrator.run(1500)
        u_mid = lbf.get_interpolated_velocity([12.0, 8.0, H_BOX / 2])[0]
        self.assertAlmostEqual(u_mid / u_max, 1.0, delta=0.15)

        rbc = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(R, R, R),
                              ks=0.005, kb=0.005, kal=0.01, kag=0.5, kv=5.0, normal=True)
        z0 = WALL + 4.0  # centre 4 from the bottom wall (1 gap), 4 below the channel's middle
        cell = oif.OifCell(cell_type=rbc, particle_type=0, origin=[6.0, 8.0, z0], rotate=(np.pi / 2, 0, 0))
        for w in walls:
            system.constraints.add(shape=w, particle_type=10, penetrable=False)
        system.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.0002, n=1.5, cutoff=0.8, offset=0.0)
        system.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=visc, dens=dens))

        zs, vx, ufl, vols = [], [], [], []
        for _ in range(30):
            system.integrator.run(200)
            c = cell.get_origin()
            zs.append(c[2])
            vx.append(cell.get_velocity()[0])
            ufl.append(lbf.get_interpolated_velocity(np.mod(c, system.box_l))[0])
            vols.append(cell.volume())
        zs, vx, ufl, vols = map(np.array, (zs, vx, ufl, vols))
        print(f"centre z {z0:.3f} -> {zs[-1]:.3f}, cell v_x {vx[-1]:.4f}, fluid u_x at centre {ufl[-1]:.4f}, "
              f"volume range {vols.min() / rbc.volume0:.4f} .. {vols.max() / rbc.volume0:.4f}")
        # moves with the flow: after the start-up, cell velocity within 5 % of the fluid's at its centre
        np.testing.assert_allclose(vx[10:], ufl[10:], rtol=0.05)
        self.assertGreater(vx[-1], 0.5 * u_max)
        # migrates away from the wall towards the middle, steadily (measured: 0.5 in 6000 steps)
        self.assertGreater(zs[-1] - z0, 0.3)
        self.assertLess(zs[-1], H_BOX / 2 + 0.5)
        self.assertTrue(np.all(np.diff(zs) > -1e-3))
        # volume within 1 %
        self.assertLess(np.abs(vols / rbc.volume0 - 1).max(), 0.01)


if __name__ == "__main__":
    unittest.main()
