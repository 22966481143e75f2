#!/usr/bin/env pyoif
"""Time the picture helpers of lbmd.visualization on the flagship scene and
write the figures of doc/visualization.md.

    pyoif maintainer/benchmarks/visualization_timings.py [--steps N] [--figures DIR] [--repeat R]

The scene is the one samples/cell_flow_in_bifurcation.py builds (--small,
case A, 24 RBCs): the sample itself runs (runpy) with --cycles 0 and the
body force given (no calibration runs), so that its globals (system, lbf,
cells, UNITS) are the scene; then N steps (default 1000) let the flow start
before the pictures are timed (best of R calls each).
"""
import argparse
import os
import runpy
import sys
import tempfile
import time

from lbmd import visualization as vis

here = os.path.dirname(os.path.abspath(__file__))
sample = os.path.join(here, "..", "..", "samples", "cell_flow_in_bifurcation.py")
ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--steps", type=int, default=1000, help="steps run before the pictures")
ap.add_argument("--repeat", type=int, default=3, help="calls per helper (the best is reported)")
ap.add_argument("--figures", default=None, help="folder for the PNGs (default: a temporary folder)")
ap.add_argument("--force", type=float, default=0.0032,
                help="body force density (lattice units; the sample calibrates about 0.0032 for --small)")
args = ap.parse_args()

output = tempfile.mkdtemp(prefix="vis_scene_")
argv = sys.argv
sys.argv = [sample, "--small", "--cycles", "0", "--force", str(args.force), "--no-plots", "--progress", "off",
            "--output", output]
t0 = time.perf_counter()
scene = runpy.run_path(sample, run_name="__main__")
sys.argv = argv
system, cells, units = scene["system"], scene["cells"], scene["UNITS"]
print(f"scene built in {time.perf_counter() - t0:.1f} s: box {list(system.box_l)}, {len(cells)} cells, "
      f"{len(system.lbboundaries)} LBBoundaries")
t0 = time.perf_counter()
system.integrator.run(args.steps)
print(f"{args.steps} steps in {time.perf_counter() - t0:.1f} s")

figures = args.figures or output
os.makedirs(figures, exist_ok=True)
z_mid = 0.5 * system.box_l[2]
cases = {
    "geometry": lambda: vis.geometry(system, "z", z_mid, units=units),
    "geometry_no_outlines": lambda: vis.geometry(system, "z", z_mid, units=units, outlines=False),
    "fluid_stream": lambda: vis.fluid(system, "z", z_mid, units=units),
    "fluid_quiver": lambda: vis.fluid(system, "z", z_mid, units=units, arrows="quiver"),
    "cells_slice": lambda: vis.cells(system, cells, "z", z_mid, units=units, color_by="deformation"),
    "cells_projected": lambda: vis.cells(system, cells, "z", mode="projected", units=units, color_by="velocity"),
}
print(f"{'helper':22s} {'figure':>9s} {'+ PNG':>9s}")
for name, make in cases.items():
    best, best_png = float("inf"), float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        fig = make()
        t1 = time.perf_counter()
        fig.savefig(os.path.join(figures, f"{name}.png"), dpi=100)
        best, best_png = min(best, t1 - t0), min(best_png, time.perf_counter() - t0)
    print(f"{name:22s} {best * 1e3:6.0f} ms {best_png * 1e3:6.0f} ms")
try:
    best = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        vis.snapshot_3d(system, cells, os.path.join(figures, "snapshot_3d.png"), color_by="deformation",
                        units=units)
        best = min(best, time.perf_counter() - t0)
    print(f"{'snapshot_3d':22s} {'':9s} {best * 1e3:6.0f} ms")
except RuntimeError as e:
    print(f"snapshot_3d: {e}")
print(f"figures in {figures}")
