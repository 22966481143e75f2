"""Validation against experiment: a red blood cell stretched by optical
tweezers, Mills, Qie, Dao, Lim & Suresh, Mech. Chem. Biosyst. 1(3),
169-180 (2004). The sample samples/validation/rbc_stretching.py runs the
cell (forces on the nodes within 1 um of the rim's ends) at every force
of the experiment, 0-193 pN; its diameters are compared here with the data
file samples/validation/data/mills2004_stretching.csv (mean and range of the
experimental scatter at each force).

Two sets of moduli (paper's units; oif.stretching):

- MILLS_MODULI, our calibration of the published set on this experiment
  (kb 0.01 instead of 0.02, not a published value; every other modulus as
  published), the sample's default. Tolerance: each diameter inside the experimental range itself
  at every force, on rbc374, rbc642 and rbc1002. Measured (27 Nov 2026):
  inside on these and rbc2562; the nearest approach is the transverse
  diameter at 16 pN, 0.05-0.10 um under the range's top (6.71-6.76
  against 6.81 um).
- RBC_MODULI, the published set (ks 0.005, kb 0.02, kal 0.007, kag 0.7,
  kv 0.9), on rbc374 only. Tolerance: inside the range widened by 0.1 um
  (1.3 % of the unloaded diameter, about the precision of reading the
  figure). Measured: the transverse diameter 0.054 um above the range at
  16 pN, 0.03 at 38 pN and 0.01 at 67 pN, the other 10 forces inside.

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
MARGIN_PAPER = 0.1  # um, the published set's tolerance (module docstring)



def relaxed_diameters(mesh, moduli):
    system = lbmd.System(box_l=[48.0, 32.0, 32.0])
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(oif.stretching.RBC_RADIUS,) * 3,
                         normal=True, **moduli)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[24.0, 16.0, 16.0])
    return oif.stretching.diameters(cell.particles.pos)


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class MillsStretching(unittest.TestCase):
    def run_mesh(self, mesh, moduli="mills", margin=0.0):
        stem = f"rbc_stretching_{mesh}" + ("_paper" if moduli == "paper" else "")
        with tempfile.TemporaryDirectory() as tmp:
            stdout = run_sample(SAMPLE, "--mesh", mesh, "--moduli", moduli, "--output", tmp, cwd=tmp)
            self.assertTrue(os.path.getsize(os.path.join(tmp, stem + ".png")) > 0)
            rows = read_csv(os.path.join(tmp, stem + ".csv"))
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
                self.assertGreaterEqual(axial, ref["axial_min_um"] - margin)
                self.assertLessEqual(axial, ref["axial_max_um"] + margin)
                self.assertGreaterEqual(transverse, ref["transverse_min_um"] - margin)
                self.assertLessEqual(transverse, ref["transverse_max_um"] + margin)
                # the sample's own verdict agrees with the range
                inside = ref["axial_min_um"] <= axial <= ref["axial_max_um"]
                self.assertEqual(r["axial_inside"], str(inside))
        # unloaded: the relaxed cell
        d0 = relaxed_diameters(mesh, oif.stretching.MILLS_MODULI if moduli == "mills"
                               else oif.stretching.RBC_MODULI)
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

    def test_rbc374_published_moduli(self):
        self.run_mesh("rbc374", "paper", MARGIN_PAPER)


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
