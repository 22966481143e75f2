"""Scenes for test_mpi_equality: the same script on 1, 2, 3 and 4 MPI ranks
must end in the same state, bit for bit.

    mpirun -np K pyoif mpi_scenes.py SCENE STEPS OUT.npz [--node-grid A,B,C]

builds SCENE with the public Python API (lbmd, oif), runs STEPS steps (in
two runs, with a read of the state in between) and writes the state on
rank 0 to OUT.npz: every node's fluid velocity, density, populations and
boundary flag, single-node reads of a few nodes on the subdomain borders,
interpolated velocities there, particle ids/pos/v/f, cell volumes, boundary
and constraint forces, fluid mass and momentum, energies. Every rank makes
every query, in the same order (SPMD): under the domain decomposition the
reads are collective. --node-grid asks for a subdomain grid
(system.cell_system.node_grid, when the engine has it; exit status 3 when
it has not).

Scenes (agrid 1; the subdomains are those of the automatic grid, which for
up to 4 ranks splits the longest axis only; "cuts" are the lattice planes
where a subdomain starts, int(n k / K)):

- fluid: 25x12x10, MRT, body force, a nonuniform initial velocity field,
  density and perturbed populations; cuts x: 12 | 8, 16 | 6, 12, 18.
- fluid_thermal: 12x10x23, as fluid with kT > 0; cuts z: 11 | 7, 15 | 5, 11, 17.
- boundaries: 12x26x10, walls z = 1 and z = 9 (the top one moving along x),
  a z cylinder at y = 13, a sphere at y = 8.5, a rod along y through the
  periodic boundary, body force along y; cuts y: 13 | 8, 17 | 6, 13, 19.
- cells: 25x12x10, walls z = 1, 9, four cells (three RBCs, one sphere)
  straddling x = 12, 16/18, 6/8 and the periodic boundary x = 0 = 25, two
  of them 0.4 apart (membrane collision), one 0.4 from the wall (soft
  sphere); cuts x as fluid.
- cells_thermal: cells with kT > 0 (fluid and coupling noise).
- crossing: cells with a body force 80x stronger, 300 steps: the cells
  move 4 lattice spacings (the one near the wall 2) across the cuts and
  the periodic boundary.
- open_channel: 25x12x10, walls z = 1, 9, a Poiseuille velocity inlet at a
  flow rate on x- and a pressure outlet on x+ (lbmd.open_boundaries); cuts
  x as fluid.
- bifurcation: samples/cell_flow_in_bifurcation.py's default scene with 6
  RBCs (160x40x16, the body force given: no calibration run) run in this
  process with --cycles 2 --steps STEPS/2;
  its printed cycle table and cells.csv are kept as text too; cuts x:
  80 | 53, 106 | 40, 80, 120.
"""
import argparse
import contextlib
import io
import os
import runpy
import sys
import tempfile

import numpy as np
from mpi4py import MPI

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(HERE, "..", ".."))

AGRID, TAU, DENS, VISC = 1.0, 0.1, 1.0, 1.5


class NodeGridUnsupported(Exception):
    pass


def new_system(box, node_grid):
    system = lbmd.System(box_l=box)
    system.time_step = TAU
    system.cell_system.skin = 0.3
    if node_grid is not None:
        # CellSystem is a plain Python class: an attribute that is no
        # property would be set silently and change nothing
        if not isinstance(getattr(type(system.cell_system), "node_grid", None), property):
            raise NodeGridUnsupported("system.cell_system.node_grid does not exist in this engine")
        system.cell_system.node_grid = list(node_grid)
    return system


def initial_fluid(lbf, seed):
    """A nonuniform field: waves along every axis plus noise, so that
    populations cross every face, edge and corner of the subdomains; then
    every population is perturbed (non-equilibrium parts too)."""
    nx, ny, nz = lbf.shape
    x, y, z = np.meshgrid(*(2 * np.pi * (np.arange(n) + 0.5) / n for n in (nx, ny, nz)), indexing="ij")
    rng = np.random.default_rng(seed)
    lbf[:, :, :].density = DENS * (1.0 + 0.02 * np.sin(x + 2 * y) * np.cos(z) + 0.005 * rng.uniform(-1, 1, x.shape))
    u = 0.05 * np.stack([np.sin(y) * np.cos(z), np.sin(z + x), np.cos(x) * np.sin(2 * y)], axis=-1)
    lbf[:, :, :].velocity = u + 0.01 * rng.uniform(-1, 1, u.shape)
    pop = lbf[:, :, :].population
    lbf[:, :, :].population = pop * (1.0 + 1e-3 * rng.uniform(-1, 1, pop.shape))


