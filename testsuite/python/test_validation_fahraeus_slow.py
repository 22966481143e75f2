"""Validation against experiments: an RBC suspension in a straight tube of
diameter 10 um at a discharge haematocrit about 0.2 (the sample
samples/validation/fahraeus_lindqvist.py, default settings: 5 rbc374 cells
in a periodic tube 38 um long, capillary number 10, node mass at
gamma dt / m = 0.3, membrane viscosity kvisc 1, 150 wall strain units,
averaged after strain 50), against the in-vitro fits of Pries et al., both
within the issue's 15 %:

- the Fahraeus-Lindqvist effect, the apparent viscosity relative to plasma
  eta_rel (Pries, Neuhaus & Gaehtgens, Am. J. Physiol. 263, H1770, 1992).
  Measured 26 Nov 2026: 1.105 against 1.115, -1.0 %.
- the Fahraeus effect, the tube over the discharge haematocrit H_T/H_D
  (Pries, Secomb, Gaehtgens & Gross, Circ. Res. 67, 826, 1990). Measured
  26 Nov 2026: 0.681 against 0.604, +12.7 % (variants of the contacts
  gave +11.3 to +12.7 %: a margin of about 2 points). It depends on Ca
  (at Ca 2 with the former node mass 1 and no membrane viscosity: +19.7 %;
  Ca 5: +18 %): met at Ca 10, with no plateau shown (doc/validation.md).
- the cell-free flow against Poiseuille's law in the lattice tube
  (pi f D^4 / (128 eta); the staircase wall): within 5 % (measured -2 %);
- every cell's volume held within 1 %.
D 15 and 20 um (doc/validation.md) are too costly for a test.
About 140 CPU s (145 s wall on the shared machine): hence _slow."""
import csv
import os
import tempfile
import unittest

from testsuite_data import BUILD, run_sample

VISCOSITY_TOLERANCE = 0.15
FAHRAEUS_TOLERANCE = 0.15


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class FahraeusLindqvist(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with tempfile.TemporaryDirectory() as tmp:
            cls.out = run_sample("validation/fahraeus_lindqvist.py", "--output", "out", cwd=tmp, timeout=1500)
            with open(os.path.join(tmp, "out", "fahraeus_lindqvist.csv")) as f:
                cls.rows = list(csv.DictReader(f))
            cls.png = os.path.getsize(os.path.join(tmp, "out", "fahraeus_lindqvist.png"))

    def test_apparent_viscosity(self):
        for r in self.rows:
            self.assertGreater(float(r["eta_rel"]), 1.0, "cells must raise the apparent viscosity")
            self.assertLess(abs(float(r["eta_rel_error"])), VISCOSITY_TOLERANCE,
                            f"eta_rel {r['eta_rel']} against Pries {r['eta_rel_pries']}")

    def test_tube_haematocrit(self):
        for r in self.rows:
            self.assertLess(float(r["HT_over_HD"]), 1.0, "no Fahraeus effect")
            self.assertLess(abs(float(r["HT_over_HD_error"])), FAHRAEUS_TOLERANCE,
                            f"H_T/H_D {r['HT_over_HD']} against Pries {r['HT_over_HD_pries']}")

    def test_plasma_flow_and_volumes(self):
        for r in self.rows:
            self.assertEqual(r["stopped"], "", "the default run must run to its end")
            self.assertAlmostEqual(float(r["Q_plasma_over_poiseuille"]), 1.0, delta=0.05)
            self.assertLess(float(r["worst_volume_dev"]), 0.01)
        self.assertGreater(self.png, 10000)


if __name__ == "__main__":
    unittest.main()
