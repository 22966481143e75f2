#!/usr/bin/env pyoif
"""Cost of OIF cells: the extra seconds per 1000 MD steps that one 374-node
RBC adds to a fluid run (membrane forces + LB coupling + contacts), for
0 / 5 / 20 / 60 cells on one core, and the time to create one cell.

    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/cell_cost.py [--cells 0 5 20 60] [--chunk 10 --rounds 60]
        [--csv cell_cost.csv] [--no-fluid] [--chunk 0 --steps 200 --repeats 5]
    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/cell_cost.py --checks-cost [--cells 60]

--checks-cost: what the run's named-failure checks cost (system.cell_checks:
inverted triangles, volumes, drift, membrane crossings; doc/engine.md): the
scene with the largest --cells count twice, checks on and off, in turns.

Scene (as the ESPResSo 4.2.2 timing in doc/model.md): channel
100 x 40 x 20 (agrid 1, tau = time step = 0.1, visc 1.5, dens 1) between two
walls, RBCs rbc374 scaled by 4 with ks 0.005, kb 0.02, kal 0.007, kag 0.7,
kv 0.9, coupling gamma 1.5, node-wall soft sphere and cell-cell membrane
collision (normals on), cells seeded at random without overlaps.
Paper (PyOIF on ESPResSo, Threadripper, 1 core): 1.5-3.2 s extra per cell
per 1000 steps; ESPResSo 4.2.2 on this machine kind: 0.77-1.59 ms per step
per cell (5-20 cells). Target: <= 0.1 s per cell per 1000 steps.

By default the configurations run in turn in short runs of 10 steps, 60
rounds, and the quietest quarter of each one's runs is averaged (wall clock;
steady on a shared machine whose speed drifts within seconds). --chunk 0
takes instead the best CPU time of --repeats runs of --steps steps.
The time of the fluid alone is the gauge of how loaded the machine was: the
extra time per cell grows with it (other jobs compete for the shared cache
that the coupling's reads of the fluid wait on), so the benchmark also
prints the cost per cell as a share of the fluid-alone time.

The same scene without fluid (--no-fluid: Langevin thermostat instead of
LB) isolates the membrane and contact cost. Where the extra time goes is
printed per phase of the step (integrator.timings(): membrane = the
cells' moduli, coupling = fluid coupling, lb_fluid = the lattice update, ...;
wall clock of the same best run, so a busy machine shows in them). For a
profile by function, run under perf, e.g.
    perf record -g -o cell_cost.perf -- build/pyoif maintainer/benchmarks/cell_cost.py --cells 20 --steps 500
    perf report -i cell_cost.perf --no-children --percent-limit 2
"""
import argparse
import os
import time

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

from benchmark_csv import write_rows

BOX = (100.0, 40.0, 20.0)
MODULI = dict(ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)


def build(n_cells, fluid, seed=1):
    system = lbmd.System(box_l=BOX)
    system.time_step = 0.1
    system.cell_system.skin = 0.3
    walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(BOX[2] - 1.0))]
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(4.0, 4.0, 4.0), normal=True,
                          **MODULI)
    if n_cells:
        oif.seed_cells(system, rbc, counts=n_cells, boundaries=walls, seed=seed, particle_types=0)
    for w in walls:
        system.constraints.add(shape=w, particle_type=10, penetrable=False)
    system.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.0001, n=1.2, cutoff=0.5, offset=0.0)
    system.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.0001, n=1.2, cutoff=0.5, offset=0.0)
    if fluid:
        lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[1e-4, 0, 0], n_threads=1)
        system.actors.add(lbf)
        for w in walls:
            system.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
        system.thermostat.set_lb(LB_fluid=lbf, gamma=1.5)
    else:
        system.thermostat.set_langevin(kT=0.0, gamma=0.1)
    return system, rbc


PHASES = lbmd.system.Integrator.PHASES
TARGET = 0.1  # s per cell per 1000 steps (issue 4)


