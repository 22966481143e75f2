"""The robustness map's slice (samples/validation/robustness_map.py): a
D 10 um tube at H_D 0.45 (cells packed by oif.pack_cells to Pries' tube
haematocrit, 0.32: 11 rbc374 cells in 40 um), Ca 10, the published moduli,
the advised hard_contact, two seeds, 30 wall strain units each.

Asserted per run: it reaches its 30 strain units with no
SimulationInstability (a membrane crossing would be one) and no packing
failure; the tube haematocrit packed is within 0.01 of Pries' 0.321; every
cell's volume stays within 1 % of its start; its surface within 2.5 %.
The map's own criterion for the surface is 1 %: at Ca 10 the published
global-area modulus (kag 0.7) lets a squeezed cell's surface grow by
1.8 % (seed 1, 29 Nov 2026), so this slice fails the map's surface
criterion, which the map shows; the 2.5 % here guards against worse.
About 2 x 100 CPU s."""
import os
import tempfile
import unittest

from testsuite_data import run_sample, read_csv

SAMPLE = "validation/robustness_map.py"
PRIES_HT = 0.321  # H_D 0.45 x Pries et al. 1990's H_T/H_D at D 10


class RobustnessSlice(unittest.TestCase):
    def test_dense_narrow_tube_runs_its_length(self):
        with tempfile.TemporaryDirectory() as tmp:
            run_sample(SAMPLE, "--diameters", "10", "--hd", "0.45", "--ca", "10", "--seeds", "1", "2",
                       "--strain", "30", "--output", "out", cwd=tmp, timeout=1500)
            rows = read_csv(os.path.join(tmp, "out", "robustness_map.csv"))
            self.assertTrue(os.path.exists(os.path.join(tmp, "out", "robustness_map.png")))
        self.assertEqual(len(rows), 2)
        for r in rows:
            print(f"[ figure ] seed {r['seed']}: {r['status']} {r['cause']}; H_T {float(r['H_T']):.3f}, strain "
                  f"{float(r['strain_reached']):.1f}, volume {100 * float(r['worst_volume_dev']):.2f} %, surface "
                  f"{100 * float(r['worst_surface_dev']):.2f} %, {float(r['cpu_s']):.0f} CPU s")
            self.assertIn(r["status"], ("passed", "drift"), r["message"])
            # the run's samples are whole steps apart: 29.99 of 30 is the end
            self.assertGreaterEqual(float(r["strain_reached"]), 0.99 * 30.0)
            self.assertLess(abs(float(r["H_T"]) - PRIES_HT), 0.01)
            self.assertLess(float(r["worst_volume_dev"]), 0.01)
            self.assertLess(float(r["worst_surface_dev"]), 0.025)


if __name__ == "__main__":
    unittest.main()
