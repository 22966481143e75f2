#!/usr/bin/env pyoif
"""Cells of two kinds through a deterministic lateral displacement (DLD)
pillar array: the large one is bumped sideways by every column of pillars,
the small one zigzags between them and follows the mean flow.

    pyoif samples/dld_array.py [--layout samples/data/dld_array.svg] [--height UM] [--speed MM_S] [--speedup S]
          [--types rbc leukocyte] [--duration MS] [--output-every US] [--seed S] [--output DIR]
          [--no-vtk] [--no-plots]

The array (Huang et al., Science 304, 987 (2004)): flow along x through
columns of round pillars, a column every lambda along x, a pillar every
lambda along y within a column, each column shifted by epsilon lambda in y
from the one before (the row shift fraction epsilon = 1/N). A particle
larger than a critical diameter D_c cannot fit in the first flow lane
beside a pillar, is pushed by each pillar into the next lane and moves
epsilon lambda sideways per column ("bump"); a smaller one stays in its
streamlines and, after N columns, is back where it started ("zigzag").
Davis's fit of the measured critical diameters: D_c = 1.4 G epsilon^0.48,
G the gap between the pillars of a column (J. A. Davis et al., PNAS 103,
14779 (2006)).

The scene is one periodic unit of the array, as in the DLD simulation
studies (T. Krueger, D. Holmes, P. V. Coveney, Biomicrofluidics 8, 054114
(2014)): N lambda along x and lambda along y, periodic both ways, so that
a cell passes column after column of a small box; walls below and above
(z). The layout, samples/data/dld_array.svg (drawn for the project: lambda
20 um, pillars 10 um wide, G 10 um, epsilon 1/5, so D_c = 6.5 um; pillars
cut by the top or bottom edge drawn on both sides; a box of 100 x 20 um),
is read with
lbmd.shapes.Extrusion.from_svg (1 um per drawing unit; the drawn circles
are the solid), and lambda, the pillar diameter, G, epsilon and the box are
read off its circles; another layout of this kind can be given with
--layout. The pillars span the channel's height (--height, default 10 um);
the one shape is the fluid's boundary and the cells' wall.

The flow: plasma (1000 kg/m^3, 1.5 mPa s) driven by a body force. In a
periodic array a force along x does not drive a flow along x: the tilted
array is anisotropic, and the flow leans towards the pillar rows, which is
not what a device with side walls does (R. Vernekar et al., Lab Chip 17,
3318 (2017)). The force is therefore found by fluid-only runs (Stokes flow
is linear in the force: one run with a force along x, one along y, then the
combination that gives the asked mean velocity along x and none along y,
checked by a third run).

The cells, one at a time, each in the settled flow, each run alone (no
other cell in the box): --types of
  rbc        a red blood cell (rbc374, radius 3.91 um, the paper's membrane),
  stiff-rbc  a red blood cell with its moduli 5x (malaria-infected cells
             stiffen 2 to 10 times: Suresh et al., Acta Biomater. 1, 15
             (2005)),
  leukocyte  a leukocyte-like sphere (sphere162, radius 4.5 um, moduli 10x
             the RBC's, or less where the time step cannot hold them: 4x
             at the default speed).
Each starts in the middle of a gap (with --seed: a random start within
+-1.5 um across the gap and a random orientation) and its centre is
followed unwrapped across the periodic box. The default run (4 ms of flow
per type, about 1.5 minutes on one core): the sphere bumps (0.99 epsilon
lambda per column), the RBC zigzags (0.00); doc/devices.md, "A pillar
array (DLD)", says what else was tried.

The numbers: every one from SI inputs by oif.scene_parameters (one plan per
cell type: the mesh's friction and node mass; the lattice, the time step
and the speed-up S are the same for all), printed at the start: --speed is
the real mean speed of the plasma in the array (mm/s, default 3); the scene
runs it S times faster with the membranes S times stiffer, which keeps the
capillary number (the cells' deformation).

Result, per cell type: the lateral displacement per column in units of
epsilon lambda (1: bumping, 0: zigzag), from the centre's y over the last
whole array periods N lambda it travelled, the first column left out (both
ends at the same place in the array, so that a zigzag's sawtooth cancels
exactly; a run must go at least N + 1 columns), and the mode: bump
(>= 0.7), zigzag (<= 0.3) or mixed.
Outputs in DIR (default output_dld): trajectories.csv (per output and
cell type: time, the centre unwrapped, velocity, volume), displacements.csv
(the table printed at the end), scene.json, flow.png (the settled flow at
mid-height, lbmd.visualization), dld_trajectories.png (the array and each
type's path), scene_<type>.png (the cell in the array at its run's end) and
walls.vtp, fluid.pvd (the settled flow, mid-height plane), cells_<type>.pvd
for ParaView (--no-vtk skips them; --no-plots the pictures).
"""
import argparse
import csv
import json
import math
import os

