#!/usr/bin/env pyoif
"""Red blood cells through a microfluidic device drawn as a 2D layout: the
device from a CAD file, an inlet and as many outlets as the layout has,
cells entering at a set haematocrit and leaving by every outlet.

    pyoif samples/device_from_mask.py [--layout samples/data/constriction.dxf]
          [--scale UM] [--height UM] [--inlet x-] [--outlets x+ [y+ ...]] [--speed MM_S] [--speedup S] [--haematocrit H]
          [--duration MS] [--output-every US] [--seed S] [--output DIR] [--no-vtk] [--no-plots]

The device: a layout -- samples/data/constriction.dxf (default; or .svg, or
a black/white PNG mask with --pixel-size), a channel 60 x 20 drawing units
whose walls bulge in to a throat 6 units wide; samples/data/t_junction.svg, a
T-junction with a side branch to the top; samples/data/bifurcation.svg, an
inlet channel splitting into two branches of widths 10 and 8 -- scaled by
--scale um per unit (default 1.5: the constriction 90 x 30 um, throat 9 um)
and extruded to --height um (default 12) with lbmd.shapes.Extrusion
(direction -1: the drawn region is the channel; the shape is both the
fluid's boundary and the cells' wall).

The ports: the box is the layout's extent, with one lattice spacing of
wall beyond the drawing on every side that is not named a port (so that the
channel's walls there are solid nodes). On the --inlet face (default x-)
and each of the --outlets faces (default x+; the T-junction: x+ y+) the
drawn channel must reach the box's side; each run of fluid nodes it has
there (read from the lattice's boundary flags) is a port. Plasma (1000
kg/m^3, 1.5 mPa s) enters the inlet ports through a Poiseuille velocity
inlet and leaves through pressure
outlets at the plasma's density on the outlet faces (lbmd.open_boundaries;
a face whose opposite face is closed by wall may be open alone, as the
T-junction's y+). The cells: red blood cells (rbc374, radius 3.91
um) enter in the first 3..18 um of each inlet run (oif.CellFlow: random
positions and orientations, seeded, never overlapping) while the
haematocrit there is below --haematocrit (default 0.1), and are removed
within 5 um of any outlet run (one CellFlow outlet region per run: two
branches ending on one face are two outlets).

The numbers: every one from SI inputs by oif.scene_parameters, printed with
its reason and expected error at the start: --speed is the real mean speed
at the inlet (mm/s, default 1.1); the scene runs S times faster (default
chosen: 27, the stiffest membranes the samples held at the time step of
0.1 us; --speedup S) with the paper's membrane moduli S times stiffer, so
the capillary number, and so the cells' deformation, is the real speed's
(40x and 60x broke here within 1 ms); lattice spacing 1 um, time step 0.1
us, the calibrated coupling friction, a light node mass (gamma dt / m =
0.3) and the advised contacts stiffened with the membranes.

Printed at the end: the mass flux out of the device over the mass flux in,
and per outlet its share of the flow and the cells that left by it.
Outputs in DIR (default output_device): cells.csv (per output, every cell
in the device: centre, velocity, volume, surface, the longest extent),
events.csv (each cell's entry and exit, time, position and, for an exit,
the outlet), scene.json, scene_start.png and scene_end.png (the device and
its cells seen from above), device_trajectories.png (the cells' paths over
the layout; --no-plots skips the pictures) and walls.vtp, cells.pvd,
fluid.pvd (mid-height plane) for ParaView (--no-vtk skips them).
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
from lbmd.open_boundaries import PressureOutlet, VelocityInlet, find_ports, port_flow, port_region
from lbmd.shapes import Extrusion

HERE = os.path.dirname(os.path.abspath(__file__))
FACES = ("x-", "x+", "y-", "y+")  # the box's sides in the layout's plane
# every number of the scene from the SI inputs below and the command line:
# oif.scene_parameters (lattice spacing, time step, speed-up with the
# membranes stiffened to match, friction, node mass, contacts; printed with
# the reasons at the start)
PLASMA_DENSITY, PLASMA_VISCOSITY = 1000.0, 1.5e-3      # kg/m^3, Pa s


def parse_arguments(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--layout", default=os.path.join(HERE, "data", "constriction.dxf"),
                    help="the device layout: .dxf, .svg or a .png mask (then --pixel-size)")
    ap.add_argument("--pixel-size", type=float, default=None, help="drawing units per pixel of a PNG mask")
    ap.add_argument("--scale", type=float, default=1.5, help="um per drawing unit")
    ap.add_argument("--height", type=float, default=12.0, help="channel height in um")
    ap.add_argument("--speed", type=float, default=1.1,
                    help="the real mean speed at the inlet in mm/s; the scene runs it S times faster with the "
                         "membranes S times stiffer (oif.scene_parameters: S = 27 here)")
    ap.add_argument("--speedup", type=float, default=None, help="S (default: chosen by oif.scene_parameters)")
    ap.add_argument("--haematocrit", type=float, default=0.1, help="haematocrit kept in the inlet region")
    ap.add_argument("--duration", type=float, default=3.0, help="simulated time in ms")
    ap.add_argument("--output-every", type=float, default=20.0, help="output interval in us")
    ap.add_argument("--inlet", choices=FACES, default="x-",
                    help="the face of the velocity inlet (the layout's channel must reach it)")
    ap.add_argument("--outlets", choices=FACES, nargs="+", default=["x+"],
                    help="the faces of the pressure outlets (the layout's channel must reach each)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--output", default="output_device")
    vtk = ap.add_mutually_exclusive_group()
    vtk.add_argument("--vtk", action="store_true", help="ParaView's files (the default)")
    vtk.add_argument("--no-vtk", action="store_true", help="write no ParaView files")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    for name in ("scale", "height", "speed", "duration", "output_every"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number, got {value}")
    if args.inlet in args.outlets or len(set(args.outlets)) != len(args.outlets):
        ap.error(f"--inlet {args.inlet} and --outlets {' '.join(args.outlets)} must be different faces")
    if not 0 < args.haematocrit <= 0.4:
        ap.error(f"--haematocrit must be in (0, 0.4], got {args.haematocrit}")
    return args


args = parse_arguments()
args.vtk = not args.no_vtk  # ParaView's files by default (a few MB)
rank0 = lbmd.rank == 0
say = print if rank0 else (lambda *a, **k: None)

# --- the device: the layout, scaled and extruded (um = lattice units). The
# box is the layout's extent; a side that is no port gets one more lattice
# spacing of wall beyond the drawing, so that the channel's walls there are
# solid nodes, not the box's periodic edge; a port's side ends at the drawing
ports_at = {args.inlet, *args.outlets}
H = args.height
origin = (0.0 if "x-" in ports_at else 1.0, 0.0 if "y-" in ports_at else 1.0)
suffix = os.path.splitext(args.layout)[1].lower()
common = dict(z=[1.0, 1.0 + H], direction=-1, origin=origin)
if suffix == ".dxf":
    device = Extrusion.from_dxf(args.layout, scale=args.scale, tolerance=0.05 / args.scale, **common)
elif suffix == ".svg":
    device = Extrusion.from_svg(args.layout, scale=args.scale, tolerance=0.05 / args.scale, **common)
elif suffix == ".png":
    if args.pixel_size is None:
        raise SystemExit("device_from_mask: a PNG mask needs --pixel-size (drawing units per pixel)")
    device = Extrusion.from_mask(args.layout, pixel_size=args.pixel_size * args.scale, solid="black", **common)
else:
    raise SystemExit(f"device_from_mask: --layout must be a .dxf, .svg or .png file, got {args.layout}")
vertices = np.concatenate([np.asarray(p) for p in device.polygons])
length = math.ceil(vertices[:, 0].max() + (0.0 if "x+" in ports_at else 1.0) - 1e-9)
width = math.ceil(vertices[:, 1].max() + (0.0 if "y+" in ports_at else 1.0) - 1e-9)
box = [float(length), float(width), H + 2.0]
plan = oif.scene_parameters(narrowest=H * 1e-6, mean_speed=args.speed * 1e-3, plasma_viscosity=PLASMA_VISCOSITY,
                            plasma_density=PLASMA_DENSITY, speedup=args.speedup)
UNITS = plan.units  # um, us, 1e-15 kg
say(plan)
system = lbmd.System(box_l=box)
system.time_step = plan.time_step
system.cell_system.skin = 0.3

# --- the fluid: the ports found on the box's faces, an inlet and outlets
dens = plan.dens
lbf = lb.LBFluid(**plan.fluid)
system.actors.add(lbf)
system.lbboundaries.add(lbboundaries.LBBoundary(shape=device))
system.constraints.add(shape=device, particle_type=10, penetrable=False)


system.prepare()  # the lattice flagged: the ports are read from it
ports = find_ports(lbf, int(round(0.5 * box[2] - 0.5)))  # each run of fluid nodes on a side face
inlets = [p for p in ports if p[0] == args.inlet]
outlets = [p for p in ports if p[0] in args.outlets]
for face in [args.inlet] + args.outlets:
    if not any(p[0] == face for p in ports):
        raise SystemExit(f"device_from_mask: the layout's channel does not reach the face {face} (it reaches "
                         f"{', '.join(sorted({p[0] for p in ports if p[0] in ports_at})) or 'none'} of "
                         f"{', '.join(sorted(ports_at))})")
lbf.open_boundaries.add(VelocityInlet(face=args.inlet, profile="poiseuille", mean_velocity=plan.speed))
for face in args.outlets:
    lbf.open_boundaries.add(PressureOutlet(face=face, density=dens))


def port_box(port, depth_from, depth_to):
    """The box of a port's run of nodes, from depth_from to depth_to (um)
    inside its face, over the channel's height."""
    return port_region(port, box, (depth_from, depth_to), (1.0, H + 1.0))


