#!/usr/bin/env pyoif
"""Writes doc/tutorials/bifurcation.ipynb from the cells below and executes
it (nbclient, kernel "python3" with this process's PYTHONPATH), so that the
notebook is stored with its pictures:

    build/pyoif doc/tutorials/make_bifurcation_notebook.py
"""
import os
import sys
import time

import nbformat
from nbclient import NotebookClient

md, code = nbformat.v4.new_markdown_cell, nbformat.v4.new_code_cell
cells = [
    md("# Cells through a bifurcation, step by step\n\n"
       "The scene of `samples/cell_flow_in_bifurcation.py` (the PyOIF paper's bifurcating channel), built one "
       "step at a time at a small size, with a picture after each step (`lbmd.visualization`). Open it with "
       "`build/pyoif notebook` (or the kernel \"PyOIF\"); the whole notebook runs in well under a minute on "
       "one core. Lengths in um, times in us, masses in 1e-15 kg (the engine's units here, "
       "`lbmd.units.UnitSystem()`)."),
    code("%matplotlib inline\n"
         "import numpy as np\n"
         "import lbmd, oif\n"
         "from lbmd import lb, lbboundaries, shapes\n"
         "from lbmd import visualization as vis\n"
         "from lbmd.units import UnitSystem, oif_moduli_from_si\n"
         "units = UnitSystem()  # 1 um, 1 us, 1e-15 kg\n"
         "print('lbmd', lbmd.__version__)"),
    md("## 1. Geometry\n\nA channel 10 um high, periodic along x (80 um): a parent channel 14 um wide splits "
       "into a lower (5 um) and an upper branch (7 um) around an island with round ends, and joins again. "
       "The walls are shapes; each becomes an `LBBoundary` of the fluid and a constraint for the cells."),
    code("L_X, L_Y, H = 80.0, 24.0, 10.0\n"
         "H_BOX = H + 2.0                       # a wall one node thick below and above\n"
         "split, join = 25.0, 55.0\n"
         "parent = (5.0, 19.0)                  # the parent channel's y range\n"
         "island = (6.0, 16.0)                  # between the branches: lower 1..6, upper 16..23\n"
         "system = lbmd.System(box_l=[L_X, L_Y, H_BOX])\n"
         "system.time_step = 0.1\n"
         "system.cell_system.skin = 0.3\n\n"
         "def box(x0, x1, y0, y1):\n"
         "    return shapes.Rhomboid(corner=[x0, y0, 0], a=[x1 - x0, 0, 0], b=[0, y1 - y0, 0], c=[0, 0, H_BOX])\n\n"
         "r = 0.5 * (island[1] - island[0])\n"
         "walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(H + 1.0)),\n"
         "         box(0, split, 0, parent[0]), box(0, split, parent[1], L_Y),      # parent channel\n"
         "         box(join, L_X, 0, parent[0]), box(join, L_X, parent[1], L_Y),    # after the confluence\n"
         "         box(split, join, 0, 1.0), box(split, join, L_Y - 1.0, L_Y),      # the branches' outer walls\n"
         "         shapes.Union(shapes=[box(split + r, join - r, *island),           # the island, round ends\n"
         "             shapes.Cylinder(center=[split + r, 0.5 * sum(island), 0.5 * H_BOX], axis=[0, 0, 1],\n"
         "                             radius=0.999 * r, length=H_BOX),\n"
         "             shapes.Cylinder(center=[join - r, 0.5 * sum(island), 0.5 * H_BOX], axis=[0, 0, 1],\n"
         "                             radius=0.999 * r, length=H_BOX)])]"),
    md("## 2. Fluid\n\nPlasma (1000 kg/m^3, 1.5 mPa s) on a lattice of 1 um, driven by a body force along x. "
       "The boundary flags of the mid-height plane, with the shapes' outlines:"),
    code("visc = units.to_lattice(1.5e-3 / 1000.0, 'm^2/s')\n"
         "dens = units.to_lattice(1000.0, 'kg/m^3')\n"
         "lbf = lb.LBFluid(agrid=1.0, dens=dens, visc=visc, tau=system.time_step, ext_force_density=[0.006, 0, 0])\n"
         "system.actors.add(lbf)\n"
         "for w in walls:\n"
         "    system.lbboundaries.add(lbboundaries.LBBoundary(shape=w))\n"
         "    system.constraints.add(shape=w, particle_type=10, penetrable=False)\n"
         "vis.geometry(system, 'z', 0.5 * H_BOX, units=units)"),
    md("Let the flow develop for 1500 steps (0.15 ms), then look at the speed in the mid-height plane:"),
    code("system.integrator.run(1500)\n"
         "vis.fluid(system, 'z', 0.5 * H_BOX, units=units)"),
    md("## 3. Cell types\n\nRed blood cells: the Evans-Fung mesh of 374 nodes, radius 3.91 um, the paper's "
       "membrane moduli (in SI, turned into OIF coefficients) 27 times stiffer, as the sample's fast `--small` "
       "flow uses (the same capillary number at 27 times the speed)."),
    code("moduli = oif_moduli_from_si(units, shear_modulus=27 * 2.1651e-6, bending_modulus=27 * 1.7321e-17,\n"
         "                            local_area_modulus=27 * 3.5e-6, global_area_modulus=27 * 3.5e-4,\n"
         "                            volume_modulus=27 * 900.0, membrane_viscosity=4.33e-10)\n"
         "rbc = oif.OifCellType(*oif.mesh_files('rbc374'), system=system, resize=(3.91,) * 3, normal=True, **moduli)\n"
         "{k: round(v, 5) for k, v in moduli.items()}"),
    md("## 4. Cells\n\nFour cells at random in the parent channel, upstream of the split; the coupling to the "
       "fluid, the walls' and the cells' contacts as in the sample:"),
    code("gamma = rbc.suggest_LBgamma(visc=visc, dens=dens)\n"
         "cells = oif.seed_cells(system, [rbc], counts=[4], boundaries=walls,\n"
         "                       region=([0.0, parent[0], 1.0], [split - 3.0, parent[1], H + 1.0]),\n"
         "                       seed=3, particle_mass=gamma * system.time_step / 0.3)\n"
         "system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)\n"
         "system.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.02 * 27, n=1.5, cutoff=1.0, offset=0.0)\n"
         "system.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.1 * 27, n=1.2, cutoff=1.0, offset=0.0)\n"
         "vis.cells(system, cells, 'z', mode='projected', color_by='deformation', units=units)"),
    md("The same cells cut by the mid-height plane, over the fluid's speed (one Axes, two pictures):"),
    code("from matplotlib.figure import Figure\n"
         "fig = Figure(figsize=(8, 3.2), layout='constrained')\n"
         "ax = fig.add_subplot()\n"
         "vis.fluid(system, 'z', 0.5 * H_BOX, units=units, arrows=None, ax=ax)\n"
         "vis.cells(system, cells, 'z', 0.5 * H_BOX, units=units, walls=False, ax=ax)\n"
         "fig"),
    md("## 5. Run\n\n`LiveView` runs the integrator in chunks and redraws one picture in place (here the "
       "projected cells, coloured by their speed); the notebook's stop button stops it cleanly between steps."),
    code("view = vis.LiveView(system, plot=lambda s, ax: vis.cells(s, cells, 'z', mode='projected',\n"
         "                    color_by='velocity', units=units, ax=ax), every=1500, units=units)\n"
         "view.run(15000)"),
    md("Where the cells went, and how much they deform (largest node distance over the undeformed one):"),
    code("for c in cells:\n"
         "    x, y, z = c.get_origin_folded()\n"
         "    print(f'cell {c.cell_id}: x {x:5.1f} um, y {y:5.1f} um, D/D0 {c.diameter() / (2 * 3.91):.3f}')\n"
         "vis.fluid(system, 'z', 0.5 * H_BOX, units=units, arrows='quiver')"),
    md("A 3D picture through VTK (needs an X display or Debian's `xvfb`; see `doc/visualization.md`):"),
    code("from IPython.display import Image\n"
         "try:\n"
         "    vis.snapshot_3d(system, cells, 'bifurcation_3d.png', color_by='deformation', size=(900, 450))\n"
         "    shown = Image('bifurcation_3d.png')\n"
         "except RuntimeError as e:\n"
         "    shown = str(e)\n"
         "shown"),
]

nb = nbformat.v4.new_notebook()
nb.cells = cells
nb.metadata["kernelspec"] = {"name": "pyoif", "display_name": "PyOIF", "language": "python"}
nb.metadata["language_info"] = {"name": "python"}
here = os.path.dirname(os.path.abspath(__file__))
os.environ.setdefault("OMP_NUM_THREADS", "1")
started = time.perf_counter()
kernel = sys.argv[1] if len(sys.argv) > 1 else "python3"
workdir = os.path.join(here, "..", "..", "build", "tutorial_run")
os.makedirs(workdir, exist_ok=True)
NotebookClient(nb, kernel_name=kernel, timeout=300, resources={"metadata": {"path": workdir}}).execute()
nb.metadata["kernelspec"] = {"name": "pyoif", "display_name": "PyOIF", "language": "python"}
for cell in nb.cells:  # execution times and ids would change at every run
    cell.metadata.pop("execution", None)
nbformat.write(nb, os.path.join(here, "bifurcation.ipynb"))
print(f"executed in {time.perf_counter() - started:.1f} s: {os.path.join(here, 'bifurcation.ipynb')}")