import numpy as np

import lbmd
import oif
from lbmd import file_output, lb, lbboundaries, shapes
from lbmd.settings_check import check_settings
from oif.scene_plan import RBC_MEMBRANE, RBC_RADIUS

HERE = os.path.dirname(os.path.abspath(__file__))
PLASMA_DENSITY, PLASMA_VISCOSITY = 1000.0, 1.5e-3      # kg/m^3, Pa s
# in fluid at the time step 0.1 us, membranes held up to 100x the paper's
# RBC moduli and failed at 200x (doc/accuracy.md, "membrane limit"): a
# stiffer cell type is made no stiffer than that
STIFFEST = 100.0
# the cell types: mesh, radius (m), moduli relative to the paper's RBC.
# The leukocyte-like sphere is meshed coarsely (sphere162, edges about
# 1.2 um): on sphere642 its plan held only about 1.2x the RBC's moduli at
# the time step 0.1 us (the membrane trial), and so soft a sphere, pressed
# against a pillar while bumping, grew its surface by 5 % and broke within
# 1 ms; sphere162 holds 4x, the most STIFFEST leaves at S = 25
CELL_TYPES = {
    "rbc": dict(label="red blood cell", mesh="rbc374", radius=RBC_RADIUS, stiffness=1.0),
    "stiff-rbc": dict(label="stiff red blood cell", mesh="rbc374", radius=RBC_RADIUS, stiffness=5.0),
    "leukocyte": dict(label="leukocyte-like sphere", mesh="sphere162", radius=4.5e-6, stiffness=10.0),
}
BUMP, ZIGZAG = 0.7, 0.3  # displacement per column (units of epsilon lambda) of the modes