# --- the cells: the paper's red cells, their membranes S times stiffer
# (the capillary number of the real speed), the plan's friction and contacts
stiffness = plan.speedup
rbc = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize, normal=True, **plan.moduli)
system.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)
oif.set_contacts(system, rbc, particle_types=0, wall_types=10, scale=plan.contact_scale)
# cells enter in the first 3..18 um of each inlet run and leave within 5 um
# of any outlet (a region per outlet run: two branches on one face are two)
flow = oif.CellFlow(system, rbc, inlet=[port_box(p, 3.0, 18.0) for p in inlets],
                    outlets=[port_box(p, 0.0, 5.0) for p in outlets], haematocrit=args.haematocrit,
                    boundaries=[device], seed=args.seed, particle_mass=plan.node_mass)
port_names = [f"{face} {first}..{last + 1} um" for face, first, last in outlets]

# --- outputs
os.makedirs(args.output, exist_ok=True)
time_step_s = UNITS.to_si(system.time_step, "s")
steps_per_output = max(1, int(round(args.output_every * 1e-6 / time_step_s)))
n_outputs = max(1, int(round(args.duration * 1e-3 / time_step_s / steps_per_output)))
to_ms = lambda t: UNITS.to_si(t, "s") * 1e3  # noqa: E731
to_mm_s = lambda v: UNITS.to_si(v, "m/s") * 1e3  # noqa: E731
file_output.write_text(os.path.join(args.output, "scene.json"), json.dumps(dict(
    layout=os.path.basename(args.layout), scale_um=args.scale, box_um=box, height_um=H, speed_mm_s=args.speed,
    speedup=plan.speedup,
    haematocrit=args.haematocrit, stiffness=stiffness, seed=args.seed, steps_per_output=steps_per_output,
    outputs=n_outputs, polygons_um=[np.asarray(p).tolist() for p in device.polygons]), indent=1) + "\n")
