"""Runs for test_checkpoint_mpi: a checkpoint written in the middle of a run
at one rank count, continued at the same or another rank count.

    mpirun -np K pyoif checkpoint_scenes.py full N1 N2 CKPT OUT.npz
    mpirun -np K pyoif checkpoint_scenes.py resume CKPT N2 OUT.npz LOADED.npz
    mpirun -np K pyoif checkpoint_scenes.py walltime CKPT N OUT.npz [SIGNAL_RANK]

The scene is mpi_scenes.scene_cells_thermal (fluid with kT > 0, three RBCs
and a sphere straddling the subdomain cuts and the periodic boundary, walls
with soft-sphere contacts, membrane collision, the fluid coupling's noise)
with the MD time step half the lattice's (two MD steps per lattice update,
so that a checkpoint can fall between a lattice update's deposits). `full`
runs N1 steps, saves CKPT (system, fluid and cells), runs N2 more steps and
writes the state (mpi_scenes.state) to OUT on rank 0; `resume` loads CKPT,
writes the state as loaded to LOADED, runs N2 steps and writes OUT.
`walltime` runs the scene up to step N (loading CKPT if it exists) with
lbmd.checkpoint.stop_on_signal(CKPT, ...); with SIGNAL_RANK, that rank alone
gets a signal (SIGALRM, armed beside SIGUSR1) 0.3 s into the run, so the
ranks must agree to stop at the same step; the state at step N goes to OUT.
"""
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mpi_scenes  # noqa: E402
import lbmd  # noqa: E402

_new_system = mpi_scenes.new_system


def new_system_half_step(box, node_grid):
    system = _new_system(box, node_grid)
    system.time_step = mpi_scenes.TAU / 2  # two MD steps per lattice update
    return system


mpi_scenes.new_system = new_system_half_step


def write(path, sc):
    result = mpi_scenes.state(sc)
    if MPI.COMM_WORLD.Get_rank() == 0:
        np.savez(path, **result)
    MPI.COMM_WORLD.Barrier()


def main(argv):
    mode = argv[0]
    if mode == "full":
        n1, n2, ckpt, out = int(argv[1]), int(argv[2]), argv[3], argv[4]
        sc = mpi_scenes.scene_cells_thermal(None)
        sc["system"].integrator.run(n1)
        lbmd.checkpoint.save(ckpt, sc["system"], lbf=sc["lbf"], cells=sc["cells"], force=sc["force"])
        sc["system"].integrator.run(n2)
        write(out, sc)
    elif mode == "resume":
        ckpt, n2, out, loaded = argv[1], int(argv[2]), argv[3], argv[4]
        ns = lbmd.checkpoint.load(ckpt)
        sc = {"system": ns.system, "lbf": ns.lbf, "cells": ns.cells, "force": ns.force}
        write(loaded, sc)
        sc["system"].integrator.run(n2)
        write(out, sc)
    elif mode == "walltime":
        import signal
        ckpt, n, out = argv[1], int(argv[2]), argv[3]
        if os.path.exists(ckpt):
            ns = lbmd.checkpoint.load(ckpt)
            sc = {"system": ns.system, "lbf": ns.lbf, "cells": ns.cells, "force": ns.force}
        else:
            sc = mpi_scenes.scene_cells_thermal(None)
        system = sc["system"]
        lbmd.checkpoint.stop_on_signal(ckpt, system, {"lbf": sc["lbf"], "cells": sc["cells"], "force": sc["force"]},
                                       signals=[signal.SIGUSR1, signal.SIGALRM])
        if len(argv) > 4 and MPI.COMM_WORLD.Get_rank() == int(argv[4]):
            signal.setitimer(signal.ITIMER_REAL, 0.3)
        while system.step_count < n:
            system.integrator.run(n - system.step_count)
        write(out, sc)
    else:
        raise SystemExit(f"checkpoint_scenes: unknown mode {mode!r}")


if __name__ == "__main__":
    main(sys.argv[1:])
