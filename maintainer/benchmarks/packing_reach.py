"""Where oif.pack_cells reaches a haematocrit of 0.45: rbc374 red cells
(radius 3.91 um, the PyOIF paper's moduli) in a periodic box, tubes of
D 10, 20, 40 and 50 um, a channel between two walls and the shipped
constriction (samples/data/constriction.svg extruded 12 um high); per
geometry and seed the cells, the haematocrit, the method (rigid alone, or
rigid then the deformable stage), the time, the worst volume and surface
deviation from the reference and the exact checks (nodes inside other
cells, closest nodes of two cells, closest node to a wall). Writes CSV.

    pyoif maintainer/benchmarks/packing_reach.py [--geometries box,tube10,...] [--seeds 1]
          [--haematocrit 0.45] [--csv packing_reach.csv]

The flagship's bifurcation is packed by the sample itself:
    pyoif samples/cell_flow_in_bifurcation.py --haematocrit 0.45 --cycles 0 --force 1e-4 --no-plots
prints the same figures.
"""
import argparse
import math
import os
import platform
import time

import numpy as np

import lbmd
import oif
from lbmd import shapes
from lbmd.shapes import Extrusion

from benchmark_csv import write_rows

RBC_MODULI = dict(ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)
HERE = os.path.dirname(os.path.abspath(__file__))
CONSTRICTION = os.path.join(HERE, "..", "..", "samples", "data", "constriction.svg")


def tube(diameter, length_ratio):
    """A tube along x through a box periodic along it (as the Fahraeus
    sample builds it): (system, boundaries, region)."""
    length, width = length_ratio * diameter, math.ceil(diameter) + 2.0
    s = lbmd.System(box_l=[length, width, width])
    t = shapes.Cylinder(center=[length / 2, width / 2, width / 2], axis=[1, 0, 0], radius=diameter / 2,
                        length=3 * length, direction=-1, open=True)
    return s, [t], None


def geometry(name):
    if name == "box":  # about 100 cells
        return lbmd.System(box_l=[27.0, 27.0, 27.0]), [], None
    if name.startswith("tube"):
        diameter = float(name[4:])
        return tube(diameter, {10.0: 4.4, 20.0: 4.0, 40.0: 2.0, 50.0: 1.6}.get(diameter, 2.0))
    if name == "channel":  # 18 um between two walls, periodic in the plane
        s = lbmd.System(box_l=[36.0, 36.0, 20.0], periodicity=[True, True, False])
        return s, [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-19.0)], None
    if name == "constriction":  # as samples/device_from_mask.py builds it (1.5 um per unit, 12 um high)
        device = Extrusion.from_svg(CONSTRICTION, scale=1.5, tolerance=0.05 / 1.5, origin=(0.0, 1.0),
                                    z=[1.0, 13.0], direction=-1)
        v = np.concatenate([np.asarray(p) for p in device.polygons])
        box = [float(math.ceil(v[:, 0].max() - 1e-9)), float(math.ceil(v[:, 1].max() + 1.0 - 1e-9)), 14.0]
        return lbmd.System(box_l=box, periodicity=[False, False, False]), [device], None
    raise SystemExit(f"packing_reach: unknown geometry {name!r}")


def one(name, haematocrit, seed):
    s, boundaries, region = geometry(name)
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.91,) * 3, normal=True, **RBC_MODULI)
    t0 = time.perf_counter()
    try:
        cells = oif.pack_cells(s, ct, haematocrit=haematocrit, boundaries=boundaries, region=region, seed=seed)
    except oif.PackingError as err:
        return {"geometry": name, "seed": seed, "cells": 0, "haematocrit": float("nan"), "method": "failed",
                "error": str(err)[:200], "total_s": round(time.perf_counter() - t0, 2)}
    total = time.perf_counter() - t0
    r = cells.report
    dv = max(abs(c.volume() / ct.volume0 - 1.0) for c in cells)
    da = max(abs(c.surface() / ct.surface0 - 1.0) for c in cells)
    return {"geometry": name, "seed": seed, "cells": len(cells), "haematocrit": round(r["haematocrit"], 4),
            "method": r["method"], "rigid_scale": round(r.get("rigid_scale", 1.0), 3),
            "rigid_iterations": r["iterations"], "swell_steps": r.get("swell_steps", 0),
            "swell_s": round(r.get("swell_seconds", 0.0), 2), "total_s": round(total, 2),
            "worst_volume_dev": round(dv, 5), "worst_surface_dev": round(da, 5),
            "nodes_inside_cells": r["nodes_inside_cells"], "min_node_distance": round(r["min_node_distance"], 4),
            "contact_offset": oif.contacts.contact_offset(ct),
            "min_wall_distance": round(min(r["min_wall_distance"], 99.0), 4), "error": "",
            "machine": platform.processor() or platform.machine()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--geometries", default="box,tube10,tube20,tube40,tube50,channel,constriction")
    ap.add_argument("--haematocrit", type=float, default=0.45)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--csv", default="packing_reach.csv")
    a = ap.parse_args()
    rows = []
    for name in a.geometries.split(","):
        for seed in range(1, a.seeds + 1):
            row = one(name.strip(), a.haematocrit, seed)
            print(row, flush=True)
            rows.append(row)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    write_rows(a.csv, [{k: r.get(k, "") for k in keys} for r in rows])


if __name__ == "__main__":
    main()
