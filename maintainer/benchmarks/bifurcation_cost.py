#!/usr/bin/env pyoif
"""Cost of the paper's bifurcation scene: CPU seconds per 1000 MD steps of
samples/cell_flow_in_bifurcation.py --full (box 160x40x22, agrid 1 um,
time step = tau = 0.1 us, the paper's 40 RBCs of 374 nodes and the stiff rare
cell of 642 nodes) on one core, without cells (fluid + rare cell) and with
them, against the paper's Table 1 (one core: 48.14 s without cells, 145.0 s
with 40), and the time the paper's 138 ms of flow (1.38 million steps; 16
hours on 6 cores in the paper) would take.

    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/bifurcation_cost.py [--steps 500]
        [--cells 0 40] [--csv bifurcation_cost.csv]

Each figure is the CPU time of the sample run for --steps + 20 steps minus
that of a run for 20 steps (so the set-up, seeding and output cancel).
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile

from benchmark_csv import write_rows

PAPER_ONE_CORE = {0: 48.14, 40: 145.00}  # s per 1000 steps, Table 1
STEPS_138_MS = 1_380_000


def child_cpu_seconds(args):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=500, help="timed MD steps (on top of 20)")
    ap.add_argument("--cells", type=int, nargs="+", default=[0, 40], help="numbers of RBCs")
    ap.add_argument("--csv", default="bifurcation_cost.csv")
    args = ap.parse_args()
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("note: set OMP_NUM_THREADS=1 for the one-core figure")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sample = os.path.join(root, "samples", "cell_flow_in_bifurcation.py")
    rows = []
    with tempfile.TemporaryDirectory() as out:
        for n in args.cells:
            run = [sys.executable, sample, "--full", "--cells", str(n), "--cycles", "1", "--output", out]
            short = child_cpu_seconds(run + ["--steps", "20"])
            long = child_cpu_seconds(run + ["--steps", str(20 + args.steps)])
            s1000 = (long - short) * 1000.0 / args.steps
            hours = s1000 * STEPS_138_MS / 1000.0 / 3600.0
            paper = PAPER_ONE_CORE.get(n)
            print(f"{n:3d} RBCs + rare cell: {s1000:7.2f} CPU s / 1000 steps"
                  + (f" (paper, one core: {paper:.2f} s; {paper / s1000:.1f}x)" if paper else "")
                  + f"; 138 ms of flow: {hours:.1f} h on one core (paper: 16 h on 6 cores = 96 core-hours)")
            rows.append({"rbcs": n, "cpu_s_per_1000_steps": s1000, "paper_one_core_s": paper or "",
                         "hours_for_138_ms_one_core": hours})
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
