#!/usr/bin/env pyoif
"""Compound cells through a constriction: a cell with a nucleus (default),
a cell filled with inner particles, or a cluster of two cells held by
adhesion (doc/compound-cells.md).

    pyoif samples/compound_cells.py [--case nucleus|inner|cluster] [--duration MS] [--output DIR]
          [--speed MM_S] [--no-plots] [--no-vtk]

The device: samples/data/constriction.svg (a channel 20 um wide whose walls
bulge in to a throat 6 um wide between x = 22 and 38 um), 10 um high,
periodic along the flow (x, 60 um) and driven by a body force scaled until
the mean speed in the channel is the one asked. The cells start upstream of
the throat and are followed until they have passed it (x beyond 45 um).

- nucleus: a cell of radius 4 um (sphere642, the red cell's membrane
  moduli x 3) with a nucleus of radius 2.2 um (sphere162, also x 3: x 12
  blew up at this time step), kept inside by the contact (oif.add_nucleus);
- inner: the same cell with 40 inner particles (OifCell(inner_particles=));
- cluster: two such cells (without nucleus) held by the Morse adhesion of
  oif.BiCluster, one behind the other along the flow.

Every number from SI inputs through oif.scene_parameters (the narrowest
channel is the 6 um throat). Each output row (cells.csv) has the time, the
centre of each cell, the largest local area strain, the volume over its
start, and: for the nucleus, how many of its nodes lie outside the cell
(the winding number; 0 throughout: the contact held) and its closest gap to
the membrane; for inner particles, how many are outside; for the cluster,
the distance between the two centres. Pictures of the scene at the start
and the end (scene_start.png, scene_end.png); ParaView files by default
(--no-vtk: none).
"""
import argparse
import csv
import math
import os

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries
from lbmd.shapes import Extrusion
from oif.compound import _inside, _nearest_distance
from lbmd.units import oif_moduli_from_si
from oif.scene_plan import RBC_MEMBRANE, RBC_MEMBRANE_VISCOSITY

HERE = os.path.dirname(os.path.abspath(__file__))
LAYOUT = os.path.join(HERE, "data", "constriction.svg")
HEIGHT = 10e-6          # m, channel height
THROAT = 6e-6           # m, the narrowest width
PASSED_X = 45.0         # um: beyond the throat (x 22..38)
HOST_RADIUS, NUCLEUS_RADIUS = 4e-6, 2.2e-6
#: a nucleated cell is stiffer than a red cell (a leukocyte's cortex): the
#: red cell's moduli times these; a nucleus 12x (stiffer than its cell) blew
#: up at the plan's time step and speed-up (doc/compound-cells.md)
HOST_STIFFNESS, NUCLEUS_STIFFNESS = 3.0, 3.0

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--case", choices=("nucleus", "inner", "cluster"), default="nucleus")
ap.add_argument("--speed", type=float, default=1.0, help="real mean speed in the channel, mm/s (default 1)")
ap.add_argument("--duration", type=float, default=None,
                help="simulated flow in ms (default: until the cells have passed the throat, at most 5 ms)")
ap.add_argument("--output", default="output_compound", help="output folder")
ap.add_argument("--no-plots", action="store_true", help="no pictures")
ap.add_argument("--no-vtk", action="store_true", help="no ParaView files")
args = ap.parse_args()
for name in ("speed", "duration"):
    value = getattr(args, name)
    if value is not None and not (math.isfinite(value) and value > 0):
        ap.error(f"--{name} must be a positive number, got {value}")
rank0 = lbmd.rank == 0
say = print if rank0 else (lambda *a, **k: None)

# --- the numbers: the host cell's plan; the nucleus's moduli at the same speed-up
host_membrane = {k: HOST_STIFFNESS * v for k, v in RBC_MEMBRANE.items()}
radius = HOST_RADIUS
plan = oif.scene_parameters(narrowest=THROAT, mean_speed=args.speed * 1e-3, cell_radius=radius, mesh="sphere642",
                            membrane=host_membrane)
