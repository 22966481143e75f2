#!/usr/bin/env pyoif
"""Red blood cells (and optionally one stiff "rare" cell) flowing through a
channel that bifurcates into two daughter branches and joins again: the
scene of the PyOIF paper's study (its Figs 2-5), its physical inputs in SI.

    pyoif samples/cell_flow_in_bifurcation.py [--small | --full] [--case A|B|C]
          [--cells N | --haematocrit H] [--rare | --no-rare] [--stiff-fraction F] [--seed S] [--orientation auto|random|flat]
          [--duration MS] [--output-every US]
          [--speed MM_S] [--height UM] [--output DIR] [--vtk | --no-vtk] [--no-plots]
          [--progress auto|bar|lines|off] [--checkpoint FILE] [--checkpoint-every MS]
          [--resume]

The paper's scene (--full). A channel 20 um high, periodic along the flow
(x, 160 um): the parent channel (30 um wide) splits at x = 50 um into a
lower and an upper branch of widths 10/20 um (case A), 12/18 um (B) or
15/15 um (C) around an island, and joins again at x = 110 um. Plasma:
density 1000 kg/m^3, viscosity 1.5 mPa s, driven so that the centre-line
speed in the parent channel is 1.3 mm/s. 40 (or --cells 60) red blood cells
(Evans-Fung shape, radius 3.91 um, 374 nodes) and the stiff rare cell (a
sphere of radius 7.5 um, 642 nodes, ten times stiffer), lattice spacing
1 um, time step 0.1 us, 138 ms of flow (the paper's "one pass of the rare
cell"; about 1.4 hours on one core here, 16 hours on 6 cores in the paper).

--haematocrit H packs as many RBCs as fill that share of the channel
with oif.pack_cells instead (e.g. 0.45, blood as it is: 331 cells in the
small scene, packed in 1.5-3 minutes, the cells swollen into place as
deformable cells; doc/oif.md, "Packing").

The default (--small) finishes in a few minutes on a laptop. It differs
from --full in: channel height 14 um (not 20), 24 RBCs (haematocrit about
4 %, as the paper's 40 in the higher channel), no rare cell unless --rare
(then of radius 4.5 um and 3.7 times as stiff as the RBCs, not 10: the
time step's limit), 8 ms of flow, and a flow 27 times faster (centre
line 35 mm/s) with the membranes and contacts 27 times stiffer: the
capillary numbers (viscous against elastic forces: how much the cells
deform) are the paper's, the Reynolds number is 27 times the paper's but
still below 1 (0.7), so the cells' paths and shapes are those of the
slow flow, reached in 1/27 of the time.

Outputs in DIR (--output, default output_bifurcation), in um, ms, mm/s:
- cells.csv: per output and cell, the centre (x, y, z; x folded into the
  box), velocity, surface, volume, diameter, rotation angle (of the node
  that was furthest downstream at the start, about the centre), the
  pass (how often the cell went round the periodic channel), and the
  per-cell observables of doc/oif.md: Taylor's deformation index, the
  largest edge and local-area strains, and the damage record (time above
  30 % local area strain so far, and the largest seen);
- branches.csv: the branch each cell entered on each pass;
- crossings.csv: centre y and z where a cell crossed x = 75 um (the
  branches' middle) and x = 130 um (after the confluence) -- Fig 2;
- haematocrit.csv: cell volume over fluid volume in the parent channel and
  each branch (a cell counts where its centre is), with --stiff-fraction
  also the stiff cells' alone -- Fig 5;
- walls.vtp, cells.pvd (+ .vtp) and fluid.pvd (+ .vti, the mid-height
  plane), for ParaView: by default at the small size (--no-vtk: none),
  with --vtk at the full one;
- scene_start.png, scene_end.png: the device and its cells seen from above
  (lbmd.visualization) at the start and the end;
- bifurcation_fig2..5.png and bifurcation_damage.png (deformation, strain
  and damage over time) from samples/analysis/plot_bifurcation.py (also
  run by hand to combine seeds; --no-plots skips these and the pictures).
- checkpoint.h5 (or --checkpoint FILE): the whole state, written on
  SIGTERM or SIGUSR1 (a batch system's walltime warning; the run then exits
  with status 75) and every --checkpoint-every ms of flow (default 10 with
  --full); --resume continues from it, the tables cut back to its output
  (doc/checkpoints.md).
At the end: the share of branch entries per branch with its count and
statistical uncertainty, the cells' volume and surface drift, and where the
time went. Under mpirun every rank runs this script, rank 0 writes.

Corners are rounded: where the parent channel widens into the branches
and narrows again with radius 2 um, and the island's two ends to
semicircles (radius 4 um, half its thickness). A cell caught on the apex of
an island with corners of 2 um folded around the corner and its nodes
flew apart within a microsecond (at every membrane stiffness from the
paper's to 27x, at time steps 0.1 and 0.05 us, with stronger walls too);
on the semicircle it slides off into a branch. The membranes' nodes weigh
gamma dt / 0.3 and the membranes have a small viscosity (see the
constants and the cells' set-up; doc/study.md).
"""
import argparse
import csv
import json
import math
import os
import sys

import numpy as np

import lbmd
import oif
from lbmd import file_output, lb, lbboundaries, shapes
from lbmd.units import UnitSystem

UNITS = UnitSystem()  # the paper's: length 1 um, time 1 us, mass 1e-15 kg

