"""Packing speed: oif.pack_cells with rbc374 red cells (radius 3.91 um) at a
haematocrit in a cubic periodic box, on one core; prints the time of the
packing (level sets, growth, the exact check) and of creating the cells,
the iterations and the checks, and writes CSV.

    pyoif maintainer/benchmarks/packing.py [--cells 1000] [--haematocrit 0.45] [--seeds 1] [--csv packing.csv]

The issue's target: 1000 cells at 0.45 in under 60 s on one core.
"""
import argparse
import os
import platform
import time

import lbmd
import oif

from benchmark_csv import write_rows


def one(n_cells, haematocrit, seed):
    s = lbmd.System(box_l=[10.0, 10.0, 10.0])
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.91,) * 3, ks=0.005, kb=0.02,
                         kal=0.007, kag=0.7, kv=0.9, normal=True)
    ct_volume = ct.volume0
    side = (n_cells * ct_volume / haematocrit) ** (1.0 / 3.0)
    s = lbmd.System(box_l=[side] * 3)
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.91,) * 3, ks=0.005, kb=0.02,
                         kal=0.007, kag=0.7, kv=0.9, normal=True)
    t0 = time.perf_counter()
    cells = oif.pack_cells(s, ct, counts=n_cells, seed=seed)
    total = time.perf_counter() - t0
    r = cells.report
    return {"cells": len(cells), "haematocrit": round(r["haematocrit"], 4), "seed": seed,
            "box": round(side, 3), "clearance": r["clearance"], "iterations": r["iterations"],
            "pack_s": round(r["pack_seconds"], 2), "create_s": round(total - r["pack_seconds"], 2),
            "total_s": round(total, 2), "nodes_inside_cells": r["nodes_inside_cells"],
            "min_node_distance": round(r["min_node_distance"], 4), "machine": platform.processor() or platform.machine()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=1000)
    ap.add_argument("--haematocrit", type=float, default=0.45)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--csv", default="packing.csv")
    a = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    rows = []
    for seed in range(1, a.seeds + 1):
        row = one(a.cells, a.haematocrit, seed)
        print(row, flush=True)
        rows.append(row)
    write_rows(a.csv, rows)


if __name__ == "__main__":
    main()
