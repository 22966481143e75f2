"""Validation against experiment: a red blood cell in simple shear flow,
tank-treading frequency and inclination angle against T. M. Fischer &
R. Korzeniewski, Biophys. J. 108, 1352-1360 (2015) (the cell-by-cell
f / shear rate of their Fig. S11 at 28.9 mPa s,
samples/validation/data/fischer2015_ttf.csv).

The sample samples/validation/rbc_shear.py runs the RBC (rbc374, radius
3.91 um, ks 0.005, kb 0.02, kal 0.007, kag 0.7, kv 0.9, plasma 1.5 mPa s
inside and outside, coupling 2 x suggest_LBgamma, box 24 x 16, channel
height 20 um) at the physical shear rates 326, 624, 1256 and 2535 1/s:
the shear stresses 0.49, 0.94, 1.88 and 3.80 Pa of the experiment's rates
16.9, 32.4, 65.2 and 131.6 1/s in its 28.9 mPa s medium (doc/validation.md).

Tolerance: where the model tank-treads, f / shear rate within two standard
deviations of the experiment's cell-to-cell scatter at the same stress
(the band of 95 % of the measured cells; 2 sd is 26-40 % of the mean).
Measured (26 Nov 2026): f / rate 0.0427, 0.0362, 0.0329 at 0.94, 1.88,
3.80 Pa against the experiment's 0.0330 +- 0.0063, 0.0287 +- 0.0057,
0.0260 +- 0.0036: 1.30, 1.26, 1.27 times the mean, +1.6, +1.3, +1.9 sd
(at 3.80 Pa just above the highest measured cell, 0.0321). The model is
systematically about 25 % faster than the mean cell; its viscosity ratio
is 1, the experiment's about 0.2 (doc/validation.md). At 0.49 Pa the
model tumbles (the experiment's cells tank-tread there): asserted as the
documented behaviour. Also asserted: f / rate falling with the stress (as
in the experiment), below the sphere's 1/(4 pi); the mean inclination
angle 5-20 deg (measured 9.5-11.7; the experiment's cells 7-17 deg); the
volume within 1 %. About 90 CPU s: hence _slow (ctest label slow)."""
import math
import os
import sys
import tempfile
import unittest

import numpy as np

from testsuite_data import BUILD, SOURCE, run_sample, read_csv

SAMPLE = "validation/rbc_shear.py"  # under samples/
RATES = (326, 624, 1256, 2535)      # 1/s: the experiment's stresses 0.49-3.80 Pa in plasma
TANK_TREADING = (624, 1256, 2535)
TUMBLING = (326,)
SD_TOLERANCE = 2.0                  # standard deviations of the cell-to-cell scatter



