"""oif.pack_cells (doc/oif.md, "Packing cells"): rigid force-biased growth.
Red cells (rbc374) packed to haematocrit 0.45 in a periodic box and mixed
with small spheres between two walls: every cell at its reference volume
and surface (rigid: to round-off), no node inside another cell (winding
numbers, computed here independently of the packer's own check), every
node at least the clearance from the other cells' nodes and from the
walls, the haematocrit reached, the same seed giving the same placements,
and the errors for an impossible packing and for bad input."""
import unittest

import numpy as np

import lbmd
import oif
from lbmd import shapes
from oif.oif_classes import _winding


def rbc(system, **kw):
    return oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.91,) * 3, ks=0.005, kb=0.02,
                           kal=0.007, kag=0.7, kv=0.9, normal=True, **kw)


def nodes_inside_other_cells(cells, box, periodic):
    """Nodes of each cell inside another (winding number > 1/2), over the
    other cell's image nearest to it."""
    pos = [c.mesh.positions() for c in cells]
    centres = [p.mean(axis=0) for p in pos]
    inside = 0
    for i, pi in enumerate(pos):
        for j, pj in enumerate(pos):
            if i == j:
                continue
            d = centres[i] - centres[j]
            shift = np.where(periodic, box * np.round(d / box), 0.0)
            q = pj + shift
            if np.linalg.norm(d - shift) > 9.0:
                continue
            lo, hi = q.min(axis=0), q.max(axis=0)
            cand = pi[np.all((pi > lo) & (pi < hi), axis=1)]
            if len(cand):
                inside += int(np.count_nonzero(_winding(cand, q, cells[j].cell_type.mesh._topo.triangles) > 0.5))
    return inside