def parse_arguments(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--layout", default=os.path.join(HERE, "data", "dld_array.svg"),
                    help="an SVG of one periodic unit of a pillar array (circles, um)")
    ap.add_argument("--height", type=float, default=10.0, help="channel height (pillar height) in um")
    ap.add_argument("--speed", type=float, default=3.0,
                    help="the real mean speed of the plasma in the array in mm/s; the scene runs it S times "
                         "faster with the membranes S times stiffer (oif.scene_parameters)")
    ap.add_argument("--speedup", type=float, default=None, help="S (default: chosen by oif.scene_parameters)")
    ap.add_argument("--types", nargs="+", choices=sorted(CELL_TYPES), default=["rbc", "leukocyte"],
                    help="the cell types, each run alone in the array")
    ap.add_argument("--duration", type=float, default=4.0, help="simulated flow per cell type in ms")
    ap.add_argument("--output-every", type=float, default=20.0, help="output interval in us")
    ap.add_argument("--seed", type=int, default=None,
                    help="random start (within +-1.5 um across the gap) and orientation; default: the middle "
                         "of the gap, the RBC's disc upright across the flow")
    ap.add_argument("--output", default="output_dld")
    vtk = ap.add_mutually_exclusive_group()
    vtk.add_argument("--vtk", action="store_true", help="ParaView's files (the default)")
    vtk.add_argument("--no-vtk", action="store_true", help="write no ParaView files")
    ap.add_argument("--no-plots", action="store_true", help="make no pictures")
    args = ap.parse_args(argv)
    for name in ("height", "speed", "duration", "output_every"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number, got {value}")
    if args.speedup is not None and not (math.isfinite(args.speedup) and args.speedup >= 1):
        ap.error(f"--speedup must be a number >= 1, got {args.speedup}")
    if args.seed is not None and args.seed < 0:
        ap.error(f"--seed must be >= 0, got {args.seed}")
    if len(set(args.types)) != len(args.types):
        ap.error(f"--types names a type twice: {' '.join(args.types)}")
    if not os.path.isfile(args.layout):
        ap.error(f"--layout: no such file '{args.layout}'")
    if args.height < 2.0 * max(CELL_TYPES[t]["radius"] for t in args.types) * 1e6:
        ap.error(f"--height {args.height:g} um is lower than the widest cell of --types "
                 f"({2e6 * max(CELL_TYPES[t]['radius'] for t in args.types):.3g} um)")
    return args


def pillar_array(polygons):
    """The array of an SVG's circles (flattened to polygons): a dict with the
    pillar centres and radius, the column spacing lambda_x, the pillar
    spacing in a column lambda_y, the row shift fraction epsilon, the number
    of columns, the gap G and the box's x and y lengths. ValueError where
    the drawing is no periodic unit of a DLD array."""
    lo = np.array([np.asarray(p).min(axis=0) for p in polygons])
    hi = np.array([np.asarray(p).max(axis=0) for p in polygons])
    centres, radii = 0.5 * (lo + hi), 0.25 * (hi - lo).sum(axis=1)  # a circle's bounding square
    if np.abs((hi - lo)[:, 0] - (hi - lo)[:, 1]).max() > 0.02 * radii.max():
        raise ValueError("a pillar is not round (its extents along x and y differ)")
    if np.ptp(radii) > 0.02 * radii.max():
        raise ValueError(f"the pillars' radii differ ({radii.min():.3g}..{radii.max():.3g}): one pillar size expected")
    xs = np.unique(np.round(centres[:, 0], 6))
    if len(xs) < 2:
        raise ValueError(f"{len(polygons)} shape(s) in {len(xs)} column: the circles of a pillar array's periodic "
                         "unit, in evenly spaced columns along x, expected")
    if np.ptp(np.diff(xs)) > 1e-6:
        raise ValueError(f"the pillars' columns (x = {', '.join(f'{x:g}' for x in xs)}) are not evenly spaced")
    lam_x, n = float(xs[1] - xs[0]), len(xs)
    rows = [np.sort(centres[np.isclose(centres[:, 0], x, atol=1e-6), 1]) for x in xs]
    spacings = [float(r[1] - r[0]) for r in rows if len(r) > 1]  # a pillar and its image across the edge
    if not spacings or np.ptp(spacings) > 1e-6:
        raise ValueError("the pillar spacing along y is that of the pillars drawn twice in a column (cut by the "
                         "periodic edge): " + ("none is" if not spacings else "they differ"))
    lam_y = spacings[0]
    shifts = [((r[0] - rows[0][0]) / lam_y) % 1.0 for r in rows]  # column i: i epsilon (mod 1)
    eps = 1.0 / n
    expected = np.mod(np.arange(n) * eps, 1.0)
    off = np.abs(((np.array(shifts) - expected) + 0.5) % 1.0 - 0.5)
    if off.max() > 1e-3:
        raise ValueError(f"the columns are not shifted by 1/{n} of the pillar spacing {lam_y:g} each "
                         f"(shifts {', '.join(f'{s:.3g}' for s in shifts)})")
    r = float(radii.mean())
    return dict(centres=centres, radius=r, lambda_x=lam_x, lambda_y=lam_y, epsilon=eps, columns=n,
                gap=lam_y - 2.0 * r, box=(n * lam_x, lam_y), first_column=float(xs[0]), first_row=float(rows[0][0]))


args = parse_arguments()
args.vtk = not args.no_vtk  # ParaView's files by default (about a MB)
rank0 = lbmd.rank == 0
say = print if rank0 else (lambda *a, **k: None)

# --- the array: the layout's circles; their centres and sizes give lambda,
# epsilon and G, and the box is one periodic unit
H = args.height
pillars = shapes.Extrusion.from_svg(args.layout, z=[0.0, H + 2.0], tolerance=0.02, direction=1)
try:
    array = pillar_array(pillars.polygons)
except ValueError as e:
    raise SystemExit(f"dld_array: {args.layout}: {e}") from None
lam, eps, G, n_columns = array["lambda_y"], array["epsilon"], array["gap"], array["columns"]
D_c = 1.4 * G * eps ** 0.48  # Davis's fit (PNAS 2006)
box = [array["box"][0], array["box"][1], H + 2.0]   # a wall one lattice spacing thick below and above

# --- the numbers: the lattice, the time step and the speed-up S from the
# RBC's plan (the Reynolds number of the flow), then a plan per cell type
# (its mesh, friction, node mass and moduli) in that flow
common = dict(narrowest=min(G, H) * 1e-6, mean_speed=args.speed * 1e-3, plasma_viscosity=PLASMA_VISCOSITY,
              plasma_density=PLASMA_DENSITY)
base = oif.scene_parameters(**common, speedup=args.speedup)
plans = {}
for name in args.types:
    kind = CELL_TYPES[name]
    # a stiffer type: at most STIFFEST times the paper's moduli after the
    # speed-up, and less where its plan would need a shorter time step than
    # the flow's (a cell at these moduli failing the membrane trial)
    factor = min(kind["stiffness"], max(1.0, STIFFEST / base.speedup))
    while True:
        plans[name] = oif.scene_parameters(**common, cell_radius=kind["radius"], mesh=kind["mesh"],
                                           speedup=base.speedup,
                                           membrane={k: factor * v for k, v in RBC_MEMBRANE.items()})
        if plans[name].time_step >= base.time_step or factor <= 1.0:
            break
        factor = max(1.0, factor / 1.5)
    plans[name].factor = factor
    if factor < kind["stiffness"]:
        say(f"note: the {kind['label']}'s moduli are {factor:.3g}x the RBC's, not {kind['stiffness']:g}x: the "
            f"most the time step {base.time_step:g} holds at the speed-up {base.speedup:.3g} (a lower --speedup "
            f"allows more)")
plan = plans[args.types[0]]
if any(p.fluid != base.fluid or p.time_step != base.time_step for p in plans.values()):
    raise SystemExit("dld_array: the cell types need different lattices or time steps (" + ", ".join(
        f"{t}: agrid {p.agrid:g}, time step {p.time_step:g}" for t, p in plans.items())
        + "); run them separately (--types)")
for name, p in plans.items():
    say(f"--- the plan for the {CELL_TYPES[name]['label']} ({name})\n{p}")
UNITS = plan.units  # um, us, 1e-15 kg
to_ms = lambda t: UNITS.to_si(t, "s") * 1e3  # noqa: E731
to_mm_s = lambda v: UNITS.to_si(v, "m/s") * 1e3  # noqa: E731
say(f"array {os.path.basename(args.layout)}: lambda {lam:g} um (columns every {array['lambda_x']:g} um), pillars "
    f"{2 * array['radius']:.3g} um, gap G {G:.3g} um, row shift fraction epsilon 1/{n_columns} = {eps:.3g}; box "
    f"{box[0]:g} x {box[1]:g} x {box[2]:g} um (height {H:g} um); critical diameter D_c = 1.4 G epsilon^0.48 "
    f"= {D_c:.2f} um (Davis 2006)")

system = lbmd.System(box_l=box)
system.time_step = plan.time_step
system.cell_system.skin = 0.3
lbf = lb.LBFluid(**plan.fluid)
system.actors.add(lbf)
walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(H + 1.0))]
for shape in [pillars] + walls:
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=shape))
    system.constraints.add(shape=shape, particle_type=10, penetrable=False)


