#!/usr/bin/env pyoif
"""Cost of the paper's bifurcation scene: seconds per 1000 MD steps of
samples/cell_flow_in_bifurcation.py --full (box 160x40x22, agrid 1 um,
time step = tau = 0.1 us, the paper's 40 RBCs of 374 nodes and the stiff rare
cell of 642 nodes) on one core, without cells (fluid + rare cell) and with
them, against the paper's Table 1 (one core: 48.14 s without cells, 145.0 s
with 40), and the time the paper's 138 ms of flow (1.38 million steps; 16
hours on 6 cores in the paper) would take.

    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/bifurcation_cost.py [--steps 500]
        [--repeats 2] [--cells 0 40] [--csv bifurcation_cost.csv]

Each figure is the wall time of the time steps alone, from the timing report
the sample prints (integrator.timings(): set-up, seeding and output are not
in it; the force computation a run starts with neither), for one run of
--steps steps; the least of --repeats runs counts (on a shared machine the
quietest). On one thread of an otherwise idle core, wall time is CPU time,
the paper's measure. Also printed: the lattice update's share.
(Until the ninth round the figure was the CPU time of a long run less that
of a short one, which the set-up's variation made noisy by several seconds.)
"""
import argparse
import os
import subprocess
import sys
import tempfile

from benchmark_csv import write_rows

PAPER_ONE_CORE = {0: 48.14, 5: 55.90, 10: 62.68, 20: 84.37, 40: 145.00, 60: 242.47}  # s per 1000 steps, Table 1
STEPS_138_MS = 1_380_000


def timed_steps(args):
    """(total, lattice update) wall seconds per step of the sample's time
    steps, read from its timing report."""
    out = subprocess.run(args, check=True, stdout=subprocess.PIPE, text=True).stdout
    total = lattice = None
    for line in out.splitlines():
        if line.startswith("total ("):
            total = float(line.split()[-2]) / 1000.0
        elif line.startswith("lattice-Boltzmann update"):
            lattice = float(line.split()[-2]) / 1000.0
    if total is None or lattice is None:
        raise RuntimeError("no timing report in the sample's output:\n" + out[-2000:])
    return total, lattice


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=500, help="timed MD steps per run")
    ap.add_argument("--cells", type=int, nargs="+", default=[0, 40], help="numbers of RBCs")
    ap.add_argument("--repeats", type=int, default=2, help="runs per configuration (the least counts)")
    ap.add_argument("--csv", default="bifurcation_cost.csv")
    args = ap.parse_args()
    if args.steps < 1 or args.repeats < 1:
        ap.error("--steps and --repeats must be at least 1")
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("note: set OMP_NUM_THREADS=1 for the one-core figure")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sample = os.path.join(root, "samples", "cell_flow_in_bifurcation.py")
    rows = []
    with tempfile.TemporaryDirectory() as out:
        for n in args.cells:
            run = [sys.executable, sample, "--full", "--cells", str(n), "--cycles", "1", "--output", out,
                   "--steps", str(args.steps), "--no-plots", "--progress", "off"]
            per_step, lattice = min(timed_steps(run) for _ in range(args.repeats))
            s1000 = 1000.0 * per_step
            hours = per_step * STEPS_138_MS / 3600.0
            paper = PAPER_ONE_CORE.get(n)
            print(f"{n:3d} RBCs + rare cell: {s1000:7.2f} wall s / 1000 steps (lattice update "
                  f"{100 * lattice / per_step:.0f} %)"
                  + (f"; paper, one core: {paper:.2f} CPU s ({paper / s1000:.1f}x)" if paper else "")
                  + f"; 138 ms of flow: {hours:.1f} h on one core (paper: 16 h on 6 cores = 96 core-hours)")
            rows.append({"rbcs": n, "s_per_1000_steps": s1000, "lattice_update_share": lattice / per_step,
                         "paper_one_core_s": paper or "", "hours_for_138_ms_one_core": hours})
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