class TestPackCells(unittest.TestCase):

    def test_periodic_box_at_045(self):
        s = lbmd.System(box_l=[20.0, 20.0, 20.0])
        ct = rbc(s)
        cells = oif.pack_cells(s, ct, haematocrit=0.45, seed=3)
        r = cells.report
        self.assertTrue(r["converged"])
        self.assertEqual(len(cells), round(0.45 * 8000 / ct.volume0))
        self.assertAlmostEqual(r["haematocrit"], len(cells) * ct.volume0 / 8000, places=12)
        self.assertGreater(r["haematocrit"], 0.445)
        self.assertEqual(r["nodes_inside_cells"], 0)
        self.assertEqual(nodes_inside_other_cells(cells, np.array(s.box_l), np.array([True] * 3)), 0)
        offset = oif.contacts.contact_offset(ct)
        self.assertGreaterEqual(r["min_node_distance"], offset)
        for c in cells:  # rigid: the reference shape to round-off
            self.assertAlmostEqual(c.volume() / ct.volume0, 1.0, places=9)
            self.assertAlmostEqual(c.surface() / ct.surface0, 1.0, places=9)

    def test_narrow_tube_across_a_periodic_box(self):
        """A D 10 um tube along x in a box 12 um wide, periodic on every
        axis (as the Fahraeus sample builds it), at the tube haematocrit of
        H_D 0.45 (Pries: 0.321): the tube keeps each cell from its own y and
        z images, so the narrow periodic axes are no reason to refuse
        (before 29 Nov 2026: 'a cell would touch its own periodic image').
        Every node inside the tube by the wall clearance, none inside
        another cell."""
        s = lbmd.System(box_l=[40.0, 12.0, 12.0])
        tube = shapes.Cylinder(center=[20.0, 6.0, 6.0], axis=[1, 0, 0], radius=5.0, length=120.0, direction=-1,
                               open=True)
        ct = rbc(s)
        cells = oif.pack_cells(s, ct, counts=11, boundaries=[tube], seed=1)
        r = cells.report
        self.assertTrue(r["converged"])
        self.assertAlmostEqual(r["haematocrit"], 11 * ct.volume0 / (np.pi * 25.0 * 40.0), delta=0.01)
        self.assertGreater(r["haematocrit"], 0.31)
        self.assertEqual(r["nodes_inside_cells"], 0)
        self.assertEqual(nodes_inside_other_cells(cells, np.array(s.box_l), np.array([True, False, False])), 0)
        nodes = np.concatenate([c.mesh.positions() for c in cells])
        # the wall clearance 0.25 holds within the packer's final tolerance
        # (5 % of the cells' clearance, 0.025 here); the report measures it
        self.assertGreaterEqual(r["min_wall_distance"], 0.25 - 0.05 * r["clearance"] - 1e-9)
        self.assertAlmostEqual(5.0 - np.hypot(nodes[:, 1] - 6.0, nodes[:, 2] - 6.0).max(), r["min_wall_distance"],
                               delta=1e-6)

    def test_same_seed_same_cells(self):
        out = []
        for _ in range(2):
            s = lbmd.System(box_l=[20.0, 20.0, 20.0])
            out.append(oif.pack_cells(s, rbc(s), haematocrit=0.3, seed=7, create=False))
        self.assertEqual(len(out[0]), len(out[1]))
        for (ta, oa, ra), (tb, ob, rb) in zip(*out):
            self.assertEqual(ta, tb)
            np.testing.assert_array_equal(oa, ob)
            np.testing.assert_array_equal(ra, rb)

    def test_two_types_between_walls(self):
        s = lbmd.System(box_l=[24.0, 24.0, 14.0])
        s.periodicity = [True, True, False]
        walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-13.0)]
        red = rbc(s)
        small = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(1.5,) * 3, ks=0.05, kb=0.1,
                                kal=0.01, kag=0.7, kv=0.9, normal=True)
        cells = oif.pack_cells(s, [red, small], haematocrit=0.35, fractions=[0.85, 0.15], boundaries=walls,
                               particle_types=[0, 1], seed=2, rotation_axis=[0, 0, 1])
        r = cells.report
        self.assertTrue(r["converged"])
        self.assertEqual(r["nodes_inside_cells"], 0)
        self.assertEqual(nodes_inside_other_cells(cells, np.array(s.box_l), np.array([True, True, False])), 0)
        self.assertGreaterEqual(r["min_wall_distance"], r["wall_clearance"] * 0.9)
        z = np.concatenate([c.mesh.positions()[:, 2] for c in cells])
        self.assertGreater(z.min(), 1.0)
        self.assertLess(z.max(), 13.0)
        kinds = [c.cell_type is small for c in cells]
        self.assertEqual(sum(kinds), r["counts"][1])
        self.assertGreater(r["counts"][1], 0)
        v = sum(c.cell_type.volume0 for c in cells) / r["fluid_volume"]
        self.assertAlmostEqual(v, r["haematocrit"], places=9)
        self.assertGreater(v, 0.34)

    def test_deformable_stage_in_a_narrow_tube_at_045(self):
        """A D 10 um tube at 0.45: rigid discs jam (the wall layer and the
        contacts' clearance), so the cells swell as deformable cells from a
        slightly smaller rigid packing (doc/oif.md, "Packing"). Every cell
        at its reference volume and surface within 0.5 %, none of its nodes
        inside another cell (winding numbers) or nearer another cell's
        nodes than the advised contact's offset (so no contact starts
        crossed), every node inside the tube by half the wall clearance,
        and the same seed giving the same nodes. deformable=False names
        the way out."""
        def pack(**kw):
            s = lbmd.System(box_l=[44.0, 12.0, 12.0])
            tube = shapes.Cylinder(center=[22.0, 6.0, 6.0], axis=[1, 0, 0], radius=5.0, length=132.0, direction=-1,
                                   open=True)
            ct = rbc(s)
            return s, ct, oif.pack_cells(s, ct, haematocrit=0.45, boundaries=[tube], seed=4, **kw)

        with self.assertRaisesRegex(oif.PackingError, r"deformable=True"):
            pack(deformable=False, max_iterations=3000)
        s, ct, cells = pack()
        r = cells.report
        self.assertEqual(r["method"], "rigid+deformable")
        self.assertTrue(r["converged"])
        self.assertFalse(r["rigid_converged"])
        self.assertEqual(len(cells), 17)
        self.assertGreaterEqual(r["haematocrit"], 0.45)
        self.assertLess(r["rigid_scale"], 1.0)
        for c in cells:
            self.assertLess(abs(c.volume() / ct.volume0 - 1.0), 0.005)
            self.assertLess(abs(c.surface() / ct.surface0 - 1.0), 0.005)
        self.assertEqual(r["nodes_inside_cells"], 0)
        self.assertEqual(nodes_inside_other_cells(cells, np.array(s.box_l), np.array([True, False, False])), 0)
        pos = [c.mesh.positions() for c in cells]
        closest = np.inf
        for i in range(len(pos)):
            for j in range(i + 1, len(pos)):
                d = pos[i].mean(axis=0) - pos[j].mean(axis=0)
                shift = np.array([44.0 * np.round(d[0] / 44.0), 0.0, 0.0])
                q = pos[j] + shift
                if np.linalg.norm(d - shift) < 10.0:
                    closest = min(closest, np.sqrt(((pos[i][:, None] - q[None]) ** 2).sum(axis=2)).min())
        offset = oif.contacts.contact_offset(ct)
        # the deformable stage's contact keeps half the packing's margin
        self.assertGreater(closest, offset + 0.5 * (r["clearance"] - offset))
        self.assertAlmostEqual(closest, r["min_node_distance"], places=9)
        nodes = np.concatenate(pos)
        self.assertGreater(5.0 - np.hypot(nodes[:, 1] - 6.0, nodes[:, 2] - 6.0).max(), 0.5 * r["wall_clearance"])
        # the cells are deformed (not the rigid packing's shapes): the
        # swelling did the work
        ref = ct.mesh._nodes - ct.mesh._nodes.mean(axis=0)
        def radius_of_gyration(x):
            return np.sqrt(((x - x.mean(axis=0)) ** 2).sum(axis=1).mean())
        self.assertGreater(max(abs(radius_of_gyration(x) / radius_of_gyration(ref) - 1.0) for x in pos), 0.005)
        _, _, again = pack()
        for a, b in zip(cells, again):
            np.testing.assert_array_equal(a.mesh.positions(), b.mesh.positions())

    def test_two_types_between_walls_at_045(self):
        """Red cells and small spheres (85/15 % of the cell volume) between
        two walls 10 um apart at 0.45: the rigid stage jams and the
        deformable one swells both types to their reference volume and
        surface within 0.5 %, no node inside another cell or beyond a
        wall."""
        s = lbmd.System(box_l=[20.0, 20.0, 12.0], periodicity=[True, True, False])
        walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-11.0)]
        red = rbc(s)
        small = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(1.5,) * 3, ks=0.05, kb=0.1,
                                kal=0.01, kag=0.7, kv=0.9, normal=True)
        cells = oif.pack_cells(s, [red, small], haematocrit=0.45, fractions=[0.85, 0.15], boundaries=walls,
                               particle_types=[0, 1], seed=2)
        r = cells.report
        self.assertEqual(r["method"], "rigid+deformable")
        self.assertGreaterEqual(r["haematocrit"], 0.445)
        self.assertEqual([sum(c.cell_type is t for c in cells) for t in (red, small)], r["counts"])
        self.assertGreater(min(r["counts"]), 10)
        for c in cells:
            self.assertLess(abs(c.volume() / c.cell_type.volume0 - 1.0), 0.005)
            self.assertLess(abs(c.surface() / c.cell_type.surface0 - 1.0), 0.005)
        self.assertEqual(nodes_inside_other_cells(cells, np.array(s.box_l), np.array([True, True, False])), 0)
        z = np.concatenate([c.mesh.positions()[:, 2] for c in cells])
        self.assertGreater(z.min(), 1.0 + 0.5 * r["wall_clearance"])
        self.assertLess(z.max(), 11.0 - 0.5 * r["wall_clearance"])

    def test_mesh_check_of_two_overlapping_cells(self):
        """The deformable stage's exact check (check_meshes) against a
        brute-force count: two spheres moved 1.5 um into each other."""
        from lbmd import _lbmd
        s = lbmd.System(box_l=[20.0, 20.0, 20.0])
        sph = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(2.0,) * 3)
        a = sph.mesh._nodes - sph.mesh._nodes.mean(axis=0) + 10.0
        b = a + [2.5, 0.0, 0.0]
        tris = oif.mesh_io.outward(sph.mesh._topo.triangles)
        wall = shapes.Wall(normal=[0, 0, 1], dist=8.5)
        out = _lbmd.check_meshes(np.concatenate([a, b]), [0, len(a), 2 * len(a)], [0, 0], [tris], [wall._core],
                                 dict(box=[20.0] * 3, periodic=[True] * 3), 3.0)
        inside = int((_winding(b, a, tris) > 0.5).sum() + (_winding(a, b, tris) > 0.5).sum())
        self.assertGreater(inside, 0)
        self.assertEqual(out["nodes_inside_cells"], inside)
        closest = np.sqrt(((a[:, None] - b[None]) ** 2).sum(axis=2)).min()
        self.assertAlmostEqual(out["min_node_distance"], closest, places=12)
        self.assertAlmostEqual(out["min_wall_distance"], np.concatenate([a, b])[:, 2].min() - 8.5, places=12)

    def test_errors(self):
        s = lbmd.System(box_l=[20.0, 20.0, 20.0])
        ct = rbc(s)
        with self.assertRaisesRegex(ValueError, "haematocrit"):
            oif.pack_cells(s, ct, haematocrit=1.2)
        with self.assertRaisesRegex(TypeError, "exactly one"):
            oif.pack_cells(s, ct)
        with self.assertRaisesRegex(oif.PackingError, "cannot be packed"):
            oif.pack_cells(s, ct, haematocrit=0.8)
        with self.assertRaisesRegex(oif.PackingError, r"reached .*haematocrit.*still growing"):
            oif.pack_cells(s, ct, haematocrit=0.6, seed=1, max_iterations=300)
        with self.assertRaisesRegex(TypeError, "deformable"):
            oif.pack_cells(s, ct, haematocrit=0.3, deformable=1)
        self.assertEqual(len(s.part), 0)  # nothing created by a failed packing
        oif.OifCell(cell_type=ct, particle_type=0, origin=[10, 10, 10])
        with self.assertRaisesRegex(ValueError, "already holds 374 particles"):
            oif.pack_cells(s, ct, haematocrit=0.2)


if __name__ == "__main__":
    unittest.main()
