"""Validation against experiment: a red blood cell stretched by optical
tweezers, Mills, Qie, Dao, Lim & Suresh, Mech. Chem. Biosyst. 1(3),
169-180 (2004). The sample samples/validation/rbc_stretching.py runs the
cell (the project's RBC moduli ks 0.005, kb 0.02, kal 0.007, kag 0.7,
kv 0.9, forces on the nodes within 1 um of the rim's ends) at every force
of the experiment, 0-193 pN; its diameters are compared here with the data
file samples/validation/data/mills2004_stretching.csv (mean and range of the
experimental scatter at each force).

Tolerance: each diameter inside the experimental range widened by 0.1 um
(1.3 % of the unloaded diameter, about the precision of reading the
figure), at every force. Measured (26 Nov 2026): the axial diameter is
inside the range itself on rbc374 and rbc642 and 0.08 um below it at
151 pN on rbc1002; the transverse diameter is inside except where the
experiment's drops steeply at low force: up to 0.08 um above the range at
16 pN and 0.03 um at 38 pN. The model lies at the stiff side of the
scatter (the axial diameter 0.9-1.3 um under the mean above 100 pN).
At 0 pN both diameters equal the relaxed cell's within 1e-3 um.
rbc374 takes about 5 CPU s, rbc642 about 9, rbc1002 about 13."""
import os
import tempfile
import unittest

import lbmd
import oif

from testsuite_data import BUILD, SOURCE, run_sample, read_csv

SAMPLE = "validation/rbc_stretching.py"  # under samples/
DATA = os.path.join(SOURCE, "samples", "validation", "data", "mills2004_stretching.csv")
MARGIN = 0.1  # um, see the module docstring



def relaxed_diameters(mesh):
    system = lbmd.System(box_l=[48.0, 32.0, 32.0])
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(oif.stretching.RBC_RADIUS,) * 3,
                         normal=True, **oif.stretching.RBC_MODULI)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[24.0, 16.0, 16.0])
    return oif.stretching.diameters(cell.particles.pos)


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class MillsStretching(unittest.TestCase):
    def run_mesh(self, mesh):
        with tempfile.TemporaryDirectory() as tmp:
            stdout = run_sample(SAMPLE, "--mesh", mesh, "--output", tmp, cwd=tmp)
            self.assertTrue(os.path.getsize(os.path.join(tmp, f"rbc_stretching_{mesh}.png")) > 0)
            rows = read_csv(os.path.join(tmp, f"rbc_stretching_{mesh}.csv"))
        self.assertIn("worst distance from the Mills range, axial", stdout)
        data = {float(r["force_pN"]): {k: float(v) for k, v in r.items()} for r in read_csv(DATA)}
        self.assertEqual([float(r["force_pN"]) for r in rows], sorted(data))
        for r in rows:
            f = float(r["force_pN"])
            ref = data[f]
            self.assertEqual(r["converged"], "True", f"{mesh} {f} pN: not converged")
            axial, transverse = float(r["axial_um"]), float(r["transverse_um"])
            # the data columns are the data file's, not made up by the sample
            self.assertEqual(float(r["axial_min_um"]), ref["axial_min_um"])
            self.assertEqual(float(r["transverse_max_um"]), ref["transverse_max_um"])
            with self.subTest(mesh=mesh, force_pN=f):
                self.assertGreaterEqual(axial, ref["axial_min_um"] - MARGIN)
                self.assertLessEqual(axial, ref["axial_max_um"] + MARGIN)
                self.assertGreaterEqual(transverse, ref["transverse_min_um"] - MARGIN)
                self.assertLessEqual(transverse, ref["transverse_max_um"] + MARGIN)
                # the sample's own verdict agrees with the range
                inside = ref["axial_min_um"] <= axial <= ref["axial_max_um"]
                self.assertEqual(r["axial_inside"], str(inside))
        # unloaded: the relaxed cell
        d0 = relaxed_diameters(mesh)
        self.assertAlmostEqual(float(rows[0]["axial_um"]), d0[0], delta=1e-3)
        self.assertAlmostEqual(float(rows[0]["transverse_um"]), d0[1], delta=1e-3)
        # the stretch is monotonic: longer and narrower with every force
        axial = [float(r["axial_um"]) for r in rows]
        self.assertTrue(all(b > a for a, b in zip(axial, axial[1:])), axial)

    def test_rbc374(self):
        self.run_mesh("rbc374")

    def test_rbc642(self):
        self.run_mesh("rbc642")

    def test_rbc1002(self):
        self.run_mesh("rbc1002")


class StretchCellInput(unittest.TestCase):
    def test_bad_input_names_the_parameter(self):
        with self.assertRaisesRegex(ValueError, "'mesh'"):
            oif.stretch_cell("rbc375", [0.01])
        with self.assertRaisesRegex(ValueError, "'forces'"):
            oif.stretch_cell("rbc374", [-0.01])
        with self.assertRaisesRegex(ValueError, "'forces'"):
            oif.stretch_cell("rbc374", [])
        with self.assertRaisesRegex(ValueError, "'patch_radius'"):
            oif.stretch_cell("rbc374", [0.01], patch_radius=0)
        with self.assertRaisesRegex(ValueError, "'patch_radius'"):
            oif.stretch_cell("rbc374", [0.01], patch_radius=0.01)


if __name__ == "__main__":
    unittest.main()