# --- the paper's physical parameters (SI); the lattice spacing (1 um), the
# time step (0.1 us), the coupling friction and the node mass follow from
# them by oif.scene_parameters (printed at the start with its reasons)
PLASMA_DENSITY = 1000.0               # kg/m^3
PLASMA_VISCOSITY = 1.5e-3             # Pa s
RBC_RADIUS = 3.91e-6                  # m
# the paper's ks 0.005, kb 0.02, kal 0.007, kag 0.7, kv 0.9 (um, us, 1e-15 kg)
# as continuum moduli (lbmd.units.oif_moduli_from_si: mu0 = sqrt(3)/4 ks,
# kc = sqrt(3)/2 kb, K_local = kal/2, K_global = kag/2, kv a bulk modulus)
RBC_MEMBRANE = dict(shear_modulus=2.1651e-6,        # N/m
                    bending_modulus=1.7321e-17,     # J
                    local_area_modulus=3.5e-6,      # N/m
                    global_area_modulus=3.5e-4,     # N/m
                    volume_modulus=900.0)           # Pa
# a membrane viscosity (the edges' dashpots, doc/model.md): eta_m / (eta R)
# = 0.074, far below the RBC's measured 1e-7 N s/m (which the explicit time
# step could not carry); it damps the nodes' relative motion. Without it a
# cell jammed head-on at the island's apex, its neighbour pressing from
# behind, was kicked apart by its own membrane forces within 3 ms (case B;
# kvisc 1 held the 8 ms). A viscosity: not scaled with the flow.
MEMBRANE_VISCOSITY = 4.33e-10         # Pa s m (kvisc 1.0)
# the rare cell's shear, bending, local and global area moduli / the RBC's.
# With kag kept at the RBC's (10x ks, kb, kal only), the rare cell pressed
# against the island's apex in the 138 ms --full run grew its surface by
# 2.4 %: its area modulus relative to its shear modulus was a tenth of an
# RBC's (doc/study.md)
RARE_STIFFNESS = 10.0
# --stiff-fraction: a second RBC population, as for the paper's "mixed"
# suspension of Fig 5 (e.g. malaria-infected cells, whose shear modulus
# rises 2 to 10 times over the parasite's stages: Suresh et al., Acta
# Biomater. 1, 15 (2005)); its shear, bending and local-area moduli / the RBC's
STIFF_RBC = 5.0
# an rbc374 in this scene (node mass as below) held 60x the paper's moduli at
# the time step 0.1 us and failed at 80x within 12 steps: the stiff
# population of the fast --small flow stays at 60x (2.2x the RBCs there)
STIFFEST_RBC = 60.0
# in fluid at time step 0.1 us, membranes held up to 100x the paper's RBC
# moduli and failed at 200x (doc/accuracy.md): the rare cell of the fast
# --small flow stays below that (3.7x the RBC's there)
STIFFEST = 100.0
# node-wall and cell-cell contacts: the advised hard_contact
# (oif.set_contacts: a repulsion that diverges as the gap closes, offset from
# the meshes, doc/interactions.md), stiffened with the membranes

# --- geometry (m): channel along x, periodic; branches between SPLIT and JOIN
CHANNEL_LENGTH, BOX_WIDTH = 160e-6, 40e-6
PARENT = (5e-6, 35e-6)               # parent channel y range (width 30 um)
SPLIT, JOIN = 50e-6, 110e-6
CASES = {"A": (10e-6, 20e-6), "B": (12e-6, 18e-6), "C": (15e-6, 15e-6)}  # lower, upper branch widths
PLANES = (75e-6, 130e-6)             # Fig 2: cells' y where they cross these x
CORNER_RADIUS = 2e-6
PAPER_SPEED = 1.3e-3                 # m/s, centre line of the parent channel

SIZES = {
    "full": dict(height=20e-6, cells=40, rare=True, rare_radius=7.5e-6, speed=PAPER_SPEED, duration=138e-3,
                 output_every=0.2e-3),
    "small": dict(height=14e-6, cells=24, rare=False, rare_radius=4.5e-6, speed=27 * PAPER_SPEED, duration=8e-3,
                  output_every=20e-6),
}


