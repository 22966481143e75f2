"""The cell half of the accuracy benchmark (maintainer/benchmarks/accuracy/
cells.py) in a tiny version: its measures see what they claim to see.

- The optical-tweezers stretch (Mills et al. 2004) of the paper's RBC at
  100 pN: the coarse meshes' axial diameter approaches the rbc1002 value as
  the mesh is refined (measured: rbc162 4.1 %, rbc374 0.7 % off), and the
  cell is longer than at rest by more than 30 % (the benchmark's full run
  gives 12-13 um against 7.8 um at rest).
- A free cell relaxes at dt 0.1 and blows up at dt 3 with a named
  lbmd.SimulationInstability (the stability map's two sides).
- The interpenetration measure finds nothing between two separate cells and
  the overlap of two cells moved into each other (winding numbers).
- The rows go to CSV with their columns and the charts are written."""
import csv
import os
import sys
import tempfile
import unittest

import numpy as np

import lbmd
import oif

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "maintainer", "benchmarks", "accuracy"))
import cells  # noqa: E402
from benchmark_csv import write_rows  # noqa: E402


class TestAccuracyCells(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.stretch = {m: cells.stretch_one(m, (0.1,), chunk=500)[0] for m in ("rbc162", "rbc374", "rbc1002")}

    def test_stretch_converges_with_mesh(self):
        ref = self.stretch["rbc1002"]["axial_um"]
        err = {m: abs(self.stretch[m]["axial_um"] / ref - 1) for m in ("rbc162", "rbc374")}
        print("stretched axial diameter at 100 pN:", {m: round(r["axial_um"], 4) for m, r in self.stretch.items()},
              "errors vs rbc1002:", err)
        for r in self.stretch.values():
            self.assertTrue(r["converged"], r)
            self.assertGreater(r["axial_um"], 1.3 * 2 * cells.R_RBC)
            self.assertLess(r["transverse_um"], 2 * cells.R_RBC)
            self.assertAlmostEqual(r["volume_rel"], 1.0, delta=0.01)
        self.assertGreater(err["rbc162"], err["rbc374"])
        self.assertLess(err["rbc162"], 0.06)
        self.assertLess(err["rbc374"], 0.02)

    def test_stability_sides(self):
        self.assertEqual(cells.relax_trial("rbc162", 0.1, {}, steps=400)[0], "stable")
        outcome, msg = cells.relax_trial("rbc162", 3.0, {}, steps=400)
        self.assertEqual(outcome, "raised", msg)
        self.assertIn("unstable", msg)

    def test_interpenetration_measure(self):
        s = lbmd.System(box_l=[30.0, 30.0, 30.0])
        ct = cells.cell_type(s, "rbc162")
        a = oif.OifCell(cell_type=ct, particle_type=0, origin=[8.0, 15.0, 15.0])
        b = oif.OifCell(cell_type=ct, particle_type=0, origin=[17.0, 15.0, 15.0])
        periodic = np.array([True, True, True])
        self.assertEqual(cells.interpenetration([a, b], s.box_l, periodic), (0.0, 0, 0))
        # b's centre 2 um from a's: the rims overlap by about 5.8 um along x
        b.particles.pos = b.particles.pos - [7.0, 0.0, 0.0]
        deepest, inside, crossed = cells.interpenetration([a, b], s.box_l, periodic)
        self.assertGreater(deepest, 0.5)
        self.assertGreater(inside, 20)
        self.assertEqual(crossed, 2)
        # across the periodic boundary: the same overlap seen through the image
        a.particles.pos = a.particles.pos + [30.0, 0.0, 0.0]
        self.assertEqual(cells.interpenetration([a, b], s.box_l, periodic)[1], inside)

    def test_csv_and_charts(self):
        rows = list(self.stretch.values())
        ref = self.stretch["rbc1002"]
        for r in rows:
            r["err_axial"] = abs(r["axial_um"] / ref["axial_um"] - 1)
            r["err_transverse"] = abs(r["transverse_um"] / ref["transverse_um"] - 1)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "cells_stretch.csv")
            write_rows(path, rows)
            with open(path) as f:
                header = next(csv.reader(f))
            for col in ("mesh", "nodes", "force_nN", "axial_um", "transverse_um", "cpu_s", "err_axial"):
                self.assertIn(col, header)
            written = cells.charts({"cells_stretch": rows}, tmp)
            self.assertEqual([os.path.basename(p) for p in written], ["cells_stretch.png"])
            self.assertGreater(os.path.getsize(written[0]), 1000)


if __name__ == "__main__":
    unittest.main()
