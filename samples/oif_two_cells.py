#!/usr/bin/env pyoif
"""Two red blood cells in a channel flow past a cylindrical obstacle, with
cell-cell membrane collision, cell-wall repulsion and VTK output.

    pyoif samples/oif_two_cells.py --output out_two [--cycles 10] [--steps 200]

Both cells use one particle type: the membrane collision acts between
different cells through their cell ids (mol_id), so many cells need no
type each. Output: <output>/cell0_<i>.vtk, cell1_<i>.vtk, walls and the
obstacle as VTK, and per cycle the cells' centres, the smallest node distance
between them, and their volumes.

Every number comes from SI inputs through oif.scene_parameters (printed at
the start with its reasons): a channel 14 um high, plasma at a real mean
speed of 1 mm/s, the PyOIF paper's red cell, run 27 times faster with the
membranes 27 times stiffer (the same capillary number).
"""
import argparse
import os
from types import SimpleNamespace

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--output", default="output_two_cells", help="folder for the VTK files")
parser.add_argument("--cycles", type=int, default=10, help="number of output cycles")
parser.add_argument("--steps", type=int, default=200, help="MD steps per cycle")
args = parser.parse_args()
os.makedirs(args.output, exist_ok=True)

HEIGHT = 14e-6  # m, between the walls
plan = oif.scene_parameters(narrowest=HEIGHT, mean_speed=1e-3)
print(plan)
box = plan.box([48e-6, 24e-6, HEIGHT + 2e-6])
system = lbmd.System(box_l=box)
system.time_step = plan.time_step
system.cell_system.skin = 0.3

rbc = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize, normal=True, **plan.moduli)
starts = (([8.0, 9.0, 8.0], (np.pi / 2, 0.0, 0.0)), ([16.0, 14.5, 8.0], (np.pi / 2, 0.0, 0.3)))  # origin, rotation
cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=origin, rotate=rotate, particle_mass=plan.node_mass)
         for origin, rotate in starts]

# plasma driven by the body force of the plan's mean speed between the walls
# (the obstacle slows it a little)
lbf = lb.LBFluid(**plan.fluid, ext_force_density=[plan.slit_force(HEIGHT), 0.0, 0.0])
system.actors.add(lbf)
system.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)

walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(box[2] - 1.0))]
boundaries = list(walls)
have_cylinder = hasattr(shapes, "Cylinder")
if have_cylinder:
    obstacle = shapes.Cylinder(center=[30.0, 12.0, 8.0], axis=[0, 0, 1], radius=3.0, length=box[2], direction=1)
    boundaries.append(obstacle)
    oif.output_vtk_cylinder(obstacle, n=32, out_file=os.path.join(args.output, "obstacle.vtk"))
for b in boundaries:
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=b))
    system.constraints.add(shape=b, particle_type=10, penetrable=False)
for name, z in (("bottom", 0.0), ("top", box[2] - 1.0)):
    slab = SimpleNamespace(corner=[0.0, 0.0, z], a=[box[0], 0, 0], b=[0, box[1], 0], c=[0, 0, 1.0])
    oif.output_vtk_rhomboid(slab, os.path.join(args.output, f"wall_{name}.vtk"))

# contacts: the advised hard_contact between the cells and with the walls
# (a repulsion that diverges as the gap closes: doc/interactions.md)
oif.set_contacts(system, rbc, particle_types=0, wall_types=10, scale=plan.contact_scale)

print("cycle   time    centre0 x,y,z          centre1 x,y,z         min distance  volumes")
for i in range(args.cycles + 1):
    if i > 0:
        system.integrator.run(args.steps)
    for k, c in enumerate(cells):
        c.output_vtk_pos_folded(os.path.join(args.output, f"cell{k}_{i}.vtk"))
    p0, p1 = (c.mesh.positions() for c in cells)
    dmin = np.sqrt(np.min(np.sum((p0[:, None] - p1[None]) ** 2, axis=2)))
    c0, c1 = (c.get_origin() for c in cells)
    print(f"{i:5d} {system.time:7.1f}  {np.array2string(c0, precision=2)}  {np.array2string(c1, precision=2)}"
          f"  {dmin:8.3f}  {cells[0].volume():.2f} {cells[1].volume():.2f}")
print(f"done: VTK files in {args.output}/")
