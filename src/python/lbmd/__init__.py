"""lbmd: the PyOIF engine — particles, lattice-Boltzmann fluid, shapes,
constraints and interactions, with an API shaped like ESPResSo 4.2's.

``import lbmd`` makes every submodule available (lbmd.lb, lbmd.shapes, ...),
so an ESPResSo script ports by replacing ``espressomd`` with ``lbmd``.
"""
# mpi4py initialises (and at exit finalises) MPI for every rank of an SPMD run.
from mpi4py import MPI as _MPI  # noqa: F401

from . import _lbmd
from ._lbmd import SimulationInstability
from .features import has_features, assert_features, features, FeaturesError
from . import validation
from . import interactions
from . import shapes
from . import constraints
from . import lb
from . import lbboundaries
from . import system as _system_module
from .system import System

__version__ = "0.1.0"

__all__ = ["System", "SimulationInstability", "has_features", "assert_features", "features",
           "FeaturesError", "interactions", "shapes", "constraints", "lb", "lbboundaries"]
