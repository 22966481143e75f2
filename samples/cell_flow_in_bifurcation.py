#!/usr/bin/env pyoif
"""Red blood cells (and optionally one stiff "rare" cell) flowing through a
channel that bifurcates into two daughter branches and joins again -- the
scene of the PyOIF paper's study (its Figs 2-5), on a smaller scale by default.

    pyoif samples/cell_flow_in_bifurcation.py [--case A|B|C] [--cells N] [--rare]
          [--cycles 20] [--steps 500] [--output DIR] [--vtk] [--seed S] [--full]

Geometry (lattice units = um, agrid 1): periodic in x; walls at z = 0..1 and
z = H-1..H (channel height 20 in the paper, --height); the parent channel
(width 30) splits at x = 50 into a lower branch and an upper branch of widths
10/20 (case A), 12/18 (B), 15/15 (C) around an island, and joins again at
x = 110. Cells: Evans-Fung RBCs of radius 3.91 with 374 nodes and the paper's
moduli (ks 0.005, kb 0.02, kal 0.007, kag 0.7, kv 0.9); the rare cell a sphere
of radius 7.5 (--full) with 642 nodes, 10x stiffer. Seeded at random in the
parent channel just upstream of the split (oif.seed_cells). Default: 6 RBCs,
channel height 14, 10 cycles of 500 steps (about 25 s on one core); --full:
the paper's 40 RBCs, height 20, the rare cell and 200 cycles.

Output in DIR: cells.csv (time, cell, type, x, y, z, surface, volume,
diameter per cycle), branches.csv (which branch each cell entered), and with
--vtk the membranes (legacy VTK, every cycle) and the walls as the fluid
sees them (walls.vtp, VTK XML) for ParaView. At the end the share
of cells that entered each branch is printed (the paper's Fig 3 quantity).

The corners that face the flow (the island's, and where the parent channel
widens into the branches and narrows again) are rounded with radius 2: a
membrane driven onto a sharp corner wraps around it until a node is pushed
through the wall. The default driving force (7e-3) keeps a margin there: at
1e-2 a cell pressed onto the island's corner pushed a node through the wall
for some seeds, and which seeds depended on round-off (a change of the
floating-point operation order in the membrane forces moved it).
"""
import argparse
import csv
import os

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

CASES = {"A": (10.0, 20.0), "B": (12.0, 18.0), "C": (15.0, 15.0)}

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--case", choices=sorted(CASES), default="A")
ap.add_argument("--cells", type=int, default=None, help="number of RBCs (default 6, --full 40)")
ap.add_argument("--rare", action="store_true", help="add the stiff rare cell")
ap.add_argument("--full", action="store_true", help="the paper's sizes (slow: hours)")
ap.add_argument("--height", type=float, default=None, help="channel height (default 14, --full 20)")
ap.add_argument("--cycles", type=int, default=None, help="output cycles (default 10, --full 200)")
ap.add_argument("--steps", type=int, default=500, help="MD steps per cycle (time step 0.1 us)")
ap.add_argument("--output", default="output_bifurcation")
ap.add_argument("--vtk", action="store_true", help="write VTK of the membranes every cycle")
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--force", type=float, default=7e-3,
                help="body force density driving the flow (default: centre speed ~0.035 um/us so that cells "
                     "reach the branches within the default run; the paper's 1.3e-3 um/us is ~27x slower)")
args = ap.parse_args()
n_rbc = args.cells if args.cells is not None else (40 if args.full else 6)
n_cycles = args.cycles if args.cycles is not None else (200 if args.full else 10)
height = args.height or (20.0 if args.full else 14.0)
rare = args.rare or args.full
os.makedirs(args.output, exist_ok=True)

L_X, L_Y = 160.0, 40.0
PARENT = (5.0, 35.0)                      # parent channel y range (width 30)
SPLIT, JOIN = 50.0, 110.0                 # x of the bifurcation and of the confluence
w_low, w_up = CASES[args.case]
system = lbmd.System(box_l=[L_X, L_Y, height + 2.0])
system.time_step = 0.1
system.cell_system.skin = 0.3

# --- geometry: blocks (fluid outside) extruded over the box height, and two walls
H_BOX = height + 2.0
R_CORNER = 2.0


def block(x0, x1, y0, y1, rounded=()):
    """Rectangle [x0, x1] x [y0, y1] over the box height, its corners named in
    `rounded` ('ll', 'lr', 'ul', 'ur': lower/upper, left/right) rounded with
    radius R_CORNER: a union of two overlapping bars, a square at each sharp
    corner and a cylinder at each rounded one."""
    r = R_CORNER
    box = lambda a0, a1, b0, b1: shapes.Rhomboid(corner=[a0, b0, 0.0], a=[a1 - a0, 0, 0], b=[0, b1 - b0, 0],
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


island = (1.0 + w_low, L_Y - 1.0 - w_up)
blocks = [
    block(0.0, SPLIT, 0.0, PARENT[0], rounded=("ur",)),          # parent, below
    block(0.0, SPLIT, PARENT[1], L_Y, rounded=("lr",)),          # parent, above
    block(JOIN, L_X, 0.0, PARENT[0], rounded=("ul",)),           # outlet, below
    block(JOIN, L_X, PARENT[1], L_Y, rounded=("ll",)),           # outlet, above
    shapes.Rhomboid(corner=[SPLIT - 1.0, 0.0, 0.0], a=[JOIN - SPLIT + 2.0, 0, 0], b=[0, 1.0, 0],
                    c=[0, 0, H_BOX]),                            # branch outer walls
    shapes.Rhomboid(corner=[SPLIT - 1.0, L_Y - 1.0, 0.0], a=[JOIN - SPLIT + 2.0, 0, 0], b=[0, 1.0, 0],
                    c=[0, 0, H_BOX]),
    block(SPLIT, JOIN, island[0], island[1], rounded=("ll", "lr", "ul", "ur")),  # island
]
boundaries = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(height + 1.0))]
boundaries += blocks

