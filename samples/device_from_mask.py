#!/usr/bin/env pyoif
"""Red blood cells through a microfluidic constriction drawn as a 2D layout:
the device from a CAD file, an inlet and an outlet, cells entering at a set
haematocrit and leaving at the outlet.

    pyoif samples/device_from_mask.py [--layout samples/data/constriction.dxf]
          [--scale UM] [--height UM] [--speed MM_S] [--haematocrit H] [--duration MS]
          [--output-every US] [--seed S] [--output DIR] [--vtk] [--no-plots]

The device: samples/data/constriction.dxf (or .svg, or a black/white PNG
mask with --pixel-size) -- a channel 60 x 20 drawing units whose walls bulge
in to a throat 6 units wide -- scaled by --scale um per unit (default 1.5:
a channel 90 x 30 um, throat 9 um) and extruded to --height um (default 12)
with lbmd.shapes.Extrusion (direction -1: the drawn region is the channel;
the shape is both the fluid's boundary and the cells' wall). The flow:
plasma (1000 kg/m^3, 1.5 mPa s) enters through a Poiseuille velocity inlet
on the x- face at a mean speed --speed (mm/s, default 30) and leaves
through a pressure outlet on the x+ face (lbmd.open_boundaries). The cells:
red blood cells (rbc374, radius 3.91 um) enter in the first 15 um of the
channel (oif.CellFlow: random positions and orientations, seeded, never
overlapping) while the haematocrit there is below --haematocrit (default
0.1), and are removed 5 um before the outlet. As in the flagship sample the
membranes are stiffer in proportion to the speed (the capillary numbers of
the paper's RBCs at 1.3 mm/s; at most 27 x their moduli), with a light
node mass and a small membrane viscosity. (At most 27x, the flagship's --small:
40x and 60x broke here within 1 ms at 45 and 60 mm/s.)

Outputs in DIR (default output_device): cells.csv (per output, every cell
in the device: centre, velocity, volume, surface, the longest extent),
events.csv (each cell's entry and exit, time and position), scene.json,
device_trajectories.png (the cells' paths over the layout) and with --vtk
walls.vtp, cells.pvd, fluid.pvd (mid-height plane) for ParaView.
"""
import argparse
import csv
import json
import math
import os

import numpy as np

import lbmd
import oif
from lbmd import file_output, lb, lbboundaries
from lbmd.open_boundaries import PressureOutlet, VelocityInlet
from lbmd.shapes import Extrusion
from lbmd.units import UnitSystem, oif_moduli_from_si

HERE = os.path.dirname(os.path.abspath(__file__))
UNITS = UnitSystem()  # um, us, 1e-15 kg
PLASMA_DENSITY, PLASMA_VISCOSITY = 1000.0, 1.5e-3      # kg/m^3, Pa s
RBC_RADIUS = 3.91e-6                                   # m
# the PyOIF paper's RBC membrane (see cell_flow_in_bifurcation.py)
RBC_MEMBRANE = dict(shear_modulus=2.1651e-6, bending_modulus=1.7321e-17, local_area_modulus=3.5e-6,
                    global_area_modulus=3.5e-4, volume_modulus=900.0)
MEMBRANE_VISCOSITY = 4.33e-10                          # Pa s m (kvisc 1.0)
PAPER_MEAN_SPEED = 1.3e-3 / 1.5                        # m/s: the paper's centre line 1.3 mm/s, as a mean
STIFFEST = 27.0                                        # as the flagship's --small (held 8 ms there)
TIME_STEP = 1e-7                                       # s


