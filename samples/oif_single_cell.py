#!/usr/bin/env pyoif
"""One red blood cell in a channel flow (lattice-Boltzmann fluid between two
walls, driven by a body force), with VTK output for ParaView.

    pyoif samples/oif_single_cell.py --output out_single [--cycles 10] [--steps 200]

Writes <output>/wall_bottom.vtk, wall_top.vtk, cell_<i>.vtk (the membrane
with per-node velocity and force) and fluid_<i>.vtk (if the fluid can write
VTK), and prints the cell's centre, velocity, volume and surface.

Every number comes from SI inputs through oif.scene_parameters (printed at
the start with its reasons): a channel 18 um high, plasma at a real mean
speed of 1 mm/s, the PyOIF paper's red cell (radius 3.91 um). The plan runs
the flow 27 times faster with the membranes 27 times stiffer (the same
capillary number); the engine's units are the paper's (1 um, 1 us, 1e-15 kg):
agrid 1 um, time step 0.1 us.
"""
import argparse
import os
from types import SimpleNamespace

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--output", default="output_single_cell", help="folder for the VTK files")
parser.add_argument("--cycles", type=int, default=10, help="number of output cycles")
parser.add_argument("--steps", type=int, default=200, help="MD steps per cycle")
parser.add_argument("--mesh", default="rbc374", help="shipped mesh name (see oif.available_meshes())")
args = parser.parse_args()
os.makedirs(args.output, exist_ok=True)

HEIGHT = 18e-6  # m, between the walls
plan = oif.scene_parameters(narrowest=HEIGHT, mean_speed=1e-3, mesh=args.mesh)
print(plan)
box = plan.box([40e-6, 20e-6, HEIGHT + 2e-6])  # channel: periodic in x and y, walls at z = 1 and z = 19
system = lbmd.System(box_l=box)
system.time_step = plan.time_step
system.cell_system.skin = 0.2

# cell type: the Evans-Fung RBC, the paper's moduli times the plan's speed-up
rbc = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize, normal=True, **plan.moduli)
cell = oif.OifCell(cell_type=rbc, particle_type=0, origin=[10.0, 10.0, 8.0], rotate=(np.pi / 2, 0.0, 0.0),
                   particle_mass=plan.node_mass)
rbc.print_info()
cell.print_info()

# fluid: plasma, driven by the body force of the plan's mean speed between the walls
lbf = lb.LBFluid(**plan.fluid, ext_force_density=[plan.slit_force(HEIGHT), 0.0, 0.0])
system.actors.add(lbf)
system.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)

# walls: the same shapes are fluid boundaries and particle constraints
walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(box[2] - 1.0))]
for w in walls:
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
    system.constraints.add(shape=w, particle_type=10, penetrable=False)
# for ParaView: the walls as 1-thick slabs (output_vtk_rhomboid reads corner, a, b, c)
for name, z in (("bottom", 0.0), ("top", box[2] - 1.0)):
    slab = SimpleNamespace(corner=[0.0, 0.0, z], a=[box[0], 0, 0], b=[0, box[1], 0], c=[0, 0, 1.0])
    oif.output_vtk_rhomboid(slab, os.path.join(args.output, f"wall_{name}.vtk"))
# node-wall contact: the advised hard_contact (diverges as the gap closes)
oif.set_contacts(system, rbc, particle_types=0, wall_types=10, scale=plan.contact_scale)

print("cycle  time     centre                 velocity_x   volume     surface")
for i in range(args.cycles + 1):
    if i > 0:
        system.integrator.run(args.steps)
    cell.output_vtk_pos_folded(os.path.join(args.output, f"cell_{i}.vtk"),
                               point_data={"velocity": cell.particles.v, "force": cell.particles.f})
    if hasattr(lbf, "write_vtk_velocity") and i == args.cycles:
        lbf.write_vtk_velocity(os.path.join(args.output, f"fluid_{i}.vtk"))
    c = cell.get_origin()
    print(f"{i:5d} {system.time:7.1f}  [{c[0]:6.2f} {c[1]:6.2f} {c[2]:6.2f}]  {cell.get_velocity()[0]:10.3e}"
          f"  {cell.volume():8.3f}  {cell.surface():8.3f}")
print(f"done: VTK files in {args.output}/ (open cell_*.vtk as a series in ParaView)")
