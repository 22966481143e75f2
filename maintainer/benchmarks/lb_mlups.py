#!/usr/bin/env pyoif
"""Lattice-Boltzmann kernel speed: MLUPS (million fluid-node updates per
second) for periodic boxes of 32^3, 64^3, 128^3, 192^3 nodes, a walled
channel and a 40 %-solid channel, with 1 and 2 threads, and the same figure
as a fraction of a memory-bandwidth roofline measured on the spot.

    pyoif maintainer/benchmarks/lb_mlups.py [--threads 1 2] [--sizes 32 64 128 192]
        [--precision double single] [--repeats 10] [--periodic-only] [--seconds 2]
        [--csv lb_mlups.csv] [--watch-cost]

The fluid's speed watch is off here (the kernel alone against the roofline);
--watch-cost times instead its pass (LBFluid(speed_watch_every=...), default
one per 100 updates) against an update.

Precision: the populations stored as double or as float
(LBFluid(single_precision=True)). Both fluids of a scene are built first
and timed interleaved (double, single, double, single, ... --repeats
rounds, the best of each kept), so that a machine shared with other jobs
slows both alike; the ratio single / double is printed per scene. Under
load, short timings and many rounds (--seconds 0.6 --repeats 12) give the
steadiest ratio.

Roofline: STREAM-like copy bandwidth B (b[i] = a[i] over 2 x 256 MiB,
counted as STREAM does, 16 bytes per element) divided by the bytes the
kernel must move per node and update: 19 populations read + 19 written,
2 * 19 * 8 = 304 bytes in double precision. The kernel moves exactly these:
one lattice updated in place (AA pattern), each node's 19 populations read
once and written back to the same cache lines, so there is no
write-allocate traffic either (no density/velocity fields); the halo
exchange and the bounce-back fix-up add surface terms, and with particle
coupling the force field adds 24 bytes read + 24 written (not in these
scenes). In single precision the populations take 4 bytes: 152 bytes per
node, twice the roofline in MLUPS. The copy counts 16 bytes per element as STREAM does; a copy whose
stores allocate lines moves 24, which is why a kernel that does not can
exceed 100 % of this roofline.
"""
import argparse
import subprocess
import time

import numpy as np

import lbmd
from lbmd import _lbmd, lb, lbboundaries, shapes

from benchmark_csv import write_rows

BYTES_PER_VALUE = {"double": 8, "single": 4}


def bytes_per_node(precision):
    return 2 * 19 * BYTES_PER_VALUE[precision]


def make_fluid(shape, threads, walls=None, precision="double", speed_watch_every=0):
    system = lbmd.System(box_l=list(shape))
    system.time_step = 0.1
    fluid = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, n_threads=threads,
                       ext_force_density=[1e-5, 0, 0], single_precision=precision == "single",
                       speed_watch_every=speed_watch_every)
    system.actors.add(fluid)
    if walls == "z":  # the paper's kind of channel (cell_cost.py's scene), fits in the L3 cache
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, 1], dist=1.0)))
        system.lbboundaries.add(lbboundaries.LBBoundary(
            shape=shapes.Wall(normal=[0, 0, -1], dist=-(shape[2] - 1.0))))
    elif walls is not None:
        lo, hi = walls
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 1, 0], dist=lo)))
        system.lbboundaries.add(lbboundaries.LBBoundary(
            shape=shapes.Wall(normal=[0, -1, 0], dist=-(shape[1] - hi))))
    system.prepare()  # the boundaries flagged (the lattice updates below do not flag)
    return system, fluid


def calibrate(fluid, seconds):
    """Updates per timing (about seconds / 3), and the first timing."""
    core = fluid._core
    core.step(2)  # warm-up: page faults, caches
    steps = 1
    while True:
        t0 = time.perf_counter()
        core.step(steps)
        dt = time.perf_counter() - t0
        if dt > seconds / 3 or steps > 10000:
            return steps, dt / steps
        steps *= 2


def timed(fluid, steps):
    t0 = time.perf_counter()
    fluid._core.step(steps)
    return (time.perf_counter() - t0) / steps


def interleaved(fluids, seconds, repeats):
    """Best seconds per update of each fluid, timed in turns (one timing of
    each per round, repeats rounds)."""
    plan = {p: calibrate(f, seconds) for p, f in fluids.items()}
    best = {p: first for p, (_, first) in plan.items()}
    for _ in range(repeats):
        for p, f in fluids.items():
            best[p] = min(best[p], timed(f, plan[p][0]))
    return best