def sample_module():
    sys.path.insert(0, os.path.join(SOURCE, "samples", "validation"))
    try:
        import rbc_shear
    finally:
        sys.path.pop(0)
    return rbc_shear


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class RbcShear(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with tempfile.TemporaryDirectory() as tmp:
            cls.stdout = run_sample(SAMPLE, "--output", tmp, "--shear-rates", *map(str, RATES), cwd=tmp,
                                    timeout=900)
            cls.png_size = os.path.getsize(os.path.join(tmp, "rbc_shear.png"))
            cls.rows = {round(float(r["shear_rate"])): r for r in read_csv(os.path.join(tmp, "rbc_shear.csv"))}

    def test_outputs(self):
        self.assertGreater(self.png_size, 0)
        self.assertEqual(sorted(self.rows), sorted(RATES))
        for rate, r in self.rows.items():
            # the experiment's group at the same stress (28.9 mPa s x its rate = 1.5 mPa s x ours)
            self.assertAlmostEqual(float(r["exp_stress_Pa"]), float(r["stress_Pa"]), delta=0.02 * float(r["stress_Pa"]))

    def test_tank_treading_frequency_against_experiment(self):
        for rate in TANK_TREADING:
            r = self.rows[rate]
            with self.subTest(rate=rate):
                self.assertEqual(r["mode"], "tank-treading")
                f, mean, sd = float(r["f_over_rate"]), float(r["exp_mean"]), float(r["exp_sd"])
                self.assertLess(abs(f - mean), SD_TOLERANCE * sd,
                                f"f/rate {f:.4f}, experiment {mean:.4f} +- {sd:.4f} at {r['stress_Pa']} Pa")
                # a full half-turn at least, and the nodes agree on the rate
                self.assertGreaterEqual(int(r["half_turns"]), 1)
                self.assertLess(float(r["f_spread"]), 0.1 * f)
                self.assertLess(f, 1.0 / (4.0 * math.pi))

    def test_frequency_falls_with_stress(self):
        f = [float(self.rows[rate]["f_over_rate"]) for rate in TANK_TREADING]
        self.assertTrue(all(b < a for a, b in zip(f, f[1:])), f)

    def test_tumbling_at_low_stress(self):
        # documented: viscosity ratio 1 tumbles at 0.49 Pa, where the experiment's cells tank-tread
        for rate in TUMBLING:
            self.assertEqual(self.rows[rate]["mode"], "tumbling")

    def test_angle_and_volume(self):
        for rate, r in self.rows.items():
            with self.subTest(rate=rate):
                self.assertLess(float(r["volume_rel_max_dev"]), 0.01)
                if r["mode"] == "tank-treading":
                    self.assertGreater(float(r["angle_mean"]), 5.0)
                    self.assertLess(float(r["angle_mean"]), 20.0)


class RbcShearAnalysis(unittest.TestCase):
    """The frequency measurement itself, on made-up histories."""

    def test_tank_treading_with_swinging(self):
        rbc_shear = sample_module()
        t = np.arange(0.0, 60.0, 0.1)
        omega = 0.23                                   # rad per unit strain
        theta = 10.0 + 12.0 * np.sin(2.0 * omega * t)  # swinging at twice the tank-treading rate
        phases = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
        # nodes on an elongated ellipse turning clockwise (phi decreasing), folded into (-pi, pi]
        psi = omega * t[:, None] + phases[None, :]
        x, z = 4.0 * np.cos(psi), 1.5 * np.sin(-psi)
        th = np.radians(theta)[:, None]
        phi = np.arctan2(x * np.sin(th) + z * np.cos(th), x * np.cos(th) - z * np.sin(th))
        r = rbc_shear.analyse(t, phi, theta)
        self.assertEqual(r["mode"], "tank-treading")
        self.assertAlmostEqual(r["omega"], omega, delta=0.01 * omega)
        self.assertAlmostEqual(r["angle_mean"], 10.0, delta=1.0)

    def test_tumbling(self):
        rbc_shear = sample_module()
        t = np.arange(0.0, 60.0, 0.1)
        theta = np.degrees(-0.2 * t)                   # the long axis turns with the flow
        theta = (theta + 90.0) % 180.0 - 90.0
        phi = np.arctan2(np.sin(-0.2 * t), np.cos(-0.2 * t))[:, None] * np.ones((1, 5))
        r = rbc_shear.analyse(t, phi, theta)
        self.assertEqual(r["mode"], "tumbling")
        self.assertAlmostEqual(r["tumble_rate"], 0.2, delta=0.01)

    def test_experiment_groups(self):
        rbc_shear = sample_module()
        rates, ttf = rbc_shear.read_ttf()
        groups = rbc_shear.experiment_groups(rates, ttf)
        self.assertEqual(len(groups), 6)
        self.assertEqual(sum(g["n"] for g in groups), len(rates))
        np.testing.assert_allclose([g["rate"] for g in groups], rbc_shear.EXPERIMENT_RATES, rtol=0.02)

    def test_bad_input_named(self):
        rbc_shear = sample_module()
        with self.assertRaisesRegex(ValueError, "shear_rate"):
            rbc_shear.run_rbc(-1.0)
        with self.assertRaisesRegex(ValueError, "coupling"):
            rbc_shear.run_rbc(100.0, coupling=0.0)


if __name__ == "__main__":
    unittest.main()