cells_file = open(os.path.join(args.output, "cells.csv") if rank0 else os.devnull, "w", newline="")
events_file = open(os.path.join(args.output, "events.csv") if rank0 else os.devnull, "w", newline="")
cells_csv, events_csv = csv.writer(cells_file), csv.writer(events_file)
cells_csv.writerow(["time_ms", "cell", "x_um", "y_um", "z_um", "vx_mm_s", "vy_mm_s", "vz_mm_s", "volume_um3",
                    "surface_um2", "extent_um"])
events_csv.writerow(["time_ms", "cell", "event", "x_um", "y_um", "z_um", "outlet"])
if args.vtk:
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
    cell_series = oif.CellSeries(os.path.join(args.output, "cells.pvd"))
    fluid_series = lbmd.vtk_output.FluidSeries(os.path.join(args.output, "fluid.pvd"), lbf,
                                               slice=("z", int(round(0.5 * box[2] - 0.5))))


def log_events(added, removed, t):
    exits = {cell_id: k for cell_id, _, k in flow.exits}
    for kind, group in (("in", added), ("out", removed)):
        for c in group:
            x, y, z = c.get_origin() if kind == "in" else c.last_origin
            where = port_names[exits[c.cell_id]] if kind == "out" else ""
            events_csv.writerow([f"{t:.4f}", c.cell_id, kind, f"{x:.3f}", f"{y:.3f}", f"{z:.3f}", where])


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
    f"height {H:g} um; inlet mean speed {args.speed:g} mm/s run {plan.speedup:.3g}x faster "
    f"({to_mm_s(plan.speed):.3g} mm/s); haematocrit {args.haematocrit:g} at the inlet; "
    f"membranes {stiffness:.3g}x the paper's moduli; {to_ms(n_outputs * steps_per_output * system.time_step):g} ms "
    f"in {n_outputs} outputs")