def scene_fluid(node_grid, thermal=False):
    box = (12.0, 10.0, 23.0) if thermal else (25.0, 12.0, 10.0)
    system = new_system(box, node_grid)
    force = np.array([2e-3, 5e-4, -3e-4])
    kw = dict(kT=1e-3, seed=17) if thermal else {}
    lbf = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TAU, ext_force_density=force, **kw)
    system.actors.add(lbf)
    initial_fluid(lbf, seed=5)
    return dict(system=system, lbf=lbf, cells=[], force=force)


def scene_boundaries(node_grid, single_precision=False):
    box = (12.0, 26.0, 10.0)
    system = new_system(box, node_grid)
    force = np.array([0.0, 2e-3, 0.0])
    lbf = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TAU, ext_force_density=force,
                     single_precision=single_precision)
    system.actors.add(lbf)
    walls = [(shapes.Wall(normal=[0, 0, 1], dist=1.0), [0.0, 0.0, 0.0]),
             (shapes.Wall(normal=[0, 0, -1], dist=-9.0), [0.05, 0.0, 0.0]),   # moving along x
             (shapes.Cylinder(center=[7.0, 13.0, 5.0], axis=[0, 0, 1], radius=2.2, length=10.0), [0, 0, 0]),
             (shapes.Sphere(center=[6.5, 8.5, 5.0], radius=2.4), [0, 0, 0]),
             (shapes.Cylinder(center=[2.5, 13.0, 5.5], axis=[0, 1, 0], radius=1.2, length=26.0, open=True),
              [0, 0, 0])]
    for shape, velocity in walls:
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=shape, velocity=velocity))
    initial_fluid(lbf, seed=6)
    return dict(system=system, lbf=lbf, cells=[], force=force)


def scene_cells(node_grid, force_x=5e-4, kT=0.0, kvisc=0.0):
    box = (25.0, 12.0, 10.0)
    system = new_system(box, node_grid)
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(2.5, 2.5, 2.5),
                          ks=0.02, kb=0.02, kal=0.02, kag=0.7, kv=0.9, normal=True, kvisc=kvisc)
    ball = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(2.0, 2.0, 2.0),
                           ks=0.05, kb=0.05, kal=0.05, kag=0.7, kv=0.9, normal=True)
    cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=[12.0, 3.5, 5.0]),        # x = 12
             oif.OifCell(cell_type=rbc, particle_type=0, origin=[17.4, 3.5, 5.3],         # x = 16, 18;
                         rotate=(0.0, 0.0, 0.4)),                                         # 0.4 from the first
             oif.OifCell(cell_type=ball, particle_type=1, origin=[7.0, 8.5, 5.0]),        # x = 6, 8
             oif.OifCell(cell_type=rbc, particle_type=0, origin=[24.5, 8.5, 2.22])]       # x = 0 = 25, z wall
    force = np.array([force_x, 0.0, 0.0])
    thermal = dict(kT=kT, seed=23) if kT > 0 else {}
    lbf = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TAU, ext_force_density=force, **thermal)
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=VISC, dens=DENS),
                             **({"seed": 29} if kT > 0 else {}))
    for wall in (shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-9.0)):
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=wall))
        system.constraints.add(shape=wall, particle_type=10, penetrable=False)
    for t in (0, 1):
        system.non_bonded_inter[t, 10].soft_sphere.set_params(a=0.0002, n=1.2, cutoff=0.6, offset=0.0)
        for u in (0, 1):
            if u >= t:
                system.non_bonded_inter[t, u].membrane_collision.set_params(a=0.002, n=2.0, cutoff=0.6,
                                                                            offset=0.0)
    return dict(system=system, lbf=lbf, cells=cells, force=force)


def scene_packed(node_grid):
    """17 red cells packed to 0.45 in a D 10 um tube by oif.pack_cells (the
    rigid packer, then the deformable stage, whose scratch System runs on
    the same ranks), then a flow with the advised contacts."""
    box = (44.0, 12.0, 12.0)
    system = new_system(box, node_grid)
    tube = shapes.Cylinder(center=[22.0, 6.0, 6.0], axis=[1, 0, 0], radius=5.0, length=132.0, direction=-1,
                           open=True)
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.91, 3.91, 3.91), ks=0.005,
                          kb=0.02, kal=0.007, kag=0.7, kv=0.9, normal=True)
    gamma = rbc.suggest_LBgamma(visc=VISC, dens=DENS)
    cells = list(oif.pack_cells(system, rbc, haematocrit=0.45, boundaries=[tube], seed=4,
                                particle_mass=gamma * TAU / 0.3))
    force = np.array([2e-4, 0.0, 0.0])
    lbf = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TAU, ext_force_density=force)
    system.actors.add(lbf)
    # the tube only as the cells' wall, not as a lattice boundary: the
    # scene tests the packing; the force sum on a curved lattice boundary
    # cancels to a few 1e-11 of its terms, beyond the sums' tolerance
    system.constraints.add(shape=tube, particle_type=10, penetrable=False)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
    oif.set_contacts(system, rbc, particle_types=0, wall_types=10)
    return dict(system=system, lbf=lbf, cells=cells, force=force)


