#!/usr/bin/env pyoif
"""Checkpoint size and save/load time for the paper's bifurcation scene
(samples/cell_flow_in_bifurcation.py --full: lattice 160 x 40 x 22, the
40 RBCs of 374 nodes and the rare cell of 642; the body force given, so no
calibration run), as the sample writes it (system, fluid, cells and the
sample's bookkeeping).

    [mpirun -np N] pyoif maintainer/benchmarks/checkpoint_io.py [--repeats 3]
        [--cells 40] [--csv checkpoint_io.csv]

Prints the file size, and the least of --repeats wall times of
lbmd.checkpoint.save (gather: particles and lattice to rank 0, pickle,
HDF5 write, fsync, rename) and of lbmd.checkpoint.load (rank 0 reads, hands
the file to the others, the scene rebuilt and the state restored), and
the time of 1000 steps of the scene for scale, and per rank the peak
memory above the resident set that save and load took (Linux: the peak
is reset through /proc/self/clear_refs before each, read from VmHWM
after): what a rank must have spare to write or read a checkpoint.
Collective under mpirun.
"""
import argparse
import contextlib
import io
import os
import runpy
import sys
import tempfile
import time

import lbmd

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLE = os.path.join(HERE, "..", "..", "samples", "cell_flow_in_bifurcation.py")
sys.path.insert(0, HERE)
from benchmark_csv import status_mb, write_rows  # noqa: E402


def _peak_above_resident(action):
    """(result of action(), MB of peak resident memory above the start)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # the peak resident set starts again from the current one
    except OSError:
        pass
    start = status_mb("VmRSS")
    result = action()
    return result, max(0.0, status_mb("VmHWM") - start)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cells", type=int, default=40)
    ap.add_argument("--csv", default="checkpoint_io.csv")
    args = ap.parse_args()
    folder = tempfile.mkdtemp(prefix="checkpoint_io_") if lbmd.rank == 0 else None
    folder = lbmd.comm.bcast(folder, root=0)
    argv = sys.argv
    sys.argv = ["cell_flow_in_bifurcation.py", "--full", "--cells", str(args.cells), "--force", "6.918e-05",
                "--cycles", "1", "--steps", "10", "--no-plots", "--progress", "off", "--output", folder]
    with contextlib.redirect_stdout(io.StringIO()):
        g = runpy.run_path(SAMPLE, run_name="__main__")
    sys.argv = argv
    system = g["system"]
    path = os.path.join(folder, "checkpoint.h5")
    saves, loads = [], []
    # per rank the peak memory a save and a load take (first, untimed)
    lbmd.comm.Barrier()
    _, save_peak = _peak_above_resident(
        lambda: lbmd.checkpoint.save(path, system, **g["checkpoint_objects"]()))
    _, load_peak = _peak_above_resident(lambda: lbmd.checkpoint.load(path))
    save_peaks = lbmd.comm.gather(save_peak, root=0)
    load_peaks = lbmd.comm.gather(load_peak, root=0)
    for _ in range(args.repeats):
        lbmd.comm.Barrier()
        t0 = time.perf_counter()
        lbmd.checkpoint.save(path, system, **g["checkpoint_objects"]())
        lbmd.comm.Barrier()
        saves.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ns = lbmd.checkpoint.load(path)
        lbmd.comm.Barrier()
        loads.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    ns.system.integrator.run(1000)
    step_time = time.perf_counter() - t0
    size_mb = os.path.getsize(path) / 1e6 if lbmd.rank == 0 else 0.0
    if lbmd.rank == 0:
        print(f"bifurcation --full, {args.cells} RBCs + rare cell, {system.part.all().id.size} particles, "
              f"{lbmd.size} rank(s)")
        print(f"checkpoint {size_mb:.1f} MB; save {min(saves):.2f} s, load {min(loads):.2f} s "
              f"(least of {args.repeats}); 1000 steps of the loaded scene {step_time:.2f} s")
        print("peak memory above the resident set, MB per rank: save "
              + " ".join(f"{m:.1f}" for m in save_peaks) + "; load " + " ".join(f"{m:.1f}" for m in load_peaks))
        write_rows(args.csv, [dict(ranks=lbmd.size, cells=args.cells, size_mb=round(size_mb, 2),
                                   save_s=round(min(saves), 3), load_s=round(min(loads), 3),
                                   steps_1000_s=round(step_time, 2),
                                   save_peak_mb_per_rank=" ".join(f"{m:.1f}" for m in save_peaks),
                                   load_peak_mb_per_rank=" ".join(f"{m:.1f}" for m in load_peaks))])


if __name__ == "__main__":
    main()