def parse_arguments(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--small", action="store_true", help="the laptop-sized scene (default)")
    size.add_argument("--full", action="store_true", help="the paper's scene (slow: about 1.4 h on one core)")
    ap.add_argument("--case", choices=sorted(CASES), default="A", help="branch widths: A 10/20, B 12/18, C 15/15 um")
    count = ap.add_mutually_exclusive_group()
    count.add_argument("--cells", type=int, default=None, help="number of RBCs (small 24, full 40; the paper: 40, 60)")
    count.add_argument("--haematocrit", type=float, default=None,
                       help="pack RBCs to this share of the channel's volume with oif.pack_cells (e.g. 0.45: blood "
                            "as it is; above about 0.35 the cells are swollen into place as deformable cells)")
    rare_cell = ap.add_mutually_exclusive_group()
    rare_cell.add_argument("--rare", action="store_true", help="add the stiff rare cell (there with --full)")
    rare_cell.add_argument("--no-rare", action="store_true",
                           help="leave the rare cell out (--full: the RBCs alone, as the paper's Table 1 times them)")
    ap.add_argument("--stiff-fraction", type=float, default=0.0,
                    help="fraction of the RBCs that are stiffer (x5 moduli, x2.2 with --small; the paper's 'mixed' "
                         "suspension, Fig 5); "
                         "with the same --seed the cells start where a uniform run's do")
    ap.add_argument("--seed", type=int, default=1, help="random seed of the cells' placement")
    ap.add_argument("--orientation", choices=("auto", "random", "flat"), default="auto",
                    help="the cells' start: random orientations, or discs lying flat between the walls (turned "
                         "at random about the height only: packs about 100 RBCs into the paper's 20 um "
                         "channel); auto (default): random, flat where random ones do not fit")
    ap.add_argument("--duration", type=float, default=None, help="simulated flow in ms (small 8, full 138)")
    ap.add_argument("--output-every", type=float, default=None, help="output interval in us (small 20, full 200)")
    ap.add_argument("--speed", type=float, default=None,
                    help="centre-line speed of the parent channel in mm/s (small 35.1, full 1.3); the membranes "
                         "and contacts are scaled with it so that the capillary numbers stay the paper's")
    ap.add_argument("--height", type=float, default=None, help="channel height in um (small 14, full 20)")
    ap.add_argument("--stiffness", type=float, default=None,
                    help="membrane moduli relative to the paper's (default: --speed / 1.3 mm/s)")
    ap.add_argument("--output", default="output_bifurcation", help="output folder")
    vtk = ap.add_mutually_exclusive_group()
    vtk.add_argument("--vtk", action="store_true",
                     help="write cells, fluid (mid-height plane) and walls for ParaView (the default at the "
                          "small size)")
    vtk.add_argument("--no-vtk", action="store_true", help="write no ParaView files")
    ap.add_argument("--no-plots", action="store_true", help="do not make the PNG figures at the end")
    ap.add_argument("--progress", choices=("auto", "bar", "lines", "off"), default="auto",
                    help="progress bar (auto: on a terminal), a line per output, or nothing")
    ap.add_argument("--checkpoint", default=None,
                    help="checkpoint file (default DIR/checkpoint.h5): written on SIGTERM or SIGUSR1 (then the "
                         "run exits with status 75), every --checkpoint-every ms, and read by --resume")
    ap.add_argument("--checkpoint-every", type=float, default=None,
                    help="write a checkpoint every this many ms of flow (full: 10; small: only on a signal)")
    ap.add_argument("--resume", action="store_true",
                    help="continue the run from its checkpoint (the scene options are the checkpoint's; "
                         "--output, --progress, --no-plots, --checkpoint and --checkpoint-every may change)")
    expert = ap.add_argument_group("lattice units (benchmarks, tests)")
    expert.add_argument("--cycles", type=int, default=None, help="number of outputs (instead of --duration)")
    expert.add_argument("--steps", type=int, default=None, help="MD steps between outputs (instead of --output-every)")
    expert.add_argument("--substeps", type=int, default=None, help="MD steps per lattice update (default 1)")
    expert.add_argument("--force", type=float, default=None,
                        help="body force density driving the flow, lattice units (instead of --speed: no "
                             "calibration run)")
    args = ap.parse_args(argv)
    for name in ("cells", "cycles", "steps"):
        value = getattr(args, name)
        if value is not None and value < (0 if name in ("cells", "cycles") else 1):
            ap.error(f"--{name} must be {'>= 0' if name != 'steps' else '>= 1'}, got {value}")
    if args.haematocrit is not None and not (0.0 < args.haematocrit < 0.6):
        ap.error(f"--haematocrit must be in (0, 0.6), got {args.haematocrit}")
    if not (0.0 <= args.stiff_fraction <= 1.0):
        ap.error(f"--stiff-fraction must be between 0 and 1, got {args.stiff_fraction}")
    for name in ("duration", "output_every", "speed", "height", "force", "stiffness", "checkpoint_every"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number, got {value}")
    return args


args = parse_arguments()
checkpoint_path = args.checkpoint or os.path.join(args.output, "checkpoint.h5")
resumed = None
if args.resume:  # the scene, the cells and this script's bookkeeping as the checkpoint left them
    resumed = lbmd.checkpoint.load(checkpoint_path)
    kept = {k: getattr(args, k) for k in ("output", "progress", "no_plots", "checkpoint", "checkpoint_every",
                                          "resume")}
    args = resumed.state["args"]
    args.__dict__.update(kept)
size_name = "full" if args.full else "small"
size = SIZES[size_name]
# ParaView's files: by default at the small size (a few MB), asked for at the full one
args.vtk = bool(args.vtk or (size_name == "small" and not getattr(args, "no_vtk", False)))
n_rbc = args.cells if args.cells is not None else size["cells"]
n_stiff = int(round(args.stiff_fraction * n_rbc))  # of the n_rbc, the stiffer population (particle type 2)
rare = (args.rare or size["rare"]) and not getattr(args, "no_rare", False)  # (checkpoints before --no-rare)
height = args.height * 1e-6 if args.height is not None else size["height"]
speed = args.speed * 1e-3 if args.speed is not None else size["speed"]
# dynamic similarity: membranes and contacts as stiff, relative to the
# viscous forces, as the paper's at its speed
stiffness = args.stiffness if args.stiffness is not None else speed / PAPER_SPEED
if args.height is not None and args.height < 10:
    raise SystemExit(f"--height {args.height} um: the channel must be at least 10 um high for RBCs of "
                     f"radius {RBC_RADIUS * 1e6} um")

# --- the numbers from the SI inputs: the narrowest channel (a branch or the
# height), the paper's flow (its centre-line speed, the mean about 2/3 of
# it) run `stiffness` times faster, the RBC's membrane
duration = args.duration * 1e-3 if args.duration is not None else size["duration"]
plan = oif.scene_parameters(narrowest=min(min(CASES[args.case]), height), mean_speed=PAPER_SPEED / 1.5,
                            speedup=stiffness, cell_radius=RBC_RADIUS, mesh="rbc374", membrane=RBC_MEMBRANE,
                            membrane_viscosity=MEMBRANE_VISCOSITY, plasma_viscosity=PLASMA_VISCOSITY,
                            plasma_density=PLASMA_DENSITY, duration=duration * stiffness,
                            box=[CHANNEL_LENGTH, BOX_WIDTH, height + 2e-6], cells=n_rbc + int(rare), units=UNITS)
if lbmd.rank == 0 and resumed is None:
    print(plan)

# --- everything below in the engine's units (um, us, 1e-15 kg)
L = lambda v: UNITS.to_lattice(v, "m")  # noqa: E731 (a length)
tau, agrid = plan.tau, plan.agrid
time_step = tau / (args.substeps or 1)  # MD steps per lattice update
H = L(height)
L_X, L_Y, H_BOX = L(CHANNEL_LENGTH), L(BOX_WIDTH), H + 2.0  # a wall one node thick below and above
w_low, w_up = (L(w) for w in CASES[args.case])
split, join, parent, r_corner = L(SPLIT), L(JOIN), tuple(L(p) for p in PARENT), L(CORNER_RADIUS)
island = (1.0 + w_low, L_Y - 1.0 - w_up)   # the branches' outer walls are 1 um thick
island_middle = 0.5 * (island[0] + island[1])

if resumed is None:  # the scene made anew (else: as the checkpoint holds it)
    system = lbmd.System(box_l=[L_X, L_Y, H_BOX])
    system.time_step = time_step
    system.cell_system.skin = 0.3


    def block(x0, x1, y0, y1, rounded=(), radius=None):
        """Rectangle [x0, x1] x [y0, y1] over the box height, its corners named in
        `rounded` ('ll', 'lr', 'ul', 'ur': lower/upper, left/right) rounded: a
        union of two overlapping bars, a square at each sharp corner and a
        cylinder at each rounded one."""
        r = radius or r_corner
        box = lambda a0, a1, b0, b1: shapes.Rhomboid(corner=[a0, b0, 0.0], a=[a1 - a0, 0, 0], b=[0, b1 - b0, 0],  # noqa
                                                      c=[0, 0, H_BOX], direction=1)
        parts = [box(x0 + r, x1 - r, y0, y1), box(x0, x1, y0 + r, y1 - r)]
        for name, (cx, cy, sx, sy) in {"ll": (x0, y0, 1, 1), "lr": (x1, y0, -1, 1),
                                       "ul": (x0, y1, 1, -1), "ur": (x1, y1, -1, -1)}.items():
            if name in rounded:
                parts.append(shapes.Cylinder(center=[cx + sx * r, cy + sy * r, 0.5 * H_BOX], axis=[0, 0, 1],
                                             radius=r, length=H_BOX))
            else:
                parts.append(box(min(cx, cx + sx * r), max(cx, cx + sx * r), min(cy, cy + sy * r),
                                 max(cy, cy + sy * r)))
        return shapes.Union(shapes=parts)


    boundaries = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(H + 1.0)),
                  block(0.0, split, 0.0, parent[0], rounded=("ur",)),          # parent, below
                  block(0.0, split, parent[1], L_Y, rounded=("lr",)),          # parent, above
                  block(join, L_X, 0.0, parent[0], rounded=("ul",)),           # outlet, below
                  block(join, L_X, parent[1], L_Y, rounded=("ll",)),           # outlet, above
                  shapes.Rhomboid(corner=[split - 1.0, 0.0, 0.0], a=[join - split + 2.0, 0, 0], b=[0, 1.0, 0],
                                  c=[0, 0, H_BOX]),                            # branch outer walls
                  shapes.Rhomboid(corner=[split - 1.0, L_Y - 1.0, 0.0], a=[join - split + 2.0, 0, 0], b=[0, 1.0, 0],
                                  c=[0, 0, H_BOX]),
                  block(split, join, island[0], island[1], rounded=("ll", "lr", "ul", "ur"),
                        radius=0.4999 * (island[1] - island[0]))]  # island, its ends semicircles

    if getattr(args, "haematocrit", None) is not None:
        # the RBC count of that haematocrit in the channel (the rare cell
        # takes its share); kept in args.cells, so a resumed run knows it
        scratch = lbmd.System(box_l=[100.0, 100.0, 100.0])
        v_rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=scratch, resize=(L(RBC_RADIUS),) * 3).volume0
        del scratch
        v_fluid = oif.fluid_volume(system, boundaries, ([0.0, 0.0, 1.0], [L_X, L_Y, H + 1.0]))
        v_rare = 4.0 / 3.0 * math.pi * L(size["rare_radius"]) ** 3 if rare else 0.0
        n_rbc = args.cells = max(1, int(round((args.haematocrit * v_fluid - v_rare) / v_rbc)))
        n_stiff = int(round(args.stiff_fraction * n_rbc))

    # --- fluid, driven to the centre-line speed
    visc, dens = plan.visc, plan.dens
    lbf = lb.LBFluid(**plan.fluid, ext_force_density=[0.0, 0.0, 0.0])
    system.actors.add(lbf)
    for b in boundaries:
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=b))
        system.constraints.add(shape=b, particle_type=10, penetrable=False)
    probe = [0.5 * split, 0.5 * (parent[0] + parent[1]), 1.0 + 0.5 * H]  # centre line of the parent channel


    def settle():
        """Run the fluid until the probe's speed changes by less than 0.1 % over
        50 us (at least 100 us); returns that speed."""
        chunk = max(1, int(round(50.0 / time_step)))
        system.integrator.run(2 * chunk)
        previous = lbf.get_interpolated_velocity(probe)[0]
        for _ in range(40):
            system.integrator.run(chunk)
            u = lbf.get_interpolated_velocity(probe)[0]
            if abs(u - previous) < 1e-3 * abs(u):
                break
            previous = u
        return u


    def drive_flow(target):
        """The body force density giving the centre-line speed `target` at the
        probe, by fluid-only runs: Stokes flow is linear in the force, so a run
        to steady state with a trial force (plane Poiseuille flow between the
        walls, 8 eta u / H^2, times 1.5 for the side walls) scales it, and a
        second run checks it (inertia at Reynolds numbers near 1 bends the
        line a little). Returns the force and the speed reached."""
        force = 1.5 * 8.0 * visc * dens * target / H**2
        for attempt in range(3):
            lbf.ext_force_density = [force, 0.0, 0.0]
            reached = settle()
            if abs(reached - target) < 2e-3 * target or attempt == 2:
                return force, reached
            force *= target / reached


    target_speed = UNITS.to_lattice(speed, "m/s")
    if args.force is None:
        force, reached = drive_flow(target_speed)
    else:  # as given: the fluid starts at rest
        force, reached = args.force, float("nan")
    lbf.ext_force_density = [force, 0.0, 0.0]
    args.force = force  # (the test scenes read it back)


    def lower_flow_share():
        """The lower branch's share of the flow through the branches' middle
        plane (x = 80 um): what a cell following the fluid would choose."""
        i = int((0.5 * (split + join)) / agrid)
        ux = lbf[i:i + 1, :, :].velocity[0, :, :, 0]
        lower = (np.arange(ux.shape[0]) + 0.5) * agrid < island_middle
        return float(ux[lower].sum() / ux.sum()) if ux.sum() > 0 else float("nan")


    flow_share = lower_flow_share() if math.isfinite(reached) else float("nan")

    # --- cells
    rbc_moduli = plan.moduli  # the paper's RBC x stiffness (oif_moduli_from_si)
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(L(RBC_RADIUS),) * 3, normal=True,
                          **rbc_moduli)
    types, counts, ptypes = [rbc], [n_rbc - n_stiff], [0]
    if n_stiff:  # the same mesh and size: seeded in the sequence of a uniform run, the last n_stiff are stiff
        stiff_moduli = dict(rbc_moduli)
        for k in ("ks", "kb", "kal"):
            stiff_moduli[k] *= min(STIFF_RBC, STIFFEST_RBC / stiffness)
        stiff_type = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(L(RBC_RADIUS),) * 3,
                                     normal=True, **stiff_moduli)
        types.append(stiff_type)
        counts.append(n_stiff)
        ptypes.append(2)
    if rare:
        rare_moduli = dict(rbc_moduli)
        for k in ("ks", "kb", "kal", "kag"):
            rare_moduli[k] *= min(RARE_STIFFNESS, STIFFEST / stiffness)
        rare_type = oif.OifCellType(*oif.mesh_files("sphere642"), system=system, resize=(L(size["rare_radius"]),) * 3,
                                    normal=True, **rare_moduli)
        types.append(rare_type)
        counts.append(1)
        ptypes.append(1)
    # at random in the parent channel (just upstream of the split; more than 12
    # cells need the whole parent channel, i.e. also the outlet, which leads
    # into the inlet)
    region = ([split - 30.0, parent[0], 1.0], [split - 3.0, parent[1], H + 1.0])
    seeding_boundaries = boundaries
    if n_rbc > 12:
        region = ([0.0, parent[0], 1.0], [L_X, parent[1], H + 1.0])
        seeding_boundaries = boundaries + [shapes.Rhomboid(corner=[split - 3.0, 0.0, 0.0], a=[join - split + 6.0, 0, 0],
                                                           b=[0, L_Y, 0], c=[0, 0, H_BOX])]  # not in the branches
    if n_rbc > 40:  # the paper's 60 do not fit there at random: the branches too (not counted as entries)
        region = ([0.0, 0.0, 1.0], [L_X, L_Y, H + 1.0])
        seeding_boundaries = boundaries
    # the coupling's friction per node (suggest_LBgamma), and the node mass at
    # gamma dt / m = 0.3 (the plan's, per MD step with --substeps): the
    # friction relaxes a node's velocity to the fluid's within a few steps.
    # With heavier nodes (gamma dt / m 0.04-0.18; mass 1 here gives 0.15) the
    # membranes of cells jammed at the island's apex folded through
    # themselves within a few ms at every stiffness tried, as the RBC in shear
    # flow did (doc/validation.md); the physical mass of a node, 27 pg / 374 =
    # 0.07 in these units, is lighter still and needs no other change
    gamma = plan.gamma
    node_mass = plan.node_mass * time_step / plan.time_step
    seeding = dict(counts=counts, boundaries=seeding_boundaries, region=region, particle_types=ptypes,
                   seed=args.seed, particle_mass=node_mass)
    if getattr(args, "haematocrit", None) is not None:  # dense: packed (doc/oif.md, "Packing")
        # the cells apart by the contacts' offset and twice their guard gap at
        # this stiffness, time step and node mass: the run's contacts start in range
        clearance = oif.contacts.packing_clearance(types, scale=stiffness, time_step=time_step, node_mass=node_mass)
        cells = oif.pack_cells(system, types, counts=counts, boundaries=boundaries,
                               region=([0.0, 0.0, 1.0], [L_X, L_Y, H + 1.0]), particle_types=ptypes, seed=args.seed,
                               particle_mass=node_mass, clearance=clearance,
                               rotation_axis=(0, 0, 1) if args.orientation == "flat" else None)
        r = cells.report
        print(f"packed {len(cells)} cells to haematocrit {r['haematocrit']:.3f} of the channel in "
              f"{r['seconds']:.1f} s ({r['method']}; nodes inside other cells: {r['nodes_inside_cells']}, closest "
              f"nodes of two cells {r['min_node_distance']:.3f} um, of a cell and a wall {r['min_wall_distance']:.3f} "
              f"um)")
    elif args.orientation == "flat":
        cells = oif.seed_cells(system, types, rotation_axis=(0, 0, 1), **seeding)
    else:
        try:
            cells = oif.seed_cells(system, types, **seeding)
        except oif.SeedingError as random_failed:
            if args.orientation == "random":
                raise
            # e.g. the paper's 100 RBCs of its Fig 5 in the 20 um channel: random
            # orientations jam at about 77; discs parallel to the walls fit
            cells = oif.seed_cells(system, types, rotation_axis=(0, 0, 1), **seeding)
            print(f"note: {n_rbc} randomly oriented cells did not fit ({random_failed}); seeded them lying "
                f"flat between the walls instead (--orientation flat)")
    system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
    oif.set_contacts(system, types, particle_types=ptypes, wall_types=10, scale=stiffness)
