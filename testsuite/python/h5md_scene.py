"""The scene of test_h5md and test_h5md_mpi: a 16x12x12 periodic box with
a fluid driven along x, a sphere cell across the periodic boundary x = 0 =
16 and two free particles.

    mpirun -np K pyoif h5md_scene.py OUT.h5

writes three frames (steps 0, 15, 30) of every field and the cell's
observables to OUT.h5 with lbmd.io.H5mdWriter (every rank calls)."""
import sys

import lbmd
import oif
from lbmd import lb


def scene():
    system = lbmd.System(box_l=[16.0, 12.0, 12.0])
    system.time_step = 0.1
    system.cell_system.skin = 0.3
    ball = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(2.5,) * 3,
                           ks=0.05, kb=0.05, kal=0.05, kag=0.7, kv=0.9)
    cell = oif.OifCell(cell_type=ball, particle_type=1, origin=[15.0, 6.0, 6.0])  # across x = 0 = 16
    free = system.part.add(pos=[[1.0, 2.0, 3.0], [8.0, 9.0, 10.0]], type=3, mol_id=-5, v=[0.01, 0.02, -0.01])
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[2e-3, 0.0, 0.0])
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=ball.suggest_LBgamma(visc=1.5, dens=1.0))
    return system, cell, free


def main(path):
    system, cell, _ = scene()
    with lbmd.io.H5mdWriter(path, system, fields=tuple(lbmd.io.FIELDS), cells=[cell],
                            cell_fields=tuple(lbmd.io.CELL_FIELDS), author="test") as writer:
        for k in range(3):
            if k:
                system.integrator.run(15)
            writer.write()


if __name__ == "__main__":
    main(sys.argv[1])