# --- the flow: the body force giving the asked mean velocity along x and
# none across
def mean_velocity():
    """The mean fluid velocity over the fluid nodes (x, y)."""
    nodes = lbf[:, :, :]
    fluid = np.asarray(nodes.boundary) == 0
    return np.asarray(nodes.velocity)[fluid][:, :2].mean(axis=0)


def settle(force):
    """Run the fluid with this force density until its mean velocity changes
    by less than 0.1 % over 20 us (at least 50 us); returns it."""
    lbf.ext_force_density = [force[0], force[1], 0.0]
    chunk = max(1, int(round(20.0 / plan.time_step)))
    system.integrator.run(2 * chunk)
    previous = mean_velocity()
    for _ in range(100):
        system.integrator.run(chunk)
        u = mean_velocity()
        if np.linalg.norm(u - previous) < 1e-3 * np.linalg.norm(u):
            break
        previous = u
    return u


def drive_flow(target):
    """The force density (fx, fy) giving the mean velocity (target, 0):
    the mobility M (u = M f, Stokes flow) from a run along x and one along y,
    then M^-1 (target, 0), checked (and corrected once more for inertia)."""
    trial = plan.slit_force(H * 1e-6) * target / plan.speed  # plane Poiseuille flow between the walls
    mobility = np.column_stack([settle((trial, 0.0)), settle((0.0, trial))]) / trial
    force = np.linalg.solve(mobility, [target, 0.0])
    for _ in range(3):
        reached = settle(force)
        if np.linalg.norm(reached - [target, 0.0]) < 2e-3 * target:
            break
        force = force + np.linalg.solve(mobility, np.array([target, 0.0]) - reached)
    return force, reached, mobility


