#!/usr/bin/env pyoif
"""The membrane pass alone: microseconds per cell per time step of the
membrane phase (integrator.timings()['membrane']) for n cells of one type,
without fluid, with the cells in vector lanes (four at a time, the default)
and one at a time (system._core.membrane_lanes = False), taken alternately.

    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/membrane_cost.py [--cells 1 4 5 20] [--steps 200] [--rounds 7]
        [--kvisc 0] [--mass 1] [--csv membrane_cost.csv]

Cells: rbc374 scaled by 4 with the paper's moduli (ks 0.005, kb 0.02, kal
0.007, kag 0.7, kv 0.9) and normals, on a cubic grid 16 apart, randomly
rotated and roughened (noise 0.02), Langevin friction only (no contacts, no
fluid). The least of --rounds runs of --steps steps counts. --kvisc adds
the membrane viscosity (implicit: the conjugate-gradient iterations per
solve are printed), --mass the node mass (the samples' 0.51 at gamma dt/m
0.3; the viscous system's conditioning grows with dt kvisc / m).
"""
import argparse

import numpy as np

import lbmd
import oif
from benchmark_csv import write_rows


def scene(n, lanes, kvisc=0.0, mass=1.0):
    rng = np.random.default_rng(1)
    m = int(np.ceil(n ** (1 / 3)))
    s = lbmd.System(box_l=[16.0 * m] * 3)
    s.time_step = 0.1
    s.cell_system.skin = 0.2
    s._core.membrane_lanes = lanes
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(4, 4, 4), ks=0.005, kb=0.02,
                         kal=0.007, kag=0.7, kv=0.9, normal=True, kvisc=kvisc)
    for k in range(n):
        i, j, l = k % m, (k // m) % m, k // (m * m)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[8 + 16 * i, 8 + 16 * j, 8 + 16 * l],
                           rotate=rng.uniform(0, 6, 3), particle_mass=mass)
        x = cell.particles.pos
        cell.particles.pos = x + rng.normal(scale=0.02, size=x.shape)
    s.thermostat.set_langevin(kT=0.0, gamma=0.1, seed=1)
    s.integrator.run(20)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, nargs="+", default=[1, 4, 5, 20])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--kvisc", type=float, default=0.0)
    ap.add_argument("--mass", type=float, default=1.0)
    ap.add_argument("--csv", default=None)
    args = ap.parse_args()
    rows = []
    for n in args.cells:
        systems = {"lanes": scene(n, True, args.kvisc, args.mass),
                   "one at a time": scene(n, False, args.kvisc, args.mass)}
        best = dict.fromkeys(systems, np.inf)
        for _ in range(args.rounds):
            for name, s in systems.items():
                before = s._core.membrane_counts()
                s.integrator.reset_timings()
                s.integrator.run(args.steps)
                best[name] = min(best[name], s.integrator.timings()["membrane"] / args.steps / n * 1e6)
                after = s._core.membrane_counts()
                per_step = {k: (after[k] - before[k]) / args.steps for k in after}
                if name == "lanes":
                    groups, alone = per_step["lane_batches"], per_step["plain_cells"]
                    iterations = per_step["viscous_iterations"] / max(per_step["viscous_solves"], 1)
        print(f"{n:4d} cells: {best['lanes']:6.2f} us per cell per step in lanes ({groups:.0f} groups of "
              f"four lanes and {alone:.0f} cells alone per step), {best['one at a time']:6.2f} one at a time; "
              f"kvisc {args.kvisc:g}, mass {args.mass:g}: {iterations:.1f} CG iterations per viscous solve")
        rows.append({"cells": n, "kvisc": args.kvisc, "mass": args.mass, "cg_iterations": iterations,
                     "lanes_us_per_cell_step": best["lanes"],
                     "one_at_a_time_us_per_cell_step": best["one at a time"]})
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
