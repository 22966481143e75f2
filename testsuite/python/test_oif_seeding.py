"""oif.seed_cells: random placement in a channel without overlaps with
walls or other cells, to a target haematocrit, reproducible from a seed,
a clear error when the target cannot be reached."""
import unittest

import numpy as np

import lbmd
import oif
from oif import mesh_io
from oif.seeding import SeedingError, fluid_volume

R = 2.0
L, H = 24.0, 12.0
WALL = 1.0


def winding(point, nodes, tris):
    """Winding number by summing triangle solid angles (test's own version):
    Omega = 2 atan2(a.(b x c), |a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|)."""
    tot = 0.0
    for t in tris:
        a, b, c = (nodes[i] - point for i in t)
        la, lb, lc = np.linalg.norm(a), np.linalg.norm(b), np.linalg.norm(c)
        tot += 2 * np.arctan2(a @ np.cross(b, c), la * lb * lc + (a @ b) * lc + (b @ c) * la + (c @ a) * lb)
    return tot / (4 * np.pi)


class TestSeeding(unittest.TestCase):

    def make(self):
        system = lbmd.System(box_l=[L, L, H])
        system.time_step = 0.1
        walls = [lbmd.shapes.Wall(normal=[0, 0, 1], dist=WALL), lbmd.shapes.Wall(normal=[0, 0, -1], dist=-(H - WALL))]
        rbc = oif.OifCellType(*oif.mesh_files("rbc162"), system=system, resize=(R, R, R))
        sphere = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(2.5, 2.5, 2.5))
        return system, walls, rbc, sphere

    def test_haematocrit_no_overlap_reproducible(self):
        system, walls, rbc, sphere = self.make()
        target = 0.06
        cells = oif.seed_cells(system, [rbc, sphere], haematocrit=target, fractions=[0.7, 0.3],
                               boundaries=walls, particle_types=[0, 1], seed=11)
        v_fluid = L * L * (H - 2 * WALL)
        self.assertAlmostEqual(fluid_volume(system, walls), v_fluid, delta=1e-9 * v_fluid)
        ht = sum(c.volume() for c in cells) / v_fluid
        # rounding to whole cells: within one cell's volume of the target
        self.assertLess(abs(ht - target), max(rbc.volume0, sphere.volume0) / v_fluid)
        n_rbc = sum(c.cell_type is rbc for c in cells)
        self.assertEqual(n_rbc, round(0.7 * target * v_fluid / rbc.volume0))
        self.assertTrue(all(c.particle_type == (0 if c.cell_type is rbc else 1) for c in cells))
        longest = max(rbc.mesh.max_edge_length(), sphere.mesh.max_edge_length())
        box = np.array([L, L, H])
        for i, c in enumerate(cells):
            p = c.mesh.positions()
            # outside the walls by at least the default margin (half the longest edge)
            self.assertGreaterEqual(p[:, 2].min(), WALL + 0.5 * longest - 1e-9)
            self.assertLessEqual(p[:, 2].max(), H - WALL - 0.5 * longest + 1e-9)
            # relaxed shape kept
            self.assertAlmostEqual(c.volume(), c.cell_type.volume0, places=9)
            for d in cells[i + 1:]:
                q = d.mesh.positions()
                diff = p[:, None, :] - q[None, :, :]
                diff[..., :2] -= box[:2] * np.round(diff[..., :2] / box[:2])  # periodic in x, y
                self.assertGreaterEqual(np.linalg.norm(diff, axis=2).min(), 1.2 * longest - 1e-9)
        # no cell inside another (centre winding numbers), checked on a few pairs
        for c, d in zip(cells, cells[1:4]):
            shift = d.get_origin() - c.get_origin()
            shift[:2] -= box[:2] * np.round(shift[:2] / box[:2])
            self.assertLess(winding(c.get_origin(), d.mesh.positions() - d.get_origin() + c.get_origin() + shift,
                                    mesh_io.outward(d.mesh.triangle_ids)), 0.5)
        # reproducible from the seed, different for another seed
        system2, walls2, rbc2, sphere2 = self.make()
        again = oif.seed_cells(system2, [rbc2, sphere2], haematocrit=target, fractions=[0.7, 0.3],
                               boundaries=walls2, particle_types=[0, 1], seed=11)
        np.testing.assert_array_equal(np.vstack([c.mesh.positions() for c in cells]),
                                      np.vstack([c.mesh.positions() for c in again]))
        other = oif.seed_cells(system2, rbc2, counts=3, boundaries=walls2, seed=12, create=False)
        self.assertFalse(np.allclose(other[0][1], cells[0].get_origin()))

    def test_impossible(self):
        system, walls, rbc, sphere = self.make()
        with self.assertRaisesRegex(SeedingError, "haematocrit 0.8 cannot be reached"):
            oif.seed_cells(system, rbc, haematocrit=0.8, boundaries=walls, seed=1)
        # below the packing bound but too crowded for random placement of big spheres
        big = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(4.4, 4.4, 4.4))
        with self.assertRaisesRegex(SeedingError, r"could not place cell \d+ of 12 in 200 random tries; placed \d+"):
            oif.seed_cells(system, big, counts=12, boundaries=walls, seed=1, max_attempts=200, create=False)
        with self.assertRaisesRegex(TypeError, "exactly one of 'counts' and 'haematocrit'"):
            oif.seed_cells(system, rbc, boundaries=walls)
        with self.assertRaisesRegex(ValueError, "'haematocrit' must be in"):
            oif.seed_cells(system, rbc, haematocrit=1.5)
        self.assertEqual(len(system.part), 0)  # nothing created on failure


if __name__ == "__main__":
    unittest.main()
