"""Validation against experiment: a red blood cell's shape recovery after
stretching, Hochmuth, Worthy & Evans, Biophys. J. 26, 101-114 (1979):
time constant t_c = eta_m / mu = 0.10-0.13 s at mu = 6 uN/m and
eta_m = (6-8)e-7 N s/m. The sample samples/validation/rbc_recovery.py
gives the cell these SI values (lbmd.units.oif_moduli_from_si, kvisc 1617
in the engine's units: the implicit membrane viscosity at dt kvisc / m
about 8, fifty times the explicit dashpots' limit), stretches it to rest,
releases it and fits the recovery of its axis ratio as the experiment was
fitted.

Tolerances: t_c within the measured 0.10-0.13 s widened by 5 % below
(0.095 s), and within 15 % of eta_m / mu (the Evans-Hochmuth model the
experiment was read with; the OIF cell is stiffer than a pure shear
membrane by its bending and local area terms, which the dashpots do not
damp). Measured (29 Nov 2026): t_c 0.1037 s, 0.889 eta_m / mu; 0.1037 at
time step 25 us too; with kb / 10, 0.112 s (0.96). Volume within 0.1 %,
surface within 0.5 %. About 16 CPU s."""
import os
import re
import tempfile
import unittest

from testsuite_data import run_sample, read_csv

SAMPLE = "validation/rbc_recovery.py"


class RecoveryTime(unittest.TestCase):
    def test_recovery_time_against_hochmuth_1979(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = run_sample(SAMPLE, "--output", "out", cwd=tmp)
            rows = read_csv(os.path.join(tmp, "out", "rbc_recovery_rbc374.csv"))
        fitted = re.search(r"t_c = ([0-9.]+) s .*eta_m / mu = ([0-9.]+) s", out)
        self.assertIsNotNone(fitted, out)
        t_c, model = float(fitted.group(1)), float(fitted.group(2))
        print(f"[ figure ] t_c {t_c:.4f} s, eta_m/mu {model:.4f} s, ratio {t_c / model:.3f}")
        self.assertGreater(t_c, 0.095)
        self.assertLess(t_c, 0.13)
        self.assertLess(abs(t_c / model - 1.0), 0.15)
        drift = re.search(r"worst volume change ([0-9.]+) %, surface ([0-9.]+) %", out)
        self.assertLess(float(drift.group(1)), 0.1)
        self.assertLess(float(drift.group(2)), 0.5)
        # recovered: the axis ratio ends within 2 % of the start's stretch above the relaxed one
        lam = [float(r["lambda"]) for r in rows]
        self.assertGreater(lam[0], 1.15)
        self.assertLess(lam[-1] - 1.0, 0.1 * (lam[0] - 1.0))


if __name__ == "__main__":
    unittest.main()
