"""Per-cell observables over time (doc/oif.md, "Per-cell observables"):
edge and area strains, the largest of each, Taylor's deformation index and
the damage record (after Gusenbauer et al., Artif. Organs 42, 746, 2018),
checked against exact values for affine deformations of a cell's mesh, and
written by H5mdWriter as the methods give them."""
import os
import tempfile
import unittest

import numpy as np

import lbmd
import lbmd.io
import oif


class Observables(unittest.TestCase):
    def setUp(self):
        self.system = lbmd.System(box_l=[40.0] * 3)
        self.system.time_step = 0.1
        self.system.cell_system.skin = 0.2
        self.type = oif.OifCellType(*oif.mesh_files("sphere642"), system=self.system, resize=(4.0,) * 3, ks=0.01,
                                    kal=0.01, kag=0.1, kv=0.1)
        self.cell = oif.OifCell(cell_type=self.type, particle_type=0, origin=[20.0] * 3)
        self.centre = self.cell.particles.pos.mean(axis=0)
        self.rest = self.cell.particles.pos.copy() - self.centre

    def deform(self, matrix):
        self.cell.particles.pos = self.centre + self.rest @ np.asarray(matrix, dtype=float).T

    def test_at_rest(self):
        self.assertLess(self.cell.max_edge_strain(), 1e-12)
        self.assertLess(self.cell.max_area_strain(), 1e-12)
        self.assertLess(self.cell.deformation_index(), 0.01)  # the mesh's own slight anisotropy

    def test_affine_deformations(self):
        # a uniform scale s: every edge strains by s - 1, every triangle by s^2 - 1, the shape stays
        s = 1.07
        self.deform(np.eye(3) * s)
        np.testing.assert_allclose(self.cell.edge_strains(), s - 1.0, atol=1e-12)
        np.testing.assert_allclose(self.cell.area_strains(), s * s - 1.0, atol=1e-12)
        self.assertAlmostEqual(self.cell.max_area_strain(), s * s - 1.0, delta=1e-12)
        self.assertLess(self.cell.deformation_index(), 0.01)
        # stretched along x by 1.2, squeezed along z by 0.9: D = (1.2 - 0.9) / (1.2 + 0.9), the
        # edges strain by at most 0.2 (those along x) and at least -0.1 (along z)
        self.deform(np.diag([1.2, 1.0, 0.9]))
        self.assertAlmostEqual(self.cell.deformation_index(), 0.3 / 2.1, delta=0.01)
        strains = self.cell.edge_strains()
        self.assertLessEqual(strains.max(), 0.2 + 1e-12)
        self.assertGreaterEqual(strains.min(), -0.1 - 1e-12)
        self.assertGreater(strains.max(), 0.18)  # an edge of 642 nodes lies almost along x
        self.assertAlmostEqual(self.cell.max_edge_strain(), strains.max(), delta=1e-15)

    def test_damage_record(self):
        """Time above the threshold, counted by each interval's start: strains
        0.1, 0, 0.1, 0.1 at times 0, 1, 2, 3 give 1 + 1 = 2 above 0.05."""
        above = np.sqrt(1.1)  # a uniform scale giving area strain 0.1
        for t, scale in ((0.0, above), (1.0, 1.0), (2.0, above), (3.0, above)):
            self.deform(np.eye(3) * scale)
            oif.update_damage([self.cell], t, threshold=0.05)
        d = self.cell.damage
        self.assertAlmostEqual(d.time_above, 2.0, delta=1e-12)
        self.assertAlmostEqual(d.peak_strain, 0.1, delta=1e-12)
        self.assertEqual(d.samples, 4)
        with self.assertRaisesRegex(ValueError, "before cell 0's previous sample"):
            oif.update_damage(self.cell, 2.5)
        # all or nothing: a refused cell leaves the others' records as they were
        other = oif.OifCell(cell_type=self.type, particle_type=0, origin=[8.0] * 3)
        with self.assertRaisesRegex(ValueError, "before cell 0's previous sample"):
            oif.update_damage([other, self.cell], 2.5)
        self.assertEqual(other.damage.samples, 0)
        self.assertEqual(self.cell.damage.samples, 4)
        # reading an untracked cell's record does not fix its threshold
        self.assertEqual(other.damage.threshold, oif.DAMAGE_AREA_STRAIN)
        oif.update_damage(other, 3.0, threshold=0.2)
        self.assertEqual(other.damage.threshold, 0.2)
        with self.assertRaisesRegex(ValueError, "keeps its first threshold"):
            oif.update_damage(self.cell, 4.0, threshold=0.1)
        with self.assertRaisesRegex(ValueError, "'threshold' is a strain"):
            oif.update_damage(self.cell, 4.0, threshold=5)
        with self.assertRaisesRegex(TypeError, "'cells' must hold oif.OifCell"):
            oif.update_damage(["cell"], 4.0)

    def test_h5md_fields(self):
        fields = ("deformation_index", "max_edge_strain", "max_area_strain", "damage_time", "peak_area_strain")
        import h5py
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "t.h5")
            expected = []
            with lbmd.io.H5mdWriter(path, self.system, cells=[self.cell], cell_fields=fields) as w:
                for k, m in enumerate((np.eye(3), np.diag([1.2, 1.0, 0.9]))):
                    self.deform(m)
                    self.system.integrator.run(0)
                    oif.update_damage(self.cell, float(k))
                    w.write()
                    c = self.cell
                    expected.append([c.deformation_index(), c.max_edge_strain(), c.max_area_strain(),
                                     c.damage.time_above, c.damage.peak_strain])
            with h5py.File(path, "r") as f:
                got = np.array([[f["observables/cells"][name]["value"][k][0] for name in fields] for k in range(2)])
        np.testing.assert_allclose(got, expected, rtol=0, atol=0)
        self.assertGreater(got[1, 0], 0.1)


if __name__ == "__main__":
    unittest.main()
