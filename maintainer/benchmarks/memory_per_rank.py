#!/usr/bin/env pyoif
"""Resident memory per MPI rank of a dense red-cell scene, at 1, 2 and 4
ranks: what a rank must hold, and whether it falls with the rank count.

    pyoif maintainer/benchmarks/memory_per_rank.py [--cells 2000] [--ranks 1 2 4]
        [--steps 10] [--csv memory_per_rank.csv] [--chart memory_per_rank.png]

(as root, Open MPI needs OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
in the environment; more ranks than cores run oversubscribed, which costs
time, not memory.)

The scene: --cells rbc374 red cells (radius 3.91 um, the published OIF
moduli of the samples) stacked as discs on a regular grid (9 um apart
across, 4 um along the stack; haematocrit about 0.29: the count matters
here, not the packing), in a periodic box of fluid (agrid 1 um, one
lattice node per um^3), coupled, with the membrane collision between
cells; --steps time steps run so that every buffer of a step exists. The
2000-cell default is the issue's scene: 748 000 membrane nodes, a lattice
of 90 x 90 x 88 nodes.

Each configuration runs in its own `mpirun -np K` (K = 1: the launcher
alone), so that no rank count inherits another's memory. Per rank, after
the steps: the resident set (VmRSS) and its peak (VmHWM) from
/proc/self/status, and what the two big stores hold on that rank: the
particles (the engine's particle arrays: n_local, as stored) and the
lattice (this rank's subdomain with its ghost layer, 19 populations).
Printed per K: the largest rank's figures and their ratio to the 1-rank
figure, and what each stage added to the resident set (the interpreter
and libraries at the start; the cells made; the fluid added, coupled and
flagged; the steps run: ghosts, pair lists, the coupling's records); written: CSV (one row per rank) and a chart of the largest rank's
resident set against K beside the ideal 1/K.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from benchmark_csv import status_mb, write_rows  # noqa: E402

RADIUS = 3.91
ACROSS, ALONG = 9.0, 4.0  # grid spacing of the stacked discs (um; whole lattice spacings)


def grid_for(n_cells):
    """(nx, ny, nz) cells per axis: a near-cubic box of stacked discs."""
    # box sides nx * ACROSS, ny * ACROSS, nz * ALONG about equal
    nz = max(1, round((n_cells * ACROSS ** 2 / ALONG ** 2) ** (1.0 / 3.0)))
    nxy = max(1, int(-(-((n_cells / nz) ** 0.5) // 1)))
    while nxy * nxy * nz < n_cells:
        nz += 1
    return nxy, nxy, nz


def child(cells, steps, out):
    """One configuration, under mpirun: build, run, report per rank."""
    import numpy as np

    import lbmd
    import oif
    from lbmd import lb

    stages = {"start": status_mb("VmRSS")}
    nx, ny, nz = grid_for(cells)
    box = [nx * ACROSS, ny * ACROSS, nz * ALONG]
    system = lbmd.System(box_l=box)
    system.time_step = 0.1
    system.cell_system.skin = 0.3
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(RADIUS,) * 3,
                          ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9, normal=True)
    made = 0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                if made == cells:
                    break
                oif.OifCell(cell_type=rbc, particle_type=0,
                            origin=[(i + 0.5) * ACROSS, (j + 0.5) * ACROSS, (k + 0.5) * ALONG])
                made += 1
    stages["cells"] = status_mb("VmRSS")
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=1.5, dens=1.0))
    oif.set_contacts(system, rbc, particle_types=0)
    system.prepare()
    stages["fluid"] = status_mb("VmRSS")
    system.integrator.run(steps)
    stages["run"] = status_mb("VmRSS")
    core = system._core
    local = [int(n) for n in lbf._core.local_shape]
    report = {"rank": lbmd.rank, "ranks": lbmd.size, "cells": made, "nodes": int(len(system.part.all().id)),
              "box": box, "lattice": [int(n) for n in lbf.shape], "local_lattice": local,
              "particles_stored": int(core.n_particles()),
              "lattice_mb": 19 * 8 * float(np.prod([n + 2 for n in local])) / 2 ** 20,
              "rss_mb": status_mb("VmRSS"), "peak_mb": status_mb("VmHWM"),
              # what each stage added to the resident set
              "start_mb": stages["start"], "cells_mb": stages["cells"] - stages["start"],
              "fluid_mb": stages["fluid"] - stages["cells"], "run_mb": stages["run"] - stages["fluid"]}
    reports = lbmd.comm.gather(report, root=0)
    if lbmd.rank == 0:
        with open(out, "w") as f:
            json.dump(reports, f)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, default=2000)
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--csv", default="memory_per_rank.csv")
    ap.add_argument("--chart", default="memory_per_rank.png")
    ap.add_argument("--pyoif", default=os.path.join(HERE, "..", "..", "build", "pyoif"))
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--child", nargs=3, metavar=("CELLS", "STEPS", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(int(args.child[0]), int(args.child[1]), args.child[2])
        return
    if 1 not in args.ranks:
        ap.error("--ranks must include 1 (the reference)")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    per_k = {}
    with tempfile.TemporaryDirectory() as tmp:
        for k in sorted(args.ranks):
            out = os.path.join(tmp, f"np{k}.json")
            cmd = [args.pyoif, os.path.abspath(__file__), "--child", str(args.cells), str(args.steps), out]
            if k > 1:
                cmd = [args.mpirun, "--oversubscribe", "-np", str(k)] + cmd
            p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
            if p.returncode != 0:
                raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-3000:]}")
            with open(out) as f:
                per_k[k] = json.load(f)
            big = max(per_k[k], key=lambda r: r["rss_mb"])
            print(f"  {k} rank(s): largest rank {big['rss_mb']:.0f} MB resident (peak {big['peak_mb']:.0f})",
                  flush=True)
    first = per_k[1][0]
    print(f"{first['cells']} rbc374 cells, {first['nodes']} membrane nodes, lattice "
          f"{'x'.join(str(n) for n in first['lattice'])} (box {' x '.join(f'{b:g}' for b in first['box'])} um)")
    print(f"{'ranks':>5s} {'rank':>4s} {'local lattice':>14s} {'lattice MB':>10s} {'particles':>9s} "
          f"{'RSS MB':>8s} {'peak MB':>8s} {'RSS / 1 rank':>12s} | {'start':>6s} {'+cells':>6s} {'+fluid':>6s} "
          f"{'+run':>6s}")
    rows = []
    ref = max(r["rss_mb"] for r in per_k[1])
    for k in sorted(per_k):
        for r in per_k[k]:
            stored = str(r["particles_stored"])
            print(f"{k:5d} {r['rank']:4d} {'x'.join(str(n) for n in r['local_lattice']):>14s} "
                  f"{r['lattice_mb']:10.1f} {stored:>9s} {r['rss_mb']:8.0f} {r['peak_mb']:8.0f} "
                  f"{r['rss_mb'] / ref:12.2f} | {r['start_mb']:6.0f} {r['cells_mb']:6.0f} {r['fluid_mb']:6.0f} "
                  f"{r['run_mb']:6.0f}")
            rows.append(dict(r, local_lattice="x".join(str(n) for n in r["local_lattice"]),
                             lattice="x".join(str(n) for n in r["lattice"]), box=" ".join(f"{b:g}" for b in r["box"]),
                             rss_over_one_rank=r["rss_mb"] / ref))
    write_rows(args.csv, rows)
    if args.chart:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        ks = sorted(per_k)
        largest = [max(r["rss_mb"] for r in per_k[k]) for k in ks]
        fig, ax = plt.subplots(figsize=(5, 3.6))
        ax.plot(ks, largest, "o-", label="largest rank, measured")
        ax.plot(ks, [ref / k for k in ks], "k--", label="1/K of one rank (ideal)")
        ax.set_xlabel("MPI ranks K")
        ax.set_ylabel("resident memory per rank (MB)")
        ax.set_xticks(ks)
        ax.set_ylim(bottom=0)
        ax.set_title(f"{first['cells']} RBCs, {first['nodes']} nodes")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.chart, dpi=120)
        print(f"written {os.path.abspath(args.chart)}")


if __name__ == "__main__":
    main()