def time_runs(systems, steps, repeats):
    """Per system (CPU seconds, wall seconds, phases) per 1000 steps, best of
    `repeats`; phases: the wall seconds per 1000 steps of each part of the
    step (integrator.timings()) in the run with the least CPU time. The
    systems take turns (one timed run each per round), so a slow spell of a
    shared machine hits every configuration alike instead of one of them.
    CPU time of this process is the paper's measure (its Table 1) and, on
    one thread, does not count time the process waited for a core."""
    for system in systems:
        system.integrator.run(20)  # warm up: neighbour lists, caches
    best_cpu = [np.inf] * len(systems)
    best_wall = [np.inf] * len(systems)
    phases = [None] * len(systems)
    for _ in range(repeats):
        for k, system in enumerate(systems):
            system.integrator.reset_timings()
            c, t = time.process_time(), time.perf_counter()
            system.integrator.run(steps)
            cpu, wall = time.process_time() - c, time.perf_counter() - t
            if cpu < best_cpu[k]:
                best_cpu[k] = cpu
                timings = system.integrator.timings()
                phases[k] = {key: timings[key] * 1000.0 / steps for key in PHASES}
            best_wall[k] = min(best_wall[k], wall)
    return [(cpu * 1000.0 / steps, wall * 1000.0 / steps, ph)
            for cpu, wall, ph in zip(best_cpu, best_wall, phases)]