else:
    system, lbf, cells = resumed.system, resumed.lbf, resumed.cells
    force, reached, flow_share = (resumed.state[k] for k in ("force", "reached", "flow_share"))

# --- output schedule
steps_per_output = args.steps or max(1, int(round(UNITS.to_lattice(
    (args.output_every * 1e-6 if args.output_every else size["output_every"]), "s") / time_step)))
n_outputs = args.cycles if args.cycles is not None else max(1, int(round(
    UNITS.to_lattice(duration, "s") / time_step / steps_per_output)))
total_steps = n_outputs * steps_per_output

rank0 = lbmd.rank == 0
say = print if rank0 else (lambda *a, **k: None)
to_ms = lambda t: UNITS.to_si(t, "s") * 1e3  # noqa: E731
to_mm_s = lambda v: UNITS.to_si(v, "m/s") * 1e3  # noqa: E731
driving = (f"centre-line speed {speed * 1e3:.3g} mm/s (reached {to_mm_s(reached):.4g} mm/s before the cells "
           f"came, body force {force:.4g})" if math.isfinite(reached)
           else f"body force {force:.4g} as given")
if resumed is not None:
    say(f"resumed from {checkpoint_path} at {to_ms(system.time - resumed.state['time0']):.4g} ms of flow "
        f"(step {system.step_count})")