def parse_arguments(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--layout", default=os.path.join(HERE, "data", "constriction.dxf"),
                    help="the device layout: .dxf, .svg or a .png mask (then --pixel-size)")
    ap.add_argument("--pixel-size", type=float, default=None, help="drawing units per pixel of a PNG mask")
    ap.add_argument("--scale", type=float, default=1.5, help="um per drawing unit")
    ap.add_argument("--height", type=float, default=12.0, help="channel height in um")
    ap.add_argument("--speed", type=float, default=30.0, help="mean speed at the inlet in mm/s")
    ap.add_argument("--haematocrit", type=float, default=0.1, help="haematocrit kept in the inlet region")
    ap.add_argument("--duration", type=float, default=3.0, help="simulated time in ms")
    ap.add_argument("--output-every", type=float, default=20.0, help="output interval in us")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--output", default="output_device")
    ap.add_argument("--vtk", action="store_true")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    for name in ("scale", "height", "speed", "duration", "output_every"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number, got {value}")
    if not 0 < args.haematocrit <= 0.4:
        ap.error(f"--haematocrit must be in (0, 0.4], got {args.haematocrit}")
    return args


args = parse_arguments()
rank0 = lbmd.rank == 0
say = print if rank0 else (lambda *a, **k: None)

# --- the device: the layout, scaled and extruded (um = lattice units)
H = args.height
suffix = os.path.splitext(args.layout)[1].lower()
common = dict(z=[1.0, 1.0 + H], direction=-1)
if suffix == ".dxf":
    device = Extrusion.from_dxf(args.layout, scale=args.scale, tolerance=0.05 / args.scale,
                                origin=(0.0, 1.0), **common)
elif suffix == ".svg":
    device = Extrusion.from_svg(args.layout, scale=args.scale, tolerance=0.05 / args.scale,
                                origin=(0.0, 1.0), **common)
elif suffix == ".png":
    if args.pixel_size is None:
        raise SystemExit("device_from_mask: a PNG mask needs --pixel-size (drawing units per pixel)")
    device = Extrusion.from_mask(args.layout, pixel_size=args.pixel_size * args.scale, solid="black",
                                 origin=(0.0, 1.0), **common)
else:
    raise SystemExit(f"device_from_mask: --layout must be a .dxf, .svg or .png file, got {args.layout}")
vertices = np.concatenate([np.asarray(p) for p in device.polygons])
length, width = math.ceil(vertices[:, 0].max() - 1e-9), math.ceil(vertices[:, 1].max() + 1.0 - 1e-9)
box = [float(length), float(width), H + 2.0]
system = lbmd.System(box_l=box)
system.time_step = UNITS.to_lattice(TIME_STEP, "s")
system.cell_system.skin = 0.3

# --- the fluid: inlet on x-, outlet on x+
visc = UNITS.to_lattice(PLASMA_VISCOSITY / PLASMA_DENSITY, "m^2/s")
dens = UNITS.to_lattice(PLASMA_DENSITY, "kg/m^3")
lbf = lb.LBFluid(agrid=1.0, dens=dens, visc=visc, tau=system.time_step)
system.actors.add(lbf)
system.lbboundaries.add(lbboundaries.LBBoundary(shape=device))
system.constraints.add(shape=device, particle_type=10, penetrable=False)
speed = UNITS.to_lattice(args.speed * 1e-3, "m/s")
lbf.open_boundaries.add(VelocityInlet(face="x-", profile="poiseuille", mean_velocity=speed))
lbf.open_boundaries.add(PressureOutlet(face="x+", density=dens))

# --- the cells: stiffer in proportion to the speed (the paper's capillary numbers)
stiffness = min(args.speed * 1e-3 / PAPER_MEAN_SPEED, STIFFEST)
moduli = oif_moduli_from_si(UNITS, **{k: stiffness * v for k, v in RBC_MEMBRANE.items()},
                            membrane_viscosity=MEMBRANE_VISCOSITY)
rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(UNITS.to_lattice(RBC_RADIUS, "m"),) * 3,
                      normal=True, **moduli)
gamma = rbc.suggest_LBgamma(visc=visc, dens=dens)
system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
# contacts: the advised hard_contact (cannot be crossed), stiffer with the membranes
oif.set_contacts(system, rbc, particle_types=0, wall_types=10, scale=stiffness)
inlet_box = ([3.0, 1.0, 1.0], [18.0, width - 1.0, H + 1.0])
flow = oif.CellFlow(system, rbc, inlet=inlet_box, outlet=length - 5.0, haematocrit=args.haematocrit,
                    boundaries=[device], seed=args.seed, particle_mass=gamma * system.time_step / 0.3)

# --- outputs
os.makedirs(args.output, exist_ok=True)
steps_per_output = max(1, int(round(args.output_every * 1e-6 / TIME_STEP)))
n_outputs = max(1, int(round(args.duration * 1e-3 / TIME_STEP / steps_per_output)))
to_ms = lambda t: UNITS.to_si(t, "s") * 1e3  # noqa: E731
to_mm_s = lambda v: UNITS.to_si(v, "m/s") * 1e3  # noqa: E731
file_output.write_text(os.path.join(args.output, "scene.json"), json.dumps(dict(
    layout=os.path.basename(args.layout), scale_um=args.scale, box_um=box, height_um=H, speed_mm_s=args.speed,
    haematocrit=args.haematocrit, stiffness=stiffness, seed=args.seed, steps_per_output=steps_per_output,
    outputs=n_outputs, polygons_um=[np.asarray(p).tolist() for p in device.polygons]), indent=1) + "\n")