def scene_cells_thermal(node_grid):
    return scene_cells(node_grid, kT=1e-4)


def scene_crossing(node_grid):
    return scene_cells(node_grid, force_x=4e-2)


def run_bifurcation(steps, node_grid):
    """The sample itself, in this process (its module globals come back),
    into a folder of this rank's own; its stdout is kept."""
    if node_grid is not None:
        raise NodeGridUnsupported("the bifurcation sample builds its own System")
    rank = MPI.COMM_WORLD.Get_rank()
    folder = tempfile.mkdtemp(prefix=f"mpi_scenes_bif_r{rank}_")
    argv = sys.argv
    sys.argv = ["cell_flow_in_bifurcation.py", "--cycles", "2", "--steps", str(steps // 2),
                "--output", folder, "--cells", "6", "--force", "3e-3", "--no-plots", "--progress", "off"]
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            g = runpy.run_path(os.path.join(SOURCE, "samples", "cell_flow_in_bifurcation.py"), run_name="__main__")
    finally:
        sys.argv = argv
    # the sample's tables are written by rank 0 (only its text is saved)
    csv_text = ""
    if rank == 0:
        with open(os.path.join(folder, "cells.csv")) as f:
            csv_text = f.read()
    lines = out.getvalue().splitlines()
    # the timing report (wall clock, differs from run to run) starts at its header
    table = []
    for line in lines:
        if line.startswith("phase"):
            break
        table.append(line)
    return dict(system=g["system"], lbf=g["lbf"], cells=g["cells"], force=np.array([g["args"].force, 0.0, 0.0]),
                text={"sample_stdout": "\n".join(table), "cells_csv": csv_text}, folder=folder)


def scene_open_channel(node_grid):
    """A channel along x between walls z = 1, 9, a Poiseuille inlet at a
    flow rate (its controller's gain is a sum over the face) on x- and a
    pressure outlet on x+."""
    from lbmd.open_boundaries import PressureOutlet, VelocityInlet
    box = (25.0, 12.0, 10.0)
    system = new_system(box, node_grid)
    lbf = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TAU)
    system.actors.add(lbf)
    for wall in (shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-9.0)):
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=wall))
    lbf.open_boundaries.add(VelocityInlet(face="x-", profile="poiseuille", flow_rate=20.0))
    lbf.open_boundaries.add(PressureOutlet(face="x+", density=DENS))
    return dict(system=system, lbf=lbf, cells=[], force=np.zeros(3))


SCENES = {"fluid": lambda grid: scene_fluid(grid),
          "fluid_thermal": lambda grid: scene_fluid(grid, thermal=True),
          "boundaries": scene_boundaries,
          "boundaries_single": lambda grid: scene_boundaries(grid, single_precision=True),
          "cells": scene_cells,
          "cells_thermal": scene_cells_thermal,
          # the red cells' membrane viscosity implicit (dt kvisc_node / m 30)
          "cells_viscous": lambda grid: scene_cells(grid, kvisc=50.0),
          "crossing": scene_crossing,
          "packed": scene_packed,
          "open_channel": scene_open_channel}
ALL_SCENES = tuple(SCENES) + ("bifurcation",)


