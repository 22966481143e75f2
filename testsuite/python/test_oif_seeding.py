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
        # a sphere of diameter 13.2 would overlap its own image along a periodic z of 12
        huge = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(6.6, 6.6, 6.6))
        with self.assertRaisesRegex(ValueError, r"cell type 0 spans at least 1[23]\.\d+ in any orientation.*"
                                                r"the periodic box length 12 along z.*own periodic image"):
            oif.seed_cells(system, huge, counts=1, boundaries=walls, seed=1, create=False)
        system.periodicity = [True, True, False]  # the walls bound z anyway
        with self.assertRaisesRegex(SeedingError, r"could not place cell \d+ of 9 in 200 random tries; placed \d+"):
            oif.seed_cells(system, big, counts=9, boundaries=walls, seed=1, max_attempts=200, create=False)
        # more cell volume than 0.6 of the fluid: refused at once, as for a haematocrit
        with self.assertRaisesRegex(SeedingError, r"12 cells of total volume \d+ cannot be placed at random in "
                                                  r"the available volume 5760"):
            oif.seed_cells(system, big, counts=12, boundaries=walls, seed=1, create=False)
        system.periodicity = [True, True, True]
        with self.assertRaisesRegex(TypeError, "exactly one of 'counts' and 'haematocrit'"):
            oif.seed_cells(system, rbc, boundaries=walls)
        with self.assertRaisesRegex(ValueError, "'haematocrit' must be in"):
            oif.seed_cells(system, rbc, haematocrit=1.5)
        self.assertEqual(len(system.part), 0)  # nothing created on failure

    def test_existing_particles_are_obstacles(self):
        """Cells already in the system (and any other particle) count: new
        nodes keep `gap` from them, no new cell lands inside an old one."""
        system = lbmd.System(box_l=[16.0, 16.0, 16.0])
        system.time_step = 0.1
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(3.0, 3.0, 3.0))
        old = oif.OifCell(cell_type=ct, particle_type=1, origin=[8, 8, 8])
        tracer = system.part.add(pos=[1.0, 1.0, 1.0], type=2)
        cells = oif.seed_cells(system, ct, counts=4, seed=1, max_attempts=2000)
        gap = 1.2 * ct.mesh.max_edge_length()
        box = np.array([16.0, 16.0, 16.0])
        obstacles = np.vstack([old.mesh.positions(), tracer.pos[None, :]])
        for c in cells:
            d = c.mesh.positions()[:, None, :] - obstacles[None, :, :]
            d -= box * np.round(d / box)
            self.assertGreaterEqual(np.linalg.norm(d, axis=2).min(), gap - 1e-9)
        # a small cell is not put inside a big existing one (no node near the big one's nodes)
        system2 = lbmd.System(box_l=[30.0, 30.0, 30.0])
        big = oif.OifCellType(*oif.mesh_files("sphere162"), system=system2, resize=(7.0, 7.0, 7.0))
        small = oif.OifCellType(*oif.mesh_files("sphere162"), system=system2, resize=(1.0, 1.0, 1.0))
        host = oif.OifCell(cell_type=big, particle_type=0, origin=[15, 15, 15])
        placed = oif.seed_cells(system2, small, counts=6, seed=3, region=([5, 5, 5], [25, 25, 25]),
                                create=False)
        gap = 1.2 * big.mesh.max_edge_length()  # the host's long edges set the gap to it
        for _, origin, _ in placed:
            self.assertGreater(np.linalg.norm(origin - host.get_origin()), 7.0 + gap)

    def test_rotation_axis_lays_discs_flat(self):
        """rotation_axis=(0, 0, 1): every RBC turned about z only (its disc
        stays in the x-y plane, at a random angle), so discs fit into a gap
        too low for randomly oriented ones; reproducible from the seed."""
        _, _, rbc0, _ = self.make()
        rel = rbc0.mesh.positions()
        thickness = np.ptp(rel[:, 2])
        margin = 0.5 * rbc0.mesh.max_edge_length()
        h_low = 2 * WALL + thickness + 2 * margin + 0.4  # a disc standing on edge (4 um) cannot fit
        self.assertLess(h_low - 2 * WALL - 2 * margin, 2 * R)

        def low_channel():
            system = lbmd.System(box_l=[L, L, h_low])
            system.time_step = 0.1
            walls = [lbmd.shapes.Wall(normal=[0, 0, 1], dist=WALL),
                     lbmd.shapes.Wall(normal=[0, 0, -1], dist=-(h_low - WALL))]
            rbc = oif.OifCellType(*oif.mesh_files("rbc162"), system=system, resize=(R, R, R))
            return system, walls, rbc

        system, walls, rbc = low_channel()
        with self.assertRaises(SeedingError):  # random orientations: the discs would have to lie flat by chance
            oif.seed_cells(system, rbc, counts=6, boundaries=walls, seed=5, max_attempts=300)
        self.assertEqual(len(system.part), 0)
        cells = oif.seed_cells(system, rbc, counts=6, boundaries=walls, seed=5, rotation_axis=(0, 0, 2.0))
        self.assertEqual(len(cells), 6)
        spins = []
        gap = 1.2 * rbc.mesh.max_edge_length()
        for i, c in enumerate(cells):
            p = c.mesh.positions()
            centred = p - p.mean(axis=0)
            # only turned about z: the z coordinates are the relaxed mesh's, node for node
            np.testing.assert_allclose(centred[:, 2], rel[:, 2] - rel[:, 2].mean(), atol=1e-9)
            np.testing.assert_allclose(np.linalg.norm(centred[:, :2], axis=1),
                                       np.linalg.norm((rel - rel.mean(axis=0))[:, :2], axis=1), atol=1e-9)
            self.assertGreaterEqual(p[:, 2].min(), WALL + margin - 1e-9)
            self.assertLessEqual(p[:, 2].max(), h_low - WALL - margin + 1e-9)
            k = int(np.argmax(rel[:, 0]))  # the node at the rim's +x end: where it went gives the spin
            spins.append(np.arctan2(centred[k, 1], centred[k, 0]))
            for other in cells[i + 1:]:
                d = p[:, None, :] - other.mesh.positions()[None, :, :]
                d[..., :2] -= L * np.round(d[..., :2] / L)
                self.assertGreaterEqual(np.linalg.norm(d, axis=2).min(), gap - 1e-9)
        self.assertGreater(np.ptp(spins), 1.0)  # random angles, not one orientation
        system2, walls2, rbc2 = low_channel()
        again = oif.seed_cells(system2, rbc2, counts=6, boundaries=walls2, seed=5, rotation_axis=(0, 0, 1))
        for c, c2 in zip(cells, again):  # the same seed, the same cells
            np.testing.assert_allclose(c.mesh.positions(), c2.mesh.positions(), atol=1e-12)
        for bad in ([0, 0, 0], [1, 0], "z", [np.nan, 0, 1]):
            with self.assertRaisesRegex(ValueError, "'rotation_axis' must be None or a non-zero vector"):
                oif.seed_cells(system, rbc, counts=1, boundaries=walls, rotation_axis=bad)
        self.assertEqual(len(system.part), 6 * len(rel))  # the bad calls created nothing

    def test_bad_arguments_create_nothing(self):
        system, walls, rbc, sphere = self.make()
        other = lbmd.System(box_l=[L, L, H])
        foreign = oif.OifCellType(*oif.mesh_files("rbc162"), system=other, resize=(R, R, R))
        cases = [
            (TypeError, "'particle_types'", dict(counts=[1, 1], particle_types=[0, 1.5])),
            (ValueError, "'particle_types'", dict(counts=[1, 1], particle_types=[0, -1])),
            (ValueError, "'particle_types' needs 2", dict(counts=[1, 1], particle_types=[0])),
            (TypeError, "'counts'", dict(counts=2.7)),
            (TypeError, "'counts'", dict(counts=[1, 2.5])),
            (ValueError, "'gap'", dict(counts=1, gap=float("nan"))),
            (ValueError, "'gap'", dict(counts=1, gap=-1.0)),
            (ValueError, "'margin'", dict(counts=1, margin=float("nan"))),
            (ValueError, "'margin'", dict(counts=1, margin=-0.5)),
            (ValueError, "'haematocrit'", dict(haematocrit="0.1")),
            (ValueError, "'haematocrit'", dict(haematocrit=float("nan"))),
            (ValueError, "'fractions'", dict(haematocrit=0.05, fractions=[float("nan"), 1.0])),
            (TypeError, "'seed'", dict(counts=1, seed=-1)),
            (TypeError, "'seed'", dict(counts=1, seed=1.5)),
            (TypeError, "'max_attempts'", dict(counts=1, max_attempts=0)),
            (ValueError, "'region'", dict(counts=1, region=[0, 0, 0])),
            (ValueError, "'region'", dict(counts=1, region=([0, 0, 0], [1, 1]))),
            (ValueError, "'region'", dict(counts=1, region=([0, 0, 0], [np.nan, 1, 1]))),
            (TypeError, "'boundaries'", dict(counts=1, boundaries=[walls[0], "wall"])),
            (TypeError, "'exclusion_neighbours'", dict(counts=1, exclusion_neighbours=-1)),
            (SeedingError, "cannot be placed", dict(counts=10**9)),  # fails fast, no huge list
        ]
        for exc, pattern, kwargs in cases:
            with self.subTest(kwargs=kwargs):
                with self.assertRaisesRegex(exc, pattern):
                    oif.seed_cells(system, [rbc, sphere] if "particle_types" in kwargs or
                                   isinstance(kwargs.get("counts"), list) or "fractions" in kwargs else rbc,
                                   **kwargs)
        with self.assertRaisesRegex(TypeError, "'system' must be an lbmd.System"):
            oif.seed_cells(None, rbc, counts=1)
        with self.assertRaisesRegex(ValueError, "cell type 1 belongs to another lbmd.System"):
            oif.seed_cells(system, [rbc, foreign], counts=[1, 1])
        self.assertEqual(len(system.part), 0)
        self.assertEqual(len(other.part), 0)
        # a single shape is taken as a list of one
        cells = oif.seed_cells(system, rbc, counts=1, boundaries=walls[0], seed=2)
        self.assertGreaterEqual(cells[0].mesh.positions()[:, 2].min(), WALL)

    def test_failure_midway_removes_created_cells(self):
        from unittest import mock
        system, walls, rbc, sphere = self.make()
        keep = oif.OifCell(cell_type=rbc, particle_type=0, origin=[2, 2, 6])
        n_before = len(system.part)
        real = oif.OifCell._add_bonds
        calls = []

        def failing(cell, *args):
            calls.append(1)
            if len(calls) == 3:
                raise RuntimeError("engine failure")
            return real(cell, *args)
        with mock.patch.object(oif.OifCell, "_add_bonds", failing):
            with self.assertRaisesRegex(RuntimeError, "engine failure"):
                oif.seed_cells(system, rbc, counts=4, boundaries=walls, seed=5)
        self.assertEqual(len(system.part), n_before)
        np.testing.assert_array_equal(np.unique(system.part.all().mol_id), [keep.cell_id])
        self.assertAlmostEqual(keep.volume(), rbc.volume0, places=9)


if __name__ == "__main__":
    unittest.main()