cells_file = open(os.path.join(args.output, "cells.csv") if rank0 else os.devnull, "w", newline="")
events_file = open(os.path.join(args.output, "events.csv") if rank0 else os.devnull, "w", newline="")
cells_csv, events_csv = csv.writer(cells_file), csv.writer(events_file)
cells_csv.writerow(["time_ms", "cell", "x_um", "y_um", "z_um", "vx_mm_s", "vy_mm_s", "vz_mm_s", "volume_um3",
                    "surface_um2", "extent_um"])
events_csv.writerow(["time_ms", "cell", "event", "x_um", "y_um", "z_um"])
if args.vtk:
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
    cell_series = oif.CellSeries(os.path.join(args.output, "cells.pvd"))
    fluid_series = lbmd.vtk_output.FluidSeries(os.path.join(args.output, "fluid.pvd"), lbf,
                                               slice=("z", int(round(0.5 * box[2] - 0.5))))


def log_events(added, removed, t):
    for kind, group in (("in", added), ("out", removed)):
        for c in group:
            x, y, z = c.get_origin() if kind == "in" else c.last_origin
            events_csv.writerow([f"{t:.4f}", c.cell_id, kind, f"{x:.3f}", f"{y:.3f}", f"{z:.3f}"])


def record():
    t = to_ms(system.time)
    for c in flow.cells:
        pos = c.mesh.positions()
        c.last_origin = pos.mean(axis=0)  # kept for the exit event
        v = c.get_velocity()
        extent = np.linalg.norm(pos.max(axis=0) - pos.min(axis=0))
        cells_csv.writerow([f"{t:.4f}", c.cell_id, *(f"{u:.3f}" for u in c.last_origin),
                            *(f"{to_mm_s(u):.4f}" for u in v), f"{c.volume():.3f}", f"{c.surface():.3f}",
                            f"{extent:.3f}"])
    cells_file.flush()
    events_file.flush()
    if args.vtk:
        cell_series.write(flow.cells, system.time)
        fluid_series.write(system.time)


say(f"device {os.path.basename(args.layout)} x {args.scale:g} um: box {box[0]:g} x {box[1]:g} x {box[2]:g} um, "
    f"height {H:g} um; inlet mean speed {args.speed:g} mm/s; haematocrit {args.haematocrit:g} at the inlet; "
    f"membranes {stiffness:.3g}x the paper's moduli; {to_ms(n_outputs * steps_per_output * system.time_step):g} ms "
    f"in {n_outputs} outputs")
added, removed = flow.update()
log_events(added, removed, to_ms(system.time))
record()
for i in range(n_outputs):
    system.integrator.run(steps_per_output)
    added, removed = flow.update()
    log_events(added, removed, to_ms(system.time))
    record()
cells_file.close()
events_file.close()
volumes = [c.volume() for c in flow.cells]
say(f"{len(flow.added)} cells entered, {len(flow.removed)} left; {len(flow.cells)} in the device at the end; "
    f"inlet-to-outlet mass flux balance {lbf.open_boundaries.mass_flux('x-') / -lbf.open_boundaries.mass_flux('x+'):.4f}"
    + (f"; cell volumes {min(volumes):.1f}-{max(volumes):.1f} um^3" if volumes else ""))
say(system.integrator.timing_report())

if rank0 and not args.no_plots:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = np.genfromtxt(os.path.join(args.output, "cells.csv"), delimiter=",", names=True)
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for p in device.polygons:
        p = np.asarray(p)
        ax.fill(p[:, 0], p[:, 1], color="0.92", zorder=0)
        ax.plot(np.append(p[:, 0], p[0, 0]), np.append(p[:, 1], p[0, 1]), color="0.4", lw=1)
    if rows.size:
        rows = np.atleast_1d(rows)
        for cell in np.unique(rows["cell"]):
            mine = rows[rows["cell"] == cell]
            ax.plot(mine["x_um"], mine["y_um"], lw=1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (um)")
    ax.set_ylabel("y (um)")
    ax.set_title(f"RBC paths through the constriction ({len(flow.added)} cells in, {len(flow.removed)} out)")
    fig.tight_layout()
    fig.savefig(os.path.join(args.output, "device_trajectories.png"), dpi=110)
    say(f"figure: {os.path.join(args.output, 'device_trajectories.png')}")
say(f"output in {os.path.abspath(args.output)}/: cells.csv, events.csv, scene.json"
    + (", walls.vtp, cells.pvd, fluid.pvd" if args.vtk else ""))
