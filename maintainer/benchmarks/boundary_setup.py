#!/usr/bin/env pyoif
"""Set-up time of lattice-Boltzmann boundaries: a zig-zag channel of
560 x 410 x 48 lattice nodes (agrid 1, 11.0 M nodes) built from 12 shapes
added one by one with system.lbboundaries.add, as user scripts assemble
channels:

  * 2 side walls, Rhomboids 560 x 10 x 48 along y = 0 and y = 400;
  * 5 baffles, slanted Rhomboids 12 nodes thick, leaning 60 nodes in x over
    their 300 nodes in y, alternately from the lower and the upper wall at
    x = 50, 150, ..., 450: the fluid zig-zags around them;
  * 5 Cylinders of radius 10 along z rounding the baffles' free ends.

z is periodic (a quasi-2D serpentine channel, 48 nodes deep).

    pyoif maintainer/benchmarks/boundary_setup.py [--modes lazy,eager,union]
        [--single-precision] [--csv boundary_setup.csv]

Times, per mode, from the first add to the flags being ready
(system.prepare(), the explicit collective step, included): lazy = the 12
adds, then system.prepare() (the fluid flags once); eager = system.prepare()
after each add (as every add flagged before lazy flagging); union = the
12 shapes as one Union in one add. The fluid is created beforehand (not
timed; its allocation time is printed). Wall and CPU seconds are printed
(CPU: of this process, all threads). With an engine from before lazy
flagging (no n_flaggings), every add flags: only 'lazy' is run and its
figure is that old path. Serial (one rank), OMP_NUM_THREADS as set.
"""
import argparse
import os
import sys
import time

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes as shapes

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from benchmark_csv import write_rows  # noqa: E402

BOX = (560.0, 410.0, 48.0)


def zigzag_shapes():
    lx, ly, lz = BOX
    out = [shapes.Rhomboid(corner=[0.0, 0.0, 0.0], a=[lx, 0.0, 0.0], b=[0.0, 10.0, 0.0], c=[0.0, 0.0, lz]),
           shapes.Rhomboid(corner=[0.0, ly - 10.0, 0.0], a=[lx, 0.0, 0.0], b=[0.0, 10.0, 0.0],
                           c=[0.0, 0.0, lz])]
    baffles, tips = [], []
    for i in range(5):
        x0 = 50.0 + 100.0 * i
        if i % 2 == 0:  # from the lower wall, leaning +x
            y0, dy, dx = 10.0, 300.0, 60.0
        else:  # from the upper wall, leaning +x going down
            y0, dy, dx = ly - 10.0, -300.0, 60.0
        baffles.append(shapes.Rhomboid(corner=[x0, y0, 0.0], a=[12.0, 0.0, 0.0], b=[dx, dy, 0.0],
                                       c=[0.0, 0.0, lz]))
        tips.append(shapes.Cylinder(center=[x0 + dx + 6.0, y0 + dy, 0.5 * lz], axis=[0, 0, 1],
                                    radius=10.0, length=lz + 2.0))
    return out + baffles + tips


def make_system(single):
    s = lbmd.System(box_l=list(BOX))
    s.time_step = 1.0
    t0 = time.perf_counter()
    lbf = s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0 / 6.0, tau=1.0,
                                       single_precision=single))
    return s, lbf, time.perf_counter() - t0


def run(mode, single):
    s, lbf, t_alloc = make_system(single)
    core = lbf._core
    lazy_engine = hasattr(core, "n_flaggings")
    before = core.n_flaggings if lazy_engine else 0
    shape_list = zigzag_shapes()
    t0, c0 = time.perf_counter(), time.process_time()
    if mode == "union":
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=shapes.Union(shapes=shape_list)))
    else:
        for sh in shape_list:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=sh))
            if mode == "eager":
                s.prepare()
    t_add = time.perf_counter() - t0
    s.prepare()
    n_fluid = core.n_fluid_nodes  # flags ready
    t_total = time.perf_counter() - t0
    cpu_total = time.process_time() - c0
    flaggings = core.n_flaggings - before if lazy_engine else len(shape_list)
    return dict(mode=mode if lazy_engine else "old_every_add", nodes=int(BOX[0] * BOX[1] * BOX[2]),
                shapes=len(shape_list), fluid_nodes=int(n_fluid), links=int(core.n_links),
                flaggings=flaggings, adds_s=round(t_add, 3), ready_s=round(t_total, 3),
                ready_cpu_s=round(cpu_total, 3),
                alloc_s=round(t_alloc, 3), single_precision=single,
                threads=os.environ.get("OMP_NUM_THREADS", "unset"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", default="lazy,eager,union")
    ap.add_argument("--single-precision", action="store_true")
    ap.add_argument("--csv", default="boundary_setup.csv")
    args = ap.parse_args()
    if lbmd.size != 1:
        sys.exit("boundary_setup.py: run it on one rank")
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    for m in modes:
        if m not in ("lazy", "eager", "union"):
            sys.exit(f"boundary_setup.py: --modes: unknown mode {m!r} (lazy, eager, union)")
    rows = []
    for m in modes:
        row = run(m, args.single_precision)
        rows.append(row)
        print(f"{row['mode']:>14}: {row['shapes']} shapes on {row['nodes'] / 1e6:.1f} M nodes, "
              f"{row['flaggings']} flagging(s): adds {row['adds_s']:.2f} s, flags ready after "
              f"{row['ready_s']:.2f} s, CPU {row['ready_cpu_s']:.2f} s ({row['fluid_nodes']} fluid nodes, {row['links']} links; "
              f"fluid allocated in {row['alloc_s']:.2f} s)", flush=True)
        if row["mode"] == "old_every_add":
            break
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