say(f"{size_name} scene, case {args.case}: {n_rbc} RBCs{f' ({n_stiff} stiff)' if n_stiff else ''}"
    f"{' + rare cell' if rare else ''}, branches "
    f"{w_low:g}/{w_up:g} um, height {H:g} um; {driving}, membranes {stiffness:.3g}x the paper's moduli; "
    f"{to_ms(total_steps * time_step):g} ms of flow = {total_steps} steps, output every "
    f"{to_ms(steps_per_output * time_step) * 1e3:g} us")

# --- per-cell bookkeeping: rotation, passes round the periodic channel, branches
if resumed is None:
    for c in cells:  # the rotation angle of the node furthest downstream, about the centre
        c.set_rotation(ids=[int(np.argmax(c.mesh.positions()[:, 0]))])
    volume0 = np.array([c.volume() for c in cells])
    surface0 = np.array([c.surface() for c in cells])
    centre_previous = np.array([c.get_origin() for c in cells])
    entered = {}          # (cell, pass) -> branch ("seeded": placed in a branch at the start, not an entry)
    drift = {"volume": 0.0, "surface": 0.0}  # largest relative change of a cell's, over the outputs
    time0 = system.time   # the cells are released now (the calibration run came before)
    release_step = system.step_count
    outputs_done = 0
    for k, c in enumerate(cells):
        x0, y0, _ = np.mod(c.get_origin(), system.box_l)
        if split <= x0 < join:
            entered[k, int(math.floor(c.get_origin()[0] / L_X))] = "seeded"