force, reached, mobility = drive_flow(plan.speed)
lean = math.degrees(math.atan2(mobility[1, 0], mobility[0, 0]))
say(f"flow: mean speed {to_mm_s(reached[0]):.4g} mm/s along x (asked {args.speed:g} mm/s x {plan.speedup:.3g} = "
    f"{to_mm_s(plan.speed):.4g}), {to_mm_s(reached[1]):.2g} mm/s across; body force density ({force[0]:.4g}, "
    f"{force[1]:.4g}); a force along x alone drives the flow {lean:.2f} deg off x (the array's anisotropy)")
settled = np.asarray(lbf[:, :, :].population).copy()

# --- outputs
os.makedirs(args.output, exist_ok=True)
steps_per_output = max(1, int(round(UNITS.to_lattice(args.output_every * 1e-6, "s") / plan.time_step)))
n_outputs = max(1, int(round(UNITS.to_lattice(args.duration * 1e-3, "s") / plan.time_step / steps_per_output)))
file_output.write_text(os.path.join(args.output, "scene.json"), json.dumps(dict(
    layout=os.path.basename(args.layout), box_um=box, height_um=H, lambda_um=lam, lambda_x_um=array["lambda_x"],
    pillar_diameter_um=2 * array["radius"], gap_um=G, epsilon=eps, columns=n_columns, critical_diameter_um=D_c,
    pillars_um=array["centres"].tolist(), speed_mm_s=args.speed, speedup=plan.speedup, force=force.tolist(),
    mean_velocity_mm_s=[to_mm_s(u) for u in reached], types=args.types, seed=args.seed,
    steps_per_output=steps_per_output, outputs=n_outputs), indent=1) + "\n")
mid = int(round(0.5 * box[2] - 0.5))  # the mid-height node plane
vtk_every = max(1, int(round(100.0 / args.output_every)))  # the cells for ParaView every 100 us (a few MB)
if args.vtk:
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
    lbmd.vtk_output.FluidSeries(os.path.join(args.output, "fluid.pvd"), lbf, slice=("z", mid)).write(system.time)
if not args.no_plots:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import lbmd.visualization
    fig = lbmd.visualization.fluid(system, position=0.5 * box[2], units=UNITS,
                                   save=os.path.join(args.output, "flow.png"))
    plt.close(fig)
table_file = open(os.path.join(args.output, "trajectories.csv") if rank0 else os.devnull, "w", newline="")
table = csv.writer(table_file)
table.writerow(["type", "time_ms", "x_um", "y_um", "z_um", "vx_mm_s", "vy_mm_s", "volume_um3", "surface_um2"])


# --- the cells, one type at a time in the settled flow
def clearance(centre, radius):
    """The gap between a ball of this radius at centre and the nearest pillar
    (periodic in y) or wall."""
    d = array["centres"] - centre[:2]
    d[:, 1] -= lam * np.round(d[:, 1] / lam)
    pillar = np.hypot(d[:, 0], d[:, 1]).min() - array["radius"]
    return min(pillar, centre[2] - 1.0, H + 1.0 - centre[2]) - radius


