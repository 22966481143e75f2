"""Shapes: regions of space with a signed distance (positive outside the
shape, where particles and fluid may be) and an outward surface normal. Used
by ShapeBasedConstraint (particles) and LBBoundary (fluid)."""
import numpy as np

from . import _lbmd
from .validation import Param, ParameterObject, unit_or_nonzero


class Shape(ParameterObject):
    """Base of shapes: subclasses declare ``_params`` and build ``_core``."""

    def calc_dist(self, pos):
        """(signed distance, outward unit normal) of the point pos."""
        dist, normal = self._core.calc_dist(np.asarray(pos, dtype=float))
        return dist, np.asarray(normal)

    def is_inside(self, position):
        return bool(self._core.is_inside(np.asarray(position, dtype=float)))


class Wall(Shape):
    """Half-space behind the plane normal·x = dist; particles live on the
    side the normal points to."""

    _params = [Param("normal", "vec3", check=unit_or_nonzero()), Param("dist", "float", 0.0)]

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.Wall(self.normal, self.dist))
