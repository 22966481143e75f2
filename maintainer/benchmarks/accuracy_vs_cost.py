#!/usr/bin/env pyoif
"""Speed against accuracy: for fixed physical questions, the error against a
reference and the cost of each setting, written as CSV (one file per
question) and PNG charts (error against cost, log scales), plus measured
stability maps.

    pyoif maintainer/benchmarks/accuracy_vs_cost.py [--part fluid|cells|all]
        [--out accuracy_out] [--quick] [--precision double single]

Parts (modules in accuracy/, each with run() -> {name: rows} and
charts(results, outdir)):
- fluid (accuracy/fluid.py): Poiseuille flow and the Stokes drag of a
  sphere against resolution, collision model and precision; the stability
  map of each collision model (lattice viscosity against Mach number).
- cells (accuracy/cells.py, where present): the cell membrane's side.

Cost is the CPU time (time.process_time) of the runs on one thread, with
the node-update counts beside it in the CSV. The figures and the advice
drawn from them: doc/accuracy.md. The default fluid part takes about 3 min
(95 s CPU) on the 2-core Xeon VM in double precision, --quick 20 s; single
precision, where LBFluid offers it, doubles that.
"""
import argparse
import importlib
import os
import sys
import time
import warnings

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)

from benchmark_csv import write_rows  # noqa: E402

PARTS = ("fluid", "cells")

# the studies go past the measured limits on purpose: the warnings that
# system.check_settings() gives at each scene's first run would only repeat
# what the charts show
warnings.filterwarnings("ignore", message="check_settings:")


def part_module(name):
    """The module accuracy.<name>, or None where this checkout has none."""
    try:
        return importlib.import_module(f"accuracy.{name}")
    except ModuleNotFoundError as e:
        if e.name in (f"accuracy.{name}", "accuracy"):
            return None
        raise


def run_parts(parts, outdir, quick=False, precisions=None, fluid_cases=None):
    """Runs the parts, writes name.csv and the charts into outdir; returns
    ({name: rows}, [png paths])."""
    os.makedirs(outdir, exist_ok=True)
    results, pngs = {}, []
    for part in parts:
        module = part_module(part)
        if module is None:
            print(f"part '{part}': accuracy/{part}.py is not in this checkout; skipped")
            continue
        t0 = time.perf_counter()
        if part == "fluid":
            res = module.run(quick, precisions=precisions, cases=fluid_cases)
        else:
            res = module.run(quick)
        for name, rows in res.items():
            write_rows(os.path.join(outdir, f"{name}.csv"), rows)
        pngs += module.charts(res, outdir)
        results.update(res)
        print(f"part '{part}': {time.perf_counter() - t0:.0f} s wall")
    for p in pngs:
        print(f"written {os.path.abspath(p)}")
    return results, pngs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", nargs="+", choices=PARTS + ("all",), default=["all"])
    ap.add_argument("--out", default="accuracy_out", help="folder for the CSV and PNG files")
    ap.add_argument("--quick", action="store_true", help="fewer settings (about a minute per part)")
    ap.add_argument("--precision", nargs="+", choices=("double", "single"), default=None,
                    help="fluid precisions (default: every one LBFluid offers)")
    args = ap.parse_args(argv)
    parts = PARTS if "all" in args.part else tuple(args.part)
    run_parts(parts, args.out, quick=args.quick, precisions=args.precision)


if __name__ == "__main__":
    main()