say(plan)
UNITS = plan.units
H = plan.length(HEIGHT)
device = Extrusion.from_svg(LAYOUT, z=[1.0, 1.0 + H], direction=-1, origin=(0.0, 1.0), tolerance=0.05)
vertices = np.concatenate([np.asarray(p) for p in device.polygons])
box = [float(math.ceil(vertices[:, 0].max() - 1e-9)), float(math.ceil(vertices[:, 1].max() + 1.0 - 1e-9)), H + 2.0]
system = lbmd.System(box_l=box)
system.time_step = plan.time_step
system.cell_system.skin = 0.3
lbf = lb.LBFluid(**plan.fluid)
system.actors.add(lbf)
system.lbboundaries.add(lbboundaries.LBBoundary(shape=device))
system.constraints.add(shape=device, particle_type=10, penetrable=False)


def mean_speed():
    nodes = lbf[:, :, :]
    fluid = np.asarray(nodes.boundary) == 0
    return float(np.asarray(nodes.velocity)[fluid][:, 0].mean())


# --- the flow: the body force of the plan's mean speed between two walls
# H apart, scaled (Stokes flow is linear in the force) until the mean speed
# over the fluid is the plan's within 1 % (the channel's mean: the throat,
# which set the lattice, runs faster, about 20/6 times by continuity)
force = plan.slit_force(HEIGHT)
for _ in range(4):
    lbf.ext_force_density = [force, 0.0, 0.0]
    for _ in range(40):
        before = mean_speed()
        system.integrator.run(int(round(20.0 / plan.time_step)))
        reached = mean_speed()
        if abs(reached - before) < 1e-3 * abs(reached):
            break
    if abs(reached / plan.speed - 1.0) < 0.01:
        break
    force *= plan.speed / reached
say(f"flow: mean speed {UNITS.to_si(reached, 'm/s') * 1e3:.4g} mm/s in the scene (asked "
    f"{UNITS.to_si(plan.speed, 'm/s') * 1e3:.4g}), body force {force:.4g}")

# --- the cells
ptypes = [0]
if args.case == "cluster":
    cell_type = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize, normal=True,
                                **plan.moduli)
    cluster = oif.BiCluster(cell_type, [13.0, 0.5 * box[1], 0.5 * box[2]], particle_types=[0, 1],
                            particle_mass=plan.node_mass, scale=plan.contact_scale)
    cells = cluster.cells
    types, ptypes = [cell_type], [0, 1]
else:
    cell_type = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize, normal=True,
                                **plan.moduli)
    types = [cell_type]
    origin = [10.0, 0.5 * box[1], 0.5 * box[2]]
    if args.case == "nucleus":
        cell = oif.OifCell(cell_type=cell_type, particle_type=0, origin=origin, particle_mass=plan.node_mass)
        # the nucleus: its moduli from SI at the cell's speed-up (its own plan
        # would resolve it with a finer lattice; inside the cell the cell's
        # lattice serves), checked by check_settings' membrane trial at the first run
        nucleus_moduli = oif_moduli_from_si(UNITS, **{k: plan.speedup * NUCLEUS_STIFFNESS * v
                                                      for k, v in RBC_MEMBRANE.items()},
                                            membrane_viscosity=RBC_MEMBRANE_VISCOSITY)
        size = plan.length(NUCLEUS_RADIUS)
        nucleus_type = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(size,) * 3,
                                       normal=True, **nucleus_moduli)
        nucleus = oif.add_nucleus(cell, nucleus_type, particle_type=1, scale=plan.contact_scale)
        types, ptypes = [cell_type, nucleus_type], [0, 1]
    else:
        cell = oif.OifCell(cell_type=cell_type, particle_type=0, origin=origin, particle_mass=plan.node_mass,
                           inner_particles=40)
    cells = [cell]
system.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)
oif.set_contacts(system, types, particle_types=ptypes, wall_types=10, scale=plan.contact_scale)

# --- outputs
os.makedirs(args.output, exist_ok=True)
to_ms = lambda t: UNITS.to_si(t, "s") * 1e3  # noqa: E731
steps_per_output = int(round(20.0 / plan.time_step))  # every 20 us
most = args.duration if args.duration is not None else 5.0
n_outputs = max(1, int(round(UNITS.to_lattice(most * 1e-3, "s") / plan.time_step / steps_per_output)))
table = open(os.path.join(args.output, "cells.csv") if rank0 else os.devnull, "w", newline="")
rows = csv.writer(table)
columns = ["time_ms"] + [f"{name}{k}" for k in range(len(cells)) for name in ("x", "y", "z")]
columns += ["max_area_strain", "volume_ratio"]
columns += {"nucleus": ["nucleus_nodes_outside", "nucleus_gap_um", "nucleus_volume_ratio"],
            "inner": ["inner_outside"], "cluster": ["separation_um"]}[args.case]