else:
    globals().update({k: resumed.state[k] for k in ("volume0", "surface0", "centre_previous", "entered", "drift",
                                                    "time0", "release_step", "outputs_done")})


def region_of(x, y):
    if split <= x < join:
        return "lower" if y < island_middle else "upper"
    return "parent"


# the fluid volume of each region, from the boundary flags (node centres)
flags = lbf[:, :, :].boundary
node_x = (np.arange(flags.shape[0]) + 0.5) * agrid
node_y = (np.arange(flags.shape[1]) + 0.5) * agrid
fluid_columns = (flags == 0).sum(axis=2) * agrid**3
in_branches = (node_x >= split) & (node_x < join)
fluid_volume = {"parent": fluid_columns[~in_branches].sum(),
                "lower": fluid_columns[np.ix_(in_branches, node_y < island_middle)].sum(),
                "upper": fluid_columns[np.ix_(in_branches, node_y >= island_middle)].sum()}


class Table:
    """A CSV file written by rank 0 as the run goes (flushed every output:
    a run that dies keeps its rows). Resumed: the rows up to the
    checkpoint's output are kept, later ones (of a run that went on after
    it) cut off."""

    def __init__(self, name, header):
        self.name = name
        path = os.path.join(args.output, name) if rank0 else os.devnull
        if resumed is not None and rank0:
            self.file = open(path, "r+", newline="")
            self.file.truncate(resumed.state["offsets"][name])
            self.file.seek(0, os.SEEK_END)
            self.writer = csv.writer(self.file)
            return
        self.file = open(path, "w", newline="")
        self.writer = csv.writer(self.file)
        self.writer.writerow(header)

    def row(self, *values):
        self.writer.writerow([f"{v:.4f}" if isinstance(v, float) else v for v in values])

    def length(self):
        """Bytes written (the checkpoint keeps it)."""
        return self.file.tell() if not self.file.closed else self.closed_length

    def close(self):
        self.closed_length = self.file.tell()
        self.file.close()