def time_chunks(systems, chunk, rounds):
    """Per system (wall seconds, wall seconds, phases) per 1000 steps from
    many short runs: `rounds` times, each system runs 2 steps (its caches
    refilled after the others' runs) and then `chunk` timed steps; of each
    system's runs the quietest quarter (least total time) is averaged,
    phase by phase (integrator.timings()). On a shared machine whose speed
    drifts within seconds this is steadier than the best of a few long
    runs; wall time, as the phase timings are."""
    for system in systems:
        system.integrator.run(20)
    records = [[] for _ in systems]
    for _ in range(rounds):
        for k, system in enumerate(systems):
            system.integrator.run(2)
            system.integrator.reset_timings()
            system.integrator.run(chunk)
            records[k].append(system.integrator.timings())
    results = []
    for runs in records:
        quiet = sorted(runs, key=lambda t: t["total"])[: max(3, len(runs) // 4)]
        phases = {key: 1000.0 * float(np.mean([t[key] for t in quiet])) / chunk for key in PHASES}
        total = 1000.0 * float(np.mean([t["total"] for t in quiet])) / chunk
        results.append((total, total, phases))
    return results


def creation_time(repeats=20):
    system = lbmd.System(box_l=[400.0, 400.0, 400.0])
    system.time_step = 0.1
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(4.0, 4.0, 4.0), normal=True,
                          **MODULI)
    oif.OifCell(cell_type=rbc, particle_type=0, origin=[5.0, 5.0, 5.0])  # first: imports, caches
    times = []
    for i in range(repeats):
        t = time.perf_counter()
        oif.OifCell(cell_type=rbc, particle_type=0, origin=[20.0 + 12 * (i % 30), 20.0 + 12 * (i // 30), 20.0])
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def checks_cost(args):
    """Seconds per 1000 steps with the cells' checks on and off (the same
    scene twice, in turns) and the checks' share of a step."""
    n = max(args.cells)
    systems = [build(n, fluid=not args.no_fluid)[0] for _ in range(2)]
    systems[1].cell_checks = False
    on, off = (r[0] for r in (time_chunks(systems, args.chunk, args.rounds) if args.chunk
                              else time_runs(systems, args.steps, args.repeats)))
    share = 100.0 * (on - off) / off
    print(f"{n} cells{'' if args.no_fluid else ' in fluid'}: checks on {on:.3f} s, off {off:.3f} s "
          f"per 1000 steps: the checks cost {share:+.2f} % of a step (target < 2 %)")
    write_rows(args.csv, [{"cells": n, "fluid": not args.no_fluid, "checks_on_s_per_1000_steps": on,
                           "checks_off_s_per_1000_steps": off, "checks_share_percent": share}])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200, help="with --chunk 0: MD steps per timed run")
    ap.add_argument("--repeats", type=int, default=5,
                    help="with --chunk 0: timed runs per configuration, taken in turns (best counts)")
    ap.add_argument("--cells", type=int, nargs="+", default=[0, 5, 20, 60])
    ap.add_argument("--no-fluid", action="store_true", help="Langevin instead of LB (membrane cost alone)")
    ap.add_argument("--chunk", type=int, default=10,
                    help="runs of CHUNK steps, the configurations in turn for --rounds rounds, the quietest "
                         "quarter averaged (wall clock; steady on a busy shared machine); 0: the best CPU "
                         "time of --repeats runs of --steps steps instead")
    ap.add_argument("--rounds", type=int, default=60, help="rounds of --chunk runs")
    ap.add_argument("--csv", default="cell_cost.csv")
    ap.add_argument("--checks-cost", action="store_true",
                    help="the cost of system.cell_checks in the scene with the most cells")
    args = ap.parse_args()
    if args.chunk and (args.steps != ap.get_default("steps") or args.repeats != ap.get_default("repeats")):
        ap.error("--steps and --repeats belong to --chunk 0 (the best of long runs); with --chunk "
                 f"{args.chunk} the runs are set by --chunk and --rounds")
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("note: set OMP_NUM_THREADS=1 for the one-core figure")
    if args.checks_cost:
        checks_cost(args)
        return
    t_create = creation_time()
    print(f"creating one 374-node cell with all bonds and exclusions: {1e3 * t_create:.2f} ms (median)")
    unit = "wall s" if args.chunk else "CPU s"
    print(f"load average before the runs: {os.getloadavg()[0]:.1f} ("
          + ("wall seconds of the quietest quarter of short runs are the figure)" if args.chunk else
             "CPU seconds are the figure; wall seconds grow with the load)"))
    rows = []
    per_cell = {}  # cells -> extra s per cell per 1000 steps
    base = base_phases = None
    systems = [build(n, fluid=not args.no_fluid)[0] for n in args.cells]
    results = (time_chunks(systems, args.chunk, args.rounds) if args.chunk
               else time_runs(systems, args.steps, args.repeats))
    for n, (s1000, wall1000, phases) in zip(args.cells, results):
        if n == 0:
            base, base_phases = s1000, phases
        extra = (s1000 - base) / n if (n and base is not None) else float("nan")
        if n and base is not None:
            per_cell[n] = extra
        row = {"cells": n, "fluid": not args.no_fluid, "measure": unit, "s_per_1000_steps": s1000,
               "extra_s_per_cell_per_1000_steps": extra, "wall_s_per_1000_steps": wall1000}
        row.update({f"{key}_s_per_1000_steps": phases[key] for key in PHASES})
        rows.append(row)
        share = f", {100.0 * extra / base:.1f} % of the fluid alone" if (n and base and not args.no_fluid) else ""
        print(f"{n:3d} cells: {s1000:8.3f} {unit} / 1000 steps (wall {wall1000:.3f} s)"
              + (f", extra per cell {extra:.4f} {unit} / 1000 steps ({extra:.4f} ms per step){share}" if n else
                 " (the gauge of the machine's load: the less, the quieter)" if not args.no_fluid else ""))
        if n and base_phases is not None:  # where the extra time goes (wall clock, same run)
            print("           per cell by phase (wall s / 1000 steps): " + ", ".join(
                f"{key} {(phases[key] - base_phases[key]) / n:.4f}" for key in PHASES))
    # T(N) - T(0) = fixed + N * marginal over the cell counts measured: the
    # marginal cost is what one more cell adds; the fixed part is paid once
    # for having cells at all (see doc/performance.md: after the lattice
    # sweep the core runs the first milliseconds of cell work slower)
    counts = [n for n in args.cells if n > 0]
    if base is not None and len(set(counts)) >= 2:
        extra_total = [s1000 - base for n, (s1000, _, _) in zip(args.cells, results) if n > 0]
        marginal, fixed = np.polyfit(counts, extra_total, 1)
        print(f"fit over {'/'.join(map(str, counts))} cells: {marginal:.4f} {unit} / 1000 steps per cell "
              f"(what one more cell adds) + {fixed:.4f} {unit} / 1000 steps for having cells at all")
        rows.append({"cells": "fit_marginal_per_cell", "fluid": not args.no_fluid, "measure": unit,
                     "s_per_1000_steps": "", "extra_s_per_cell_per_1000_steps": marginal,
                     "wall_s_per_1000_steps": ""})
        rows.append({"cells": "fit_fixed", "fluid": not args.no_fluid, "measure": unit + " (extra, all cells)",
                     "s_per_1000_steps": fixed, "extra_s_per_cell_per_1000_steps": "",
                     "wall_s_per_1000_steps": ""})
    if per_cell and not args.no_fluid:
        met = [n for n, x in per_cell.items() if x <= TARGET]
        missed = [n for n, x in per_cell.items() if x > TARGET]
        print(f"target (<= {TARGET} s per cell per 1000 steps): "
              + (f"met at {'/'.join(map(str, met))} cells" if met else "not met")
              + (f"; above it at {'/'.join(map(str, missed))} cells" if met and missed else "")
              + f" (fluid alone {base:.2f} s per 1000 steps in this run: the less, the quieter the machine)")
    rows.append({"cells": "create_one_cell_s", "fluid": "", "measure": "wall s", "s_per_1000_steps": t_create,
                 "extra_s_per_cell_per_1000_steps": "", "wall_s_per_1000_steps": ""})
    write_rows(args.csv, rows)


if __name__ == "__main__":
    main()