# --- cells
rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.91, 3.91, 3.91),
                      ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9, normal=True)
types, counts, ptypes = [rbc], [n_rbc], [0]
if rare:
    r_rare = 7.5 if args.full else 4.5
    rare_type = oif.OifCellType(*oif.mesh_files("sphere642"), system=system, resize=(r_rare,) * 3,
                                ks=0.05, kb=0.2, kal=0.07, kag=0.7, kv=0.9, normal=True)
    types.append(rare_type)
    counts.append(1)
    ptypes.append(1)
# just upstream of the split; the paper's 40 RBCs need the whole channel
# upstream, i.e. also the outlet, which leads into the inlet (periodic in x)
region = ([SPLIT - 30.0, PARENT[0], 1.0], [SPLIT - 3.0, PARENT[1], height + 1.0])
seeding_boundaries = boundaries
if n_rbc > 12:
    region = ([0.0, PARENT[0], 1.0], [L_X, PARENT[1], height + 1.0])
    seeding_boundaries = boundaries + [shapes.Rhomboid(corner=[SPLIT - 3.0, 0.0, 0.0], a=[JOIN - SPLIT + 6.0, 0, 0],
                                                       b=[0, L_Y, 0], c=[0, 0, H_BOX])]  # not in the branches
cells = oif.seed_cells(system, types, counts=counts, boundaries=seeding_boundaries, region=region,
                       particle_types=ptypes, seed=args.seed)
print(f"case {args.case}: {n_rbc} RBCs{' + rare cell' if rare else ''}, branches {w_low}/{w_up}, "
      f"height {height}")

# --- fluid, coupling, contacts
lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[args.force, 0.0, 0.0])
system.actors.add(lbf)
for b in boundaries:
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=b))
    system.constraints.add(shape=b, particle_type=10, penetrable=False)
if args.vtk:  # for ParaView: the walls as the fluid sees them (rounded corners included)
    lbmd.vtk_output.write_wall_surface(os.path.join(args.output, "walls.vtp"), lbf)
system.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=1.5, dens=1.0))
for t in set(ptypes):
    # node-wall repulsion strong enough for cells driven onto the island's corners
    system.non_bonded_inter[t, 10].soft_sphere.set_params(a=0.02, n=1.5, cutoff=1.0, offset=0.0)
    for u in set(ptypes):
        if u >= t:
            system.non_bonded_inter[t, u].membrane_collision.set_params(a=0.01, n=4.0, cutoff=0.8, offset=0.0)

# --- run
branch = {}  # cell index -> "lower"/"upper", decided when the centre is inside the branches
# under mpirun every rank runs this loop (the cells' queries are collective),
# rank 0 writes the tables
def writer_path(name):
    return os.path.join(args.output, name) if lbmd.rank == 0 else os.devnull


with open(writer_path("cells.csv"), "w", newline="") as f:
    out = csv.writer(f)
    out.writerow(["time", "cell", "type", "x", "y", "z", "surface", "volume", "diameter"])
    for i in range(n_cycles + 1):
        if i:
            system.integrator.run(args.steps)
        for k, c in enumerate(cells):
            x, y, z = c.get_origin_folded()
            out.writerow([f"{system.time:.1f}", k, c.particle_type, f"{x:.3f}", f"{y:.3f}", f"{z:.3f}",
                          f"{c.surface():.3f}", f"{c.volume():.3f}", f"{c.diameter():.3f}"])
            if SPLIT + 8.0 < x < JOIN and k not in branch:
                branch[k] = "lower" if y < 1.0 + w_low + 0.5 * (L_Y - 2.0 - w_low - w_up) else "upper"
            if args.vtk:
                c.output_vtk_pos_folded(os.path.join(args.output, f"cell{k}_{i}.vtk"))
        f.flush()
        print(f"cycle {i:3d}  time {system.time:8.1f} us  cells in branches: "
              f"lower {sum(v == 'lower' for v in branch.values())}, upper {sum(v == 'upper' for v in branch.values())}")
with open(writer_path("branches.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["cell", "type", "branch"])
    for k, v in sorted(branch.items()):
        w.writerow([k, cells[k].particle_type, v])
n = max(len(branch), 1)
print(f"share of cells entering the lower (width {w_low}) / upper (width {w_up}) branch: "
      f"{sum(v == 'lower' for v in branch.values()) / n:.2f} / {sum(v == 'upper' for v in branch.values()) / n:.2f}"
      f" ({len(branch)} cells)")
# where the time went (wall clock by phase of the step), as after a LAMMPS run
print(system.integrator.timing_report())
print(f"output in {os.path.abspath(args.output)}/: cells.csv, branches.csv" + (", VTK files" if args.vtk else ""))