os.makedirs(args.output, exist_ok=True)
# the scene, for plot_bifurcation.py (which combines runs of one case)
resumed is None and file_output.write_text(os.path.join(args.output, "scene.json"), json.dumps(dict(
    size=size_name, case=args.case, seed=args.seed, rbcs=n_rbc, rare=rare, stiff_rbcs=n_stiff,
    stiff_factor=min(STIFF_RBC, STIFFEST_RBC / stiffness) if n_stiff else None, channel_length_um=L_X,
    box_width_um=L_Y, height_um=H, parent_um=parent, split_um=split, join_um=join, island_um=island,
    branch_widths_um=(w_low, w_up), planes_um=[L(p) for p in PLANES], speed_mm_s=speed * 1e3,
    stiffness=stiffness, force=force, time_step_us=time_step, steps_per_output=steps_per_output,
    outputs=n_outputs, lower_flow_share=flow_share,
    fluid_volume_um3={k: float(v) for k, v in fluid_volume.items()}), indent=1) + "\n")
tables = dict(
    cells=Table("cells.csv", ["time_ms", "cell", "type", "x_um", "y_um", "z_um", "vx_mm_s", "vy_mm_s", "vz_mm_s",
                              "surface_um2", "volume_um3", "diameter_um", "rotation_deg", "pass",
                              "deformation_index", "max_edge_strain", "max_area_strain", "damage_time_ms",
                              "peak_area_strain"]),
    branches=Table("branches.csv", ["cell", "type", "pass", "branch", "time_ms"]),
    crossings=Table("crossings.csv", ["time_ms", "cell", "type", "plane_x_um", "y_um", "z_um", "pass"]),
    haematocrit=Table("haematocrit.csv", ["time_ms", "parent", "lower", "upper"]
                      + (["parent_stiff", "lower_stiff", "upper_stiff"] if n_stiff else [])))
if args.vtk and resumed is not None and resumed.state["vtk"] is not None:
    cell_series, fluid_series = resumed.state["vtk"]  # the .pvd files go on
elif args.vtk:
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
    cell_series = oif.CellSeries(os.path.join(args.output, "cells.pvd"))
    fluid_series = lbmd.vtk_output.FluidSeries(os.path.join(args.output, "fluid.pvd"), lbf,
                                               slice=("z", int(round(0.5 * H_BOX - 0.5))))


def record():
    """One output: every cell's row, branch entries, plane crossings since the
    last output (interpolated), the haematocrit; collective under MPI."""
    t = to_ms(system.time - time0)
    cell_volume = {"parent": 0.0, "lower": 0.0, "upper": 0.0}
    stiff_volume = {"parent": 0.0, "lower": 0.0, "upper": 0.0}  # the stiff population's share
    oif.update_damage(cells, system.time)  # each cell's time above 30 % local area strain (doc/oif.md)
    for k, c in enumerate(cells):
        centre = c.get_origin()
        x, y, z = np.mod(centre, system.box_l)
        lap = int(math.floor(centre[0] / L_X))
        velocity = c.get_velocity()
        volume, surface = c.volume(), c.surface()
        drift["volume"] = max(drift["volume"], abs(volume / volume0[k] - 1.0))
        drift["surface"] = max(drift["surface"], abs(surface / surface0[k] - 1.0))
        cell_volume[region_of(x, y)] += volume
        if c.particle_type == 2:
            stiff_volume[region_of(x, y)] += volume
        tables["cells"].row(t, k, c.particle_type, float(x), float(y), float(z),
                            *(float(to_mm_s(v)) for v in velocity), float(surface), float(volume),
                            float(c.diameter()), float(math.degrees(c.get_rotation_angles()[0])), lap,
                            c.deformation_index(), c.max_edge_strain(), c.max_area_strain(),
                            float(to_ms(c.damage.time_above)), c.damage.peak_strain)
        if split + 8.0 < x < join and (k, lap) not in entered:
            entered[k, lap] = region_of(x, y)
            tables["branches"].row(k, c.particle_type, lap, entered[k, lap], t)
        before = centre_previous[k]
        for plane in (L(p) for p in PLANES):  # crossings of x = plane + n L_X, n integer
            for n in range(math.ceil((before[0] - plane) / L_X), math.floor((centre[0] - plane) / L_X) + 1):
                if before[0] < plane + n * L_X <= centre[0]:  # linear between the outputs
                    w = (plane + n * L_X - before[0]) / (centre[0] - before[0])
                    at = np.mod(before + w * (centre - before), system.box_l)
                    tables["crossings"].row(t, k, c.particle_type, plane, float(at[1]), float(at[2]), n)
        centre_previous[k] = centre
    regions = ("parent", "lower", "upper")
    tables["haematocrit"].row(t, *(f"{cell_volume[r] / fluid_volume[r]:.6f}" for r in regions),
                              *((f"{stiff_volume[r] / fluid_volume[r]:.6f}" for r in regions) if n_stiff else ()))
    for table in tables.values():
        table.file.flush()
    if args.vtk:
        cell_series.write(cells, system.time)
        fluid_series.write(system.time)


