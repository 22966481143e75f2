"""Speed at density: the cost per cell per 1000 steps in one tube at a
dilute and a dense tube haematocrit, with the advised hard_contact, the
published moduli (rbc374) and the coupling; prints the phases and writes CSV.

    pyoif maintainer/benchmarks/dense_cost.py [--diameter 20] [--length 60] [--haematocrits 0.1 0.45] [--steps 1000] [--skin 0.2]

The tube: a cylinder along x, periodic along it, a body force driving
Poiseuille flow (centre speed 5 mm/s), the cells packed by
oif.pack_cells. The cost per cell is (time of the run - time of the same
tube without cells) / cells; the ratio dense / dilute is the issue's
measure (target: no more than 1.5).
"""
import argparse
import os
import platform
import time

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

from benchmark_csv import write_rows

VISC, DENS, DT = 1.5, 1.0, 0.1
PAPER = dict(ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)


def scene(d, length, haematocrit, seed=1, skin=0.2):
    side = d + 4.0
    s = lbmd.System(box_l=[length, side, side])
    s.periodicity = [True, False, False]
    s.time_step = DT
    s.cell_system.skin = skin
    tube = shapes.Cylinder(center=[length / 2, side / 2, side / 2], axis=[1, 0, 0], radius=d / 2,
                           length=10 * length, direction=-1)
    cells = []
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.91,) * 3, normal=True, **PAPER)
    if haematocrit > 0:
        cells = oif.pack_cells(s, ct, haematocrit=haematocrit, boundaries=[tube], seed=seed,
                               particle_mass=ct.suggest_LBgamma(visc=VISC, dens=DENS) * DT / 0.3)
    u_centre = 0.005  # um/us: 5 mm/s, a capillary number of the paper's order at the published moduli
    force = 4.0 * DENS * VISC * u_centre / (d / 2) ** 2
    lbf = lb.LBFluid(agrid=1.0, dens=DENS, visc=VISC, tau=DT, ext_force_density=[force, 0, 0])
    s.actors.add(lbf)
    s.lbboundaries.add(lbboundaries.LBBoundary(shape=tube))
    s.constraints.add(shape=tube, particle_type=10, penetrable=False)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=ct.suggest_LBgamma(visc=VISC, dens=DENS))
    oif.set_contacts(s, ct, particle_types=0, wall_types=10)
    return s, cells


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--diameter", type=float, default=20.0)
    ap.add_argument("--length", type=float, default=60.0)
    ap.add_argument("--haematocrits", type=float, nargs="+", default=[0.1, 0.45])
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--skin", type=float, default=0.2, help="the Verlet skin (um; 0.2 measured the fastest at 0.45)")
    ap.add_argument("--csv", default="dense_cost.csv")
    a = ap.parse_args()
    rows = []
    base = None
    for h in [0.0] + a.haematocrits:
        s, cells = scene(a.diameter, a.length, h, skin=a.skin)
        s.integrator.run(10)  # first forces, settings check
        s.integrator.reset_timings()
        t0 = time.perf_counter()
        s.integrator.run(a.steps)
        wall = time.perf_counter() - t0
        t = s.integrator.timings()
        if h == 0.0:
            base = wall
        n = len(cells)
        row = {"diameter": a.diameter, "haematocrit": round(cells.report["haematocrit"], 4) if n else 0.0,
               "cells": n, "steps": a.steps, "wall_s": round(wall, 3),
               "s_per_cell_per_1000_steps": round((wall - base) / n * 1000 / a.steps, 5) if n else float("nan"),
               "membrane_s": round(t["membrane"], 3), "non_bonded_s": round(t["non_bonded"], 3),
               "constraints_s": round(t["constraints"], 3), "coupling_s": round(t["coupling"], 3),
               "lb_fluid_s": round(t["lb_fluid"], 3), "other_s": round(t["other"], 3),
               "machine": platform.processor() or platform.machine()}
        if n:
            vol = max(abs(c.volume() / c.cell_type.volume0 - 1) for c in cells)
            row["volume_drift_max"] = round(vol, 5)
        print(row, flush=True)
        rows.append(row)
    dense = [r for r in rows if r["cells"]]
    if len(dense) >= 2:
        print(f"dense / dilute cost per cell: {dense[-1]['s_per_cell_per_1000_steps'] / dense[0]['s_per_cell_per_1000_steps']:.2f}")
    write_rows(a.csv, [dict(r, **{k: r.get(k, float('nan')) for k in ('volume_drift_max',)}) for r in rows])


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
