"""lbmd: the PyOIF engine — particles, lattice-Boltzmann fluid, shapes,
constraints and interactions, with an API shaped like ESPResSo 4.2's.

``import lbmd`` makes every submodule available (lbmd.lb, lbmd.shapes, ...),
so an ESPResSo script ports by replacing ``espressomd`` with ``lbmd``.

Under ``mpirun -np N pyoif script.py`` every rank runs the same script (SPMD)
and every query returns the same value on every rank. For a script's own
rank-dependent work:

- ``lbmd.rank``: this process's rank in MPI_COMM_WORLD (int, 0 without mpirun);
- ``lbmd.size``: the number of ranks (int, 1 without mpirun);
- ``lbmd.comm``: mpi4py's ``MPI.COMM_WORLD``, for the script's own
  collectives (``lbmd.comm.bcast(x, root=0)``, ``lbmd.comm.barrier()``).

With more than one rank, an uncaught exception on any rank prints its
traceback to stderr with every line prefixed ``[rank R]`` and then ends all
ranks (``MPI.COMM_WORLD.Abort(1)``): the other ranks may be waiting for the
failed one in a collective and would otherwise hang until the job's time
limit. On one rank, and in an interactive session, Python's usual handling
stays.
"""
import sys
import traceback

# mpi4py initialises (and at exit finalises) MPI for every rank of an SPMD run.
from mpi4py import MPI as _MPI

from . import _lbmd
from ._lbmd import SimulationInstability
from .features import has_features, assert_features, features, FeaturesError
from . import validation
from . import interactions
from . import shapes
from . import constraints
from . import lb
from . import lbboundaries
from . import open_boundaries
from . import vtk_output
from . import units
from . import checkpoint
from . import io
from . import progress
from . import packing
from . import cell_registry
from . import system as _system_module
from .system import CellDriftWarning, System
from .old_names import OldNameWarning

__version__ = "0.1.0"

comm = _MPI.COMM_WORLD
rank = comm.Get_rank()
size = comm.Get_size()


def _abort_all_ranks(exc_type, exc, tb):
    """sys.excepthook with more than one rank: print the traceback marked
    with this rank (stderr of all ranks is interleaved), then MPI_Abort.
    Returning would let Python exit this rank alone, and a rank waiting for
    it in a collective would wait forever (mpi4py's atexit MPI_Finalize
    blocks too)."""
    try:
        prefix = f"[rank {rank}] "
        lines = "".join(traceback.format_exception(exc_type, exc, tb)).splitlines()
        lines.append(f"uncaught {exc_type.__name__}: ending all {size} ranks (MPI_Abort)")
        sys.stderr.write("".join(prefix + line + "\n" for line in lines))
    finally:
        # Abort kills the process without Python's exit-time flush: what this
        # rank printed before the error would be lost from a piped stdout.
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # a closed or None stream must not stop the abort
                pass
        comm.Abort(1)


if size > 1 and not sys.flags.interactive:
    sys.excepthook = _abort_all_ranks

__all__ = ["System", "SimulationInstability", "CellDriftWarning", "OldNameWarning", "has_features", "assert_features",
           "features", "FeaturesError", "interactions", "shapes", "constraints", "lb", "lbboundaries", "open_boundaries",
           "units", "checkpoint", "io", "progress", "packing", "cell_registry",
           "rank", "size", "comm"]