def progress_note():
    """Beside the progress bar's steps, steps/s and time left: the simulated
    time and the branch entries so far."""
    lower = sum(v == "lower" for v in entered.values())
    upper = sum(v == "upper" for v in entered.values())
    return f"{to_ms(system.time - time0):.3f} ms of {to_ms(total_steps * time_step):g}, entries lower {lower} upper {upper}"


# --- run
def sample_state():
    """What this script needs beside the engine's objects to go on from a
    checkpoint (its bookkeeping and the CSV files' lengths)."""
    return dict(args=args, force=force, reached=reached, flow_share=flow_share, volume0=volume0,
                surface0=surface0, centre_previous=centre_previous, entered=entered, drift=drift, time0=time0,
                release_step=release_step, outputs_done=outputs_done,
                offsets={t.name: t.length() for t in tables.values()},
                vtk=(cell_series, fluid_series) if args.vtk else None)


def checkpoint_objects():
    return dict(lbf=lbf, cells=cells, state=sample_state())


# a walltime signal (SIGTERM, SIGUSR1) writes a checkpoint and exits with
# status 75; --resume goes on from it
lbmd.checkpoint.stop_on_signal(checkpoint_path, system, checkpoint_objects)
every = args.checkpoint_every if args.checkpoint_every is not None else (10.0 if size_name == "full" else None)
steps_per_checkpoint = (max(1, int(round(UNITS.to_lattice(every * 1e-3, "s") / time_step / steps_per_output)))
                        * steps_per_output if every else None)
system.integrator.reset_timings()  # the report below covers the cells' run, not the calibration


def picture(name):
    """The device and its cells seen from above (the cells projected on the
    mid-height plane's walls): a PNG in the output folder; collective."""
    if args.no_plots:
        return
    import lbmd.visualization
    path = os.path.join(args.output, name)
    fig = lbmd.visualization.cells(system, cells, mode="projected", units=UNITS, ids=False, save=path)
    import matplotlib.pyplot as plt
    plt.close(fig)
    say(f"picture: {path}")


if resumed is None:
    record()
    picture("scene_start.png")
progress = lbmd.progress.Bar(total_steps, initial=outputs_done * steps_per_output, mode=args.progress)
for i in range(outputs_done + 1, n_outputs + 1):
    # up to the output's step (a run resumed from a walltime checkpoint
    # does the rest of the interval the signal cut)
    system.integrator.run(release_step + i * steps_per_output - system.step_count)
    record()
    outputs_done = i
    progress.update(steps_per_output, postfix=progress_note())
    if steps_per_checkpoint and (i * steps_per_output) % steps_per_checkpoint == 0 and i < n_outputs:
        lbmd.checkpoint.save(checkpoint_path, system, **checkpoint_objects())
progress.close()
for table in tables.values():
    table.close()
picture("scene_end.png")

# --- results
counts = {b: sum(v == b for v in entered.values()) for b in ("lower", "upper")}
n = counts["lower"] + counts["upper"]
if n < 10:
    say(f"branch entries: lower {counts['lower']}, upper {counts['upper']}: too few cells passed the "
        f"bifurcation to give a share (run longer: --duration)")
else:
    p = counts["lower"] / n
    error = math.sqrt(p * (1.0 - p) / n)  # binomial standard error, entries taken as independent
    say(f"share of the {n} branch entries: lower (width {w_low:g} um) {p:.2f} +- {error:.2f}, "
        f"upper (width {w_up:g} um) {1 - p:.2f} +- {error:.2f}"
        + (f"; share of the flow: lower {flow_share:.2f}" if math.isfinite(flow_share) else ""))
say(f"largest change of a cell's volume during the run {100 * drift['volume']:.2f} %, of its surface "
    f"{100 * drift['surface']:.2f} %")
# where the time went (wall clock by phase of the step), as after a LAMMPS run
say(system.integrator.timing_report())
if rank0 and not args.no_plots:
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "analysis"))
    import plot_bifurcation
    figures = plot_bifurcation.make_figures([args.output], args.output)
    say("figures: " + ", ".join(os.path.basename(f) for f in figures))
say(f"output in {os.path.abspath(args.output)}/: cells.csv, branches.csv, crossings.csv, haematocrit.csv"
    + ("" if args.no_plots else ", scene_start.png, scene_end.png")
    + (", walls.vtp, cells.pvd, fluid.pvd (ParaView)" if args.vtk else ""))