def watch_cost(scenes, threads, args):
    """The speed watch's pass (LBFluid(speed_watch_every=...)): each scene
    timed with a pass after every update and with none, interleaved; its
    cost as a share of an update, and at the default of one pass per 100."""
    rows = []
    print(f"{'scene':<34} {'precision':>9} {'ms/update':>10} {'+pass ms':>9} {'pass/update':>12} "
          f"{'cost at 1/100':>13}")
    for name, shape, walls in scenes:
        for p in args.precision:
            built = {every: make_fluid(shape, threads, walls, p, every) for every in (0, 1)}
            best = interleaved({every: fluid for every, (_, fluid) in built.items()}, args.seconds,
                               args.repeats)
            share = (best[1] - best[0]) / best[0]
            print(f"{name:<34} {p:>9} {best[0] * 1e3:>10.2f} {(best[1] - best[0]) * 1e3:>9.2f} {share:>12.2f} "
                  f"{share / 100:>12.2%}")
            rows.append(dict(threads=threads, scene=name, precision=p, ms_per_update=best[0] * 1e3,
                             ms_per_watch_pass=(best[1] - best[0]) * 1e3, pass_per_update=share,
                             cost_every_100=share / 100))
            for system, _ in built.values():
                system.actors.clear()
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128, 192])
    ap.add_argument("--precision", nargs="+", choices=("double", "single"),
                    default=["double", "single"])
    ap.add_argument("--repeats", type=int, default=10, help="interleaved timing rounds")
    ap.add_argument("--periodic-only", action="store_true", help="skip the walled channels")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--csv", default="lb_mlups.csv")
    ap.add_argument("--watch-cost", action="store_true",
                    help="instead: the fluid's speed watch, a pass every update against none, per scene")
    args = ap.parse_args()
    try:
        print(subprocess.run(["lscpu"], capture_output=True, text=True).stdout.split("\n")[7])
    except (OSError, IndexError):
        pass
    rows = []
    for threads in args.threads:
        bw = _lbmd.copy_bandwidth(1 << 25, 10, threads)
        roof = {p: bw / bytes_per_node(p) / 1e6 for p in args.precision}
        print(f"\n{threads} thread(s): copy bandwidth {bw / 1e9:.2f} GB/s -> roofline "
              + ", ".join(f"{roof[p]:.1f} MLUPS in {p} ({bytes_per_node(p)} bytes/node)"
                          for p in args.precision))
        scenes = [(f"periodic {n}^3", (n, n, n), None) for n in args.sizes]
        if not args.periodic_only:
            scenes.append(("channel 256x64x64, 2 walls", (256, 64, 64), (1.0, 1.0)))
            scenes.append(("channel 100x40x20, walls normal to z", (100, 40, 20), "z"))
            scenes.append(("channel 128^3, 40 % solid", (128, 128, 128), (26.0, 25.0)))
        if args.watch_cost:
            rows += watch_cost(scenes, threads, args)
            continue
        print(f"{'scene':<34} {'precision':>9} {'fluid nodes':>12} {'ms/update':>10} {'MLUPS':>8} "
              f"{'roofline':>9}")
        for name, shape, walls in scenes:
            built = {p: make_fluid(shape, threads, walls, p) for p in args.precision}
            fluids = {p: fluid for p, (_, fluid) in built.items()}
            best = interleaved(fluids, args.seconds, args.repeats)
            total = int(np.prod(shape))
            speed = {}
            for p in args.precision:
                n_fluid = fluids[p]._core.n_fluid_nodes
                sec = best[p]
                m = speed[p] = n_fluid / sec / 1e6
                extra = f" ({100 * (1 - n_fluid / total):.0f} % solid, {sec / total * 1e9:.2f} ns per box node)" \
                    if walls else f" ({sec / total * 1e9:.2f} ns per box node)"
                print(f"{name:<34} {p:>9} {n_fluid:>12d} {sec * 1e3:>10.2f} {m:>8.1f} {m / roof[p]:>8.0%}"
                      f"{extra}")
                rows.append(dict(threads=threads, scene=name, precision=p, fluid_nodes=n_fluid,
                                 ms_per_update=sec * 1e3, mlups=m, copy_GBs=bw / 1e9,
                                 roofline_mlups=roof[p], fraction=m / roof[p]))
            if "double" in speed and "single" in speed:
                print(f"{'':<34} single / double = {speed['single'] / speed['double']:.2f}x")
            for system, _ in built.values():
                system.actors.clear()
            del fluids, built
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