def picture(name):
    """The device and its cells seen from above: a PNG in the output
    folder; collective."""
    if args.no_plots:
        return
    import lbmd.visualization
    path = os.path.join(args.output, name)
    fig = lbmd.visualization.cells(system, flow.cells, mode="projected", units=UNITS, ids=False, save=path)
    import matplotlib.pyplot as plt
    plt.close(fig)
    say(f"picture: {path}")


added, removed = flow.update()
log_events(added, removed, to_ms(system.time))
record()
picture("scene_start.png")
for i in range(n_outputs):
    system.integrator.run(steps_per_output)
    added, removed = flow.update()
    log_events(added, removed, to_ms(system.time))
    record()
cells_file.close()
events_file.close()
picture("scene_end.png")
volumes = [c.volume() for c in flow.cells]
fluxes = {f.face: lbf.open_boundaries.mass_flux(f.face) for f in lbf.open_boundaries}
flows = [port_flow(lbf, p) for p in outlets]
say(f"{len(flow.added)} cells entered, {len(flow.removed)} left; {len(flow.cells)} in the device at the end"
    + (f"; cell volumes {min(volumes):.1f}-{max(volumes):.1f} um^3" if volumes else ""))
say("mass flux out of the device over the mass flux in: "
    f"{-sum(v for k, v in fluxes.items() if k != args.inlet) / fluxes[args.inlet]:.4f}")
for name, q, n in zip(port_names, flows, flow.exit_counts()):
    say(f"  outlet {name}: {100 * q / sum(flows):5.1f} % of the flow, {n} cells left by it")
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
    ax.set_title(f"RBC paths through {os.path.basename(args.layout)} ({len(flow.added)} cells in, "
                 f"{len(flow.removed)} out: " + ", ".join(str(n) for n in flow.exit_counts()) + " by outlet)")
    fig.tight_layout()
    fig.savefig(os.path.join(args.output, "device_trajectories.png"), dpi=110)
    say(f"figure: {os.path.join(args.output, 'device_trajectories.png')}")
say(f"output in {os.path.abspath(args.output)}/: cells.csv, events.csv, scene.json"
    + ("" if args.no_plots else ", scene_start.png, scene_end.png, device_trajectories.png")
    + (", walls.vtp, cells.pvd, fluid.pvd (ParaView)" if args.vtk else ""))