rows.writerow(columns)
volume0 = [c.volume() for c in cells]
separation0 = cluster.separation() if args.case == "cluster" else None
if args.case == "nucleus":
    nucleus_volume0 = nucleus.volume()
vtk = None
if not args.no_vtk:
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
    vtk = oif.CellSeries(os.path.join(args.output, "cells.pvd"))
worst = {"outside": 0, "gap": math.inf, "volume": 0.0}


def record():
    row = [f"{to_ms(system.time):.4f}"]
    for c in cells:
        row += [f"{u:.3f}" for u in c.get_origin()]
    row += [f"{max(c.max_area_strain() for c in cells):.4f}"]
    ratio = max(abs(c.volume() / v0 - 1.0) for c, v0 in zip(cells, volume0))
    worst["volume"] = max(worst["volume"], ratio)
    row += [f"{ratio:.5f}"]
    triangles = cell_type.mesh._topo.triangles
    if args.case == "nucleus":
        membrane = cell.mesh.positions()
        out = int(np.count_nonzero(~_inside(nucleus.mesh.positions(), membrane, triangles)))
        gap = float(_nearest_distance(nucleus.mesh.positions(), membrane).min())
        worst["outside"], worst["gap"] = max(worst["outside"], out), min(worst["gap"], gap)
        row += [out, f"{gap:.4f}", f"{nucleus.volume() / nucleus_volume0:.5f}"]
    elif args.case == "inner":
        out = int(np.count_nonzero(~_inside(cell.inner_particles.pos, cell.mesh.positions(), triangles)))
        worst["outside"] = max(worst["outside"], out)
        row += [out]
    else:
        row += [f"{cluster.separation():.4f}"]
    rows.writerow(row)
    table.flush()
    if vtk is not None:
        vtk.write(cells + ([nucleus] if args.case == "nucleus" else []), system.time)


def picture(name):
    if args.no_plots:
        return
    import lbmd.visualization
    shown = cells + ([nucleus] if args.case == "nucleus" else [])
    path = os.path.join(args.output, name)
    lbmd.visualization.cells(system, shown, mode="projected", units=UNITS, ids=False, save=path)
    say(f"picture: {path}")


record()
picture("scene_start.png")
passed_at = None
for i in range(n_outputs):
    system.integrator.run(steps_per_output)
    record()
    rear = min(c.mesh.positions()[:, 0].min() for c in cells)  # the cells' rearmost node, unfolded
    if passed_at is None and rear > PASSED_X:
        passed_at = to_ms(system.time)
        if args.duration is None:
            break
table.close()
picture("scene_end.png")
what = {"nucleus": "the nucleated cell", "inner": "the cell with inner particles", "cluster": "the cluster"}[args.case]
say(f"{what} {'passed the throat at ' + format(passed_at, '.3f') + ' ms' if passed_at else 'did not pass the throat'}"
    f" (its rearmost node beyond x = {PASSED_X:g} um); largest volume change {100 * worst['volume']:.2f} %")
if args.case == "nucleus":
    say(f"nucleus nodes outside the cell, most at any output: {worst['outside']}; closest gap to the membrane "
        f"{worst['gap']:.3f} um (contact offset {system.non_bonded_inter[0, 1].hard_contact.get_params()['offset']:g})")
elif args.case == "inner":
    say(f"inner particles outside the cell, most at any output: {worst['outside']}")
else:
    say(f"distance of the two cells' centres at the end: {cluster.separation():.3f} um (at the start "
        f"{separation0:.3f})")
say(system.integrator.timing_report())
say(f"output in {os.path.abspath(args.output)}/: cells.csv"
    + ("" if args.no_plots else ", scene_start.png, scene_end.png") + ("" if vtk is None else ", walls.vtp, cells.pvd"))
