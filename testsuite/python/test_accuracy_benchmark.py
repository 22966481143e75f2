"""The fluid part of maintainer/benchmarks/accuracy_vs_cost.py in its
smallest form (accuracy.fluid.TINY, a few seconds): it must write the CSV
files with their columns and non-empty PNG charts, and its rows must carry
the physics the benchmark is there to show.

- Poiseuille, 20 fluid nodes across, nu_lattice = 1, peak speed 0.025
  (Re 0.5): the default MRT keeps the bounce-back wall midway, maximum
  error < 1e-4 of the peak speed (measured 1.2e-5, a compressibility error
  ~ u^2; single precision, where the build has it: < 1e-3); MRT_ESPRESSO
  (ESPResSo 4.2's ghost relaxation) puts it elsewhere: ESPResSo's own
  1.75e-2 within 5 % (measured 1.755e-2).
- Stokes drag of a sphere of radius 3 nodes in a periodic box of 15: within
  3 % of Sangani & Acrivos' periodic-array drag (measured +2.1 %, the
  staircase sphere), the drag balancing the driving force within 1e-3.
- Stability: MRT at tau_lattice 1, Mach 0.1 is stable over 4 convective
  times; BGK at tau_lattice 0.5005, Mach 0.7 raises SimulationInstability.
"""
import csv
import os
import sys
import tempfile
import unittest

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "maintainer", "benchmarks"))

import accuracy_vs_cost  # noqa: E402
from accuracy import fluid  # noqa: E402

COLUMNS = {
    "fluid_poiseuille": {"study", "collision", "precision", "nodes_across", "nu_lattice", "tau_lattice",
                         "mach", "err_max", "err_l2", "updates", "node_updates", "cpu_s", "wall_s"},
    "fluid_stokes": {"collision", "precision", "radius_nodes", "box_nodes", "nu_lattice", "drag_ratio",
                     "err_rel", "force_balance", "converged", "updates", "node_updates", "cpu_s"},
    "fluid_stability": {"collision", "precision", "nu_lattice", "tau_lattice", "mach", "stable", "reason",
                        "energy_growth", "updates", "node_updates", "cpu_s"},
}


class AccuracyBenchmark(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.results, cls.pngs = accuracy_vs_cost.run_parts(["fluid"], cls.tmp.name, fluid_cases=fluid.TINY)
        cls.precisions = fluid.precisions_available()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def rows(self, name, **match):
        return [r for r in self.results[name] if all(r[k] == v for k, v in match.items())]

    def test_files(self):
        for name, columns in COLUMNS.items():
            with open(os.path.join(self.tmp.name, name + ".csv")) as f:
                rows = list(csv.DictReader(f))
            self.assertEqual(len(rows), len(fluid.TINY[name.split("_")[1]]) * len(self.precisions), name)
            self.assertLessEqual(columns, set(rows[0]), name)
        names = sorted(os.path.basename(p) for p in self.pngs)
        self.assertEqual(names, ["fluid_poiseuille_viscosity.png", "fluid_stability.png", "fluid_stokes.png"])
        for p in self.pngs:
            with open(p, "rb") as f:
                data = f.read()
            self.assertTrue(data.startswith(b"\x89PNG"), p)
            self.assertGreater(len(data), 5000, p)

    def test_poiseuille_wall(self):
        for prec in self.precisions:
            (mrt,) = self.rows("fluid_poiseuille", collision="MRT", precision=prec)
            self.assertLess(mrt["err_max"], 1e-4 if prec == "double" else 1e-3, prec)
            (esp,) = self.rows("fluid_poiseuille", collision="MRT_ESPRESSO", precision=prec)
            self.assertAlmostEqual(esp["err_max"] / 1.75e-2, 1.0, delta=0.05, msg=prec)
            self.assertGreater(mrt["node_updates"], 0)
            self.assertGreater(mrt["updates"], 1000)  # 40 / pi^2 diffusion times at N = 20

    def test_stokes_drag(self):
        for prec in self.precisions:
            (row,) = self.rows("fluid_stokes", precision=prec)
            self.assertEqual(row["converged"], 1)
            self.assertAlmostEqual(row["force_balance"], 1.0, delta=1e-3)
            self.assertAlmostEqual(row["drag_ratio"], 1.0, delta=0.03)

    def test_stability(self):
        for prec in self.precisions:
            (stable,) = self.rows("fluid_stability", collision="MRT", precision=prec)
            self.assertEqual(stable["stable"], 1)
            self.assertEqual(stable["updates_done"], stable["updates_planned"])
            (broken,) = self.rows("fluid_stability", collision="BGK", precision=prec)
            self.assertEqual(broken["stable"], 0)
            self.assertEqual(broken["reason"], "SimulationInstability")

    def test_bad_precision(self):
        with self.assertRaisesRegex(ValueError, "precisions"):
            fluid.run(precisions=["quadruple"], cases=fluid.TINY, log=None)


if __name__ == "__main__":
    unittest.main()
