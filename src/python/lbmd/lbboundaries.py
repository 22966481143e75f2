"""Lattice-Boltzmann boundaries (ESPResSo 4.2 ``espressomd.lbboundaries``):
nodes whose centre lies inside a shape are solid; halfway bounce-back, moving
with ``velocity``; ``get_force()`` is the force the fluid exerts on them.
Adding, removing or clearing boundaries is cheap: the nodes are flagged once,
at the fluid's next use (doc/lb.md)."""
import numpy as np

from .shapes import Shape
from .validation import Param, ParameterObject


class LBBoundary(ParameterObject):
    """``LBBoundary(shape=<lbmd.shapes.Shape>, velocity=[0, 0, 0])``."""

    _params = [Param("shape", "object", cls=Shape, doc="region of solid nodes"),
               Param("velocity", "vec3", np.zeros(3), doc="wall velocity (MD units)")]

    def _validate(self):
        object.__setattr__(self, "_owner", None)

    def get_force(self):
        """Force (MD units) of the fluid on this boundary in the last lattice
        update (momentum exchange)."""
        owner = self._owner
        if owner is None:
            raise RuntimeError("LBBoundary: add it with system.lbboundaries.add() first")
        fluid = owner._fluid()
        if fluid is None:
            raise RuntimeError("LBBoundary.get_force: no lattice-Boltzmann fluid is active")
        return np.asarray(fluid._collective_core().boundary_force(owner._list.index(self)))


class LBBoundaries:
    """``system.lbboundaries``: add / remove / clear / iterate."""

    def __init__(self, system):
        self._system = system
        self._list = []

    def _fluid(self):
        from .lb import LBFluid
        for a in self._system.actors:
            if isinstance(a, LBFluid) and a._core is not None:
                return a
        return None

    def _apply(self, core):
        """Hands the boundaries to a fluid's lattice (also called by
        LBFluid._activate, before the fluid is listed in system.actors).
        Cheap: the fluid checks them and flags its nodes later, once, at
        the first call that needs the flags (collective under MPI)."""
        core.set_boundaries([(b.shape._core, b.velocity) for b in self._list])

    def _update(self):
        fluid = self._fluid()
        if fluid is not None:
            self._apply(fluid._core)

    def add(self, boundary):
        if not isinstance(boundary, LBBoundary):
            raise TypeError("lbboundaries.add: expected an lbmd.lbboundaries.LBBoundary, "
                            f"got {type(boundary).__name__}")
        if boundary._owner is not None:
            raise ValueError("lbboundaries.add: this boundary is already in a system")
        self._list.append(boundary)
        object.__setattr__(boundary, "_owner", self)
        try:
            self._update()
        except Exception:
            self._list.remove(boundary)
            object.__setattr__(boundary, "_owner", None)
            raise
        return boundary

    def remove(self, boundary):
        if not any(b is boundary for b in self._list):
            raise ValueError("lbboundaries.remove: this boundary was not added")
        self._list.remove(boundary)
        object.__setattr__(boundary, "_owner", None)
        self._update()

    def clear(self):
        for b in self._list:
            object.__setattr__(b, "_owner", None)
        self._list = []
        self._update()

    def size(self):
        return len(self._list)

    def __len__(self):
        return len(self._list)

    def __iter__(self):
        return iter(list(self._list))

    def __getitem__(self, i):
        return self._list[i]

    def __repr__(self):
        return f"LBBoundaries({self._list!r})"
