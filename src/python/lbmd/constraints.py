"""Shape-based constraints: a shape acting on particles through the
non-bonded table entry (particle type, constraint's particle_type)."""
import numpy as np

from . import _lbmd
from .shapes import Shape
from .validation import Param, ParameterObject, non_negative


class Constraint(ParameterObject):
    """Base of constraints."""


class ShapeBasedConstraint(Constraint):
    """A wall or obstacle: particles of type t feel the non-bonded
    interactions of the pair (t, particle_type) at their distance from the
    shape's surface. A particle inside a non-penetrable shape stops the run
    with SimulationInstability. Inside a penetrable one (as in ESPResSo) it
    feels the interaction at the mirrored distance -d along d * normal: a
    repulsion pushes it away from the surface, deeper in; with
    only_positive=True it feels nothing inside."""

    _params = [Param("shape", "object", cls=Shape),
               Param("particle_type", "int", 0, check=non_negative),
               Param("penetrable", "bool", False),
               Param("only_positive", "bool", False)]

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.ShapeBasedConstraint(
            self.shape._core, self.particle_type, self.penetrable, self.only_positive))

    _restore_core = _validate

    def total_force(self):
        """Force the particles exert on the shape, at the last force calculation.
        Under mpirun with a fluid the particles are spread over the ranks:
        then this is a sum over them (collective: call it on every rank)."""
        force = np.array(self._core.total_force, dtype=float)
        system_core = self.__dict__.get("_system_core")
        if system_core is not None and system_core.particles_spread:
            from mpi4py import MPI
            MPI.COMM_WORLD.Allreduce(MPI.IN_PLACE, force)
        return force


class Constraints:
    """``system.constraints``."""

    def __init__(self, system):
        self._system = system
        self._list = []

    def add(self, *args, **kwargs):
        if args and kwargs or len(args) > 1:
            raise TypeError("constraints.add: pass one constraint, or keyword arguments of ShapeBasedConstraint")
        c = args[0] if args else ShapeBasedConstraint(**kwargs)
        if not isinstance(c, Constraint):
            raise TypeError(f"constraints.add: expected a constraint, got {type(c).__name__}")
        if any(x is c for x in self._list):
            raise ValueError("constraints.add: this constraint was already added (its force would count twice)")
        self._system._core.add_constraint(c._core)
        c.__dict__["_system_core"] = self._system._core
        self._list.append(c)
        return c

    def remove(self, c):
        if c not in self._list:
            raise ValueError("constraints.remove: this constraint was not added")
        self._system._core.remove_constraint(c._core)
        self._list.remove(c)

    def clear(self):
        for c in list(self._list):
            self.remove(c)

    def __iter__(self):
        return iter(self._list)

    def __len__(self):
        return len(self._list)

    def __getitem__(self, i):
        return self._list[i]

    def __repr__(self):
        return f"Constraints({self._list!r})"