def probe_nodes(shape):
    """Nodes at the cuts of 2, 3 and 4 subdomains along each axis (both
    sides), at the periodic boundary and in the middle."""
    nx, ny, nz = shape
    nodes = {(0, 0, 0), (nx - 1, ny - 1, nz - 1), (nx // 2, ny // 2, nz // 2)}
    for k in (2, 3, 4):
        for j in range(1, k):
            c = [n * j // k for n in shape]
            nodes.add(tuple(c))
            nodes.add(tuple(max(v - 1, 0) for v in c))
    return sorted(nodes)


def probe_points(box):
    """Positions for interpolated velocities: on and beside the cuts, and
    across the periodic boundary."""
    box = np.asarray(box)
    pts = [0.01 * box, 0.999 * box, 0.5 * box, [0.0, 0.0, 0.0]]
    for k in (2, 3, 4):
        for j in range(1, k):
            c = np.floor(box * j / k)
            pts += [c, c + 0.3, c - 0.3]
    return np.array(pts, dtype=float)


def fluid_state(lbf, prefix):
    """Every node's velocity, density, populations, boundary flag."""
    s = lbf[:, :, :]
    return {prefix + "velocity": s.velocity, prefix + "density": s.density,
            prefix + "population": s.population, prefix + "boundary": s.boundary}


def particle_state(system, prefix):
    p = system.part.all()
    return {prefix + "id": p.id, prefix + "pos": p.pos, prefix + "v": p.v, prefix + "f": p.f,
            prefix + "type": p.type, prefix + "mol_id": p.mol_id}


def state(sc):
    """The whole state; every rank calls every query in this order."""
    system, lbf, cells = sc["system"], sc["lbf"], sc["cells"]
    out = {"ranks": np.array(MPI.COMM_WORLD.Get_size()), "time": np.array(system.time),
           "box_l": system.box_l, "force": sc["force"]}
    out.update(fluid_state(lbf, "fluid_"))
    nodes = probe_nodes(lbf.shape)
    out["probe_nodes"] = np.array(nodes)
    out["probe_velocity"] = np.array([lbf[n].velocity for n in nodes])
    out["probe_density"] = np.array([lbf[n].density for n in nodes])
    out["probe_population"] = np.array([lbf[n].population for n in nodes])
    pts = probe_points(system.box_l)
    out["interp_points"] = pts
    out["interp_velocity"] = np.array([lbf.get_interpolated_velocity(p) for p in pts])
    out.update(particle_state(system, "part_"))
    out["cell_volume"] = np.array([c.volume() for c in cells])
    out["cell_surface"] = np.array([c.surface() for c in cells])
    out["cell_origin"] = np.array([c.get_origin() for c in cells]).reshape(-1, 3)
    out["constraint_force"] = np.array([c.total_force() for c in system.constraints]).reshape(-1, 3)
    # sums over ranks under the domain decomposition
    out["sum_boundary_force"] = np.array([b.get_force() for b in system.lbboundaries]).reshape(-1, 3)
    out["sum_fluid_mass"] = np.array(lbf.total_mass())
    out["sum_fluid_momentum"] = lbf.total_momentum()
    out["sum_linear_momentum"] = system.analysis.linear_momentum()
    for key, value in system.analysis.energy().items():
        name = ":".join(str(k) for k in key) if isinstance(key, tuple) else str(key)
        out["energy_" + name] = np.array(value)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", choices=ALL_SCENES)
    ap.add_argument("steps", type=int)
    ap.add_argument("out")
    ap.add_argument("--node-grid", default=None, help="ranks per axis, e.g. 2,2,1")
    args = ap.parse_args(argv)
    grid = tuple(int(v) for v in args.node_grid.split(",")) if args.node_grid else None
    comm = MPI.COMM_WORLD
    try:
        if args.scene == "bifurcation":
            sc = run_bifurcation(args.steps, grid)
            result = {}
        else:
            sc = SCENES[args.scene](grid)
            sc["text"] = {}
            result = {}
            # the initial state and a read in the middle of the run (state
            # reads between runs must leave the run unchanged)
            result.update({"initial_" + k: v for k, v in state(sc).items()
                           if k != "ranks" and not k.startswith("fluid_population")})
            sc["system"].integrator.run(args.steps // 2)
            mid = state(sc)
            result.update({"mid_" + k: mid[k] for k in ("fluid_velocity", "part_pos", "sum_fluid_momentum")})
            sc["system"].integrator.run(args.steps - args.steps // 2)
    except NodeGridUnsupported as e:
        if comm.Get_rank() == 0:
            print(f"mpi_scenes: {e}", file=sys.stderr)
        sys.exit(3)
    result.update(state(sc))
    # how the population halo travelled: neighbours through shared memory,
    # summed over the ranks (0: MPI messages only); not a state, not compared
    result["shared_halo_peers"] = np.array(comm.allreduce(sc["lbf"]._core.shared_halo_peers))
    for key, text in sc["text"].items():
        result["text_" + key] = np.array(text)
    if comm.Get_rank() == 0:
        tmp = args.out + ".part.npz"
        np.savez(tmp, **result)
        os.replace(tmp, args.out)
    comm.Barrier()
    if "folder" in sc:
        import shutil
        shutil.rmtree(sc["folder"], ignore_errors=True)


if __name__ == "__main__":
    main()