def start(radius, rng):
    """Where a cell starts and how it is turned: its centre midway between the
    first two columns, in the middle of the next column's gap (y), at
    mid-height; the RBC's disc upright across the flow (the y-z plane).
    With --seed (rng): the centre drawn within +-1 um along x, +-1.5 um
    across the gap and up to +-0.5 um in height (as far as the walls
    leave room), the cell's ball (the mesh's farthest node) clear of the
    pillars and walls by the contacts' reach, and the angles about x, y and
    z drawn at random."""
    centre = np.array([array["first_column"] + 0.5 * array["lambda_x"],
                       (array["first_row"] + eps * lam + 0.5 * lam) % lam, 1.0 + 0.5 * H])
    if rng is None:
        return centre, (0.0, 0.5 * math.pi, 0.0)
    room = max(0.0, 0.5 * H - radius - oif.contacts.CONTACT_CUTOFF)  # in height
    for _ in range(1000):
        drawn = centre + rng.uniform(-1.0, 1.0, 3) * [1.0, 1.5, min(0.5, room)]
        if clearance(drawn, radius) >= oif.contacts.CONTACT_CUTOFF - 1e-6:  # (rounding: a sphere between walls)
            return drawn, tuple(rng.uniform(0.0, 2.0 * math.pi, 3))
    raise SystemExit(f"dld_array: no start for a cell of radius {radius:g} um within the contacts' reach "
                     f"({oif.contacts.CONTACT_CUTOFF:g} um) clear of the pillars near {centre.round(2).tolist()}")


def displacement(x, y):
    """The lateral displacement per column in units of epsilon lambda over the
    last whole array periods the centre travelled, the first column left
    out (where a cell started off its lane finds it): from the y where it
    was k N lambda_x before its end (interpolated between outputs) to its
    y at the end, the same place in the array, so that a zigzag's sawtooth
    cancels exactly. Returns it and k; (nan, 0) before one period."""
    period = n_columns * array["lambda_x"]
    k = int((x[-1] - x[0] - array["lambda_x"]) // period)
    if k < 1:
        return float("nan"), 0
    x_start = x[-1] - k * period
    i = int(np.argmax(x >= x_start))  # the first output at or past it (i >= 1)
    w = (x_start - x[i - 1]) / (x[i] - x[i - 1])
    y_start = y[i - 1] + w * (y[i] - y[i - 1])
    return float((y[-1] - y_start) / (k * n_columns) / (eps * lam)), k


results = {}
rng = None if args.seed is None else np.random.default_rng(args.seed)
for name in args.types:
    kind, p = CELL_TYPES[name], plans[name]
    lbf[:, :, :].population = settled  # every type meets the same settled flow
    cell_type = oif.OifCellType(*oif.mesh_files(p.mesh), system=system, resize=p.resize, normal=True, **p.moduli)
    ptype = args.types.index(name)
    reach = float(np.linalg.norm(cell_type.mesh.positions() - cell_type.mesh.positions().mean(axis=0),
                                 axis=1).max())
    origin, angles = start(reach, rng)
    cell = oif.OifCell(cell_type=cell_type, particle_type=ptype, origin=origin, rotate=angles,
                       particle_mass=p.node_mass)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=p.gamma)
    oif.set_contacts(system, cell_type, particle_types=ptype, wall_types=10, scale=p.contact_scale)
    check_settings(system, warn=True)  # this cell in this flow against the measured limits
    if args.vtk:
        series = oif.CellSeries(os.path.join(args.output, f"cells_{name}.pvd"))
    volume0, t0 = cell.volume(), system.time
    track, drift = [], 0.0
    for i in range(n_outputs + 1):
        if i:
            system.integrator.run(steps_per_output)
        centre, v = cell.get_origin(), cell.get_velocity()
        volume = cell.volume()
        drift = max(drift, abs(volume / volume0 - 1.0))
        track.append(centre)
        table.writerow([name, f"{to_ms(system.time - t0):.4f}", *(f"{c:.3f}" for c in centre),
                        f"{to_mm_s(v[0]):.4f}", f"{to_mm_s(v[1]):.4f}", f"{volume:.3f}", f"{cell.surface():.3f}"])
        if args.vtk and i % vtk_every == 0:
            series.write([cell], system.time - t0)
    table_file.flush()
    track = np.array(track)
    per_column, periods = displacement(track[:, 0], track[:, 1])
    mode = ("too short" if periods == 0 else "bump" if per_column >= BUMP else "zigzag" if per_column <= ZIGZAG
            else "mixed")
    results[name] = dict(label=kind["label"], diameter=2e6 * kind["radius"], stiffness=p.factor,
                         travelled=float(track[-1, 0] - track[0, 0]), periods=periods, per_column=per_column,
                         mode=mode, volume_drift=drift, track=track)
    say(f"{name}: travelled {results[name]['travelled']:.1f} um ({periods} array periods) in "
        f"{to_ms(system.time - t0):g} ms, lateral displacement per column {per_column:.3f} epsilon lambda: "
        f"{mode}; volume held within {100 * drift:.2f} %")
    if not args.no_plots:
        fig = lbmd.visualization.cells(system, [cell], mode="projected", units=UNITS, ids=False,
                                       save=os.path.join(args.output, f"scene_{name}.png"))
        plt.close(fig)
    cell.remove()
table_file.close()

# --- the result
rows = [["type", "cell", "diameter_um", "stiffness", "travelled_um", "periods", "displacement_per_column",
         "mode", "volume_drift"]]
for name, r in results.items():
    rows.append([name, r["label"], f"{r['diameter']:.2f}", f"{r['stiffness']:.3g}", f"{r['travelled']:.1f}",
                 r["periods"], f"{r['per_column']:.3f}", r["mode"], f"{r['volume_drift']:.4f}"])
if rank0:
    with open(os.path.join(args.output, "displacements.csv"), "w", newline="") as f:
        csv.writer(f).writerows(rows)
say(f"\nlateral displacement per column, in units of epsilon lambda = {eps * lam:.3g} um (1: bump, 0: zigzag); "
    f"D_c = {D_c:.2f} um")
widths = [max(len(str(r[k])) for r in rows) for k in range(len(rows[0]))]
for r in rows:
    say("  " + "  ".join(f"{str(v):<{w}}" for v, w in zip(r, widths)))
say(system.integrator.timing_report())

if rank0 and not args.no_plots:
    from matplotlib.patches import Circle
    tracks = [r["track"] for r in results.values()]
    x_hi = max(array["box"][0], max(t[:, 0].max() for t in tracks) + 5.0)
    y_lo = min(0.0, min(t[:, 1].min() for t in tracks) - 5.0)
    y_hi = max(lam, max(t[:, 1].max() for t in tracks) + 5.0)
    fig, ax = plt.subplots(figsize=(min(16.0, 2.0 + x_hi / 40.0), 1.5 + (y_hi - y_lo) / 40.0 * 1.2))
    period = array["box"][0]
    for m in range(int(x_hi // period) + 1):  # the periodic unit repeated over the paths
        for k in range(int(math.floor(y_lo / lam)) - 1, int(math.ceil(y_hi / lam)) + 1):
            for cx, cy in array["centres"]:
                ax.add_patch(Circle((cx + m * period, cy + k * lam), array["radius"], color="0.8", lw=0))
    for (name, r), colour in zip(results.items(), ("tab:red", "tab:blue", "tab:green")):
        ax.plot(r["track"][:, 0], r["track"][:, 1], color=colour, lw=1.8,
                label=f"{r['label']} ({r['diameter']:.3g} um): {r['per_column']:.2f} epsilon lambda per column, "
                      f"{r['mode']}")
    x0, y0 = tracks[0][0, :2]
    ax.plot([x0, x_hi], [y0, y0 + (x_hi - x0) / array["lambda_x"] * eps * lam], color="k", lw=0.8, ls="--",
            label="the array's tilt (full bumping)")
    ax.set_xlim(0, x_hi)
    ax.set_ylim(y_lo, y_hi)
    ax.set_aspect("equal")
    ax.set_xlabel("x (um), the flow")
    ax.set_ylabel("y (um)")
    ax.set_title(f"DLD array: lambda {lam:g} um, gap {G:.3g} um, epsilon {eps:.3g}, D_c {D_c:.2f} um (Davis 2006)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.25), fontsize=8, ncol=1, frameon=False)
    fig.tight_layout()
    fig.savefig(os.path.join(args.output, "dld_trajectories.png"), dpi=110, bbox_inches="tight")
    plt.close(fig)
    say(f"figure: {os.path.join(args.output, 'dld_trajectories.png')}")
say(f"output in {os.path.abspath(args.output)}/: trajectories.csv, displacements.csv, scene.json"
    + ("" if args.no_plots else ", flow.png, dld_trajectories.png, " + ", ".join(f"scene_{t}.png" for t in args.types))
    + (", walls.vtp, fluid.pvd, " + ", ".join(f"cells_{t}.pvd" for t in args.types) + " (ParaView)"
       if args.vtk else ""))
