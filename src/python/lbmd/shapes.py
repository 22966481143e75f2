"""Shapes: regions of space with a signed distance (positive outside the
shape, where particles and fluid may be, negative inside) and a unit outward
surface normal. Used by ShapeBasedConstraint (particles) and LBBoundary
(fluid: lattice nodes with distance <= 0 are boundary nodes).

Keyword names and meanings are those of ESPResSo 4.2's ``espressomd.shapes``.
``direction=-1`` turns a shape inside out (a hollow sphere, a pipe, a box
whose interior is free): distance and normal change sign.
"""
import collections.abc

import numpy as np

from . import _lbmd
from .validation import Param, ParameterObject, parse, positive, non_negative, unit_or_nonzero

direction_check = (lambda d: d in (1, -1), "1 or -1 (1: the solid, -1: hollow, its complement)")


def _position(owner, pos):
    return Param("pos", "vec3").convert(owner, pos)


class Shape(ParameterObject):
    """Base of shapes: subclasses declare ``_params`` and build ``_core`` (the
    C++ shape, shared with the constraints and the lattice-Boltzmann code)."""

    def calc_dist(self, pos):
        """(signed distance, outward unit normal) of the point pos; the closest
        surface point is ``pos - dist * normal``."""
        dist, normal = self._core.calc_dist(_position(f"{type(self).__name__}.calc_dist", pos))
        return float(dist), np.asarray(normal)

    def calc_distance(self, position):
        """ESPResSo's form: (signed distance, vector from the closest surface
        point to position)."""
        dist, normal = self.calc_dist(position)
        return dist, dist * normal

    def is_inside(self, position):
        """True where the shape occupies space (signed distance <= 0)."""
        return bool(self._core.is_inside(_position(f"{type(self).__name__}.is_inside", position)))

    def signed_distances(self, points):
        """Signed distances of an (n, 3) array of points, in one call (the
        values calc_dist gives, without its per-point checks)."""
        pts = np.ascontiguousarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"{type(self).__name__}.signed_distances: parameter 'points' must be an "
                             f"(n, 3) array, got shape {pts.shape}")
        return np.asarray(self._core.signed_distances(pts))


    def _restore_core(self):
        self._validate()


class Wall(Shape):
    """Half-space behind the plane normal·x = dist (normal made unit); particles
    live on the side the normal points to."""

    _params = [Param("normal", "vec3", check=unit_or_nonzero()), Param("dist", "float", 0.0)]

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.Wall(self.normal, self.dist))


class Sphere(Shape):
    """Ball of the given radius about center; direction=-1: a spherical cavity
    (the shape is everything outside the ball)."""

    _params = [Param("center", "vec3"), Param("radius", "float", check=positive),
               Param("direction", "int", 1, check=direction_check)]

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.Sphere(self.center, self.radius, self.direction))


class Cylinder(Shape):
    """Finite cylinder of the given radius and length (the full length, centred
    on center) about axis (any non-zero length). direction=-1: hollow (particles
    inside); open=True: no caps (a tube, meant to run through the periodic box:
    beyond its ends the distance is to the rim circles and counts as inside the
    shape for direction=-1, as in ESPResSo)."""

    _params = [Param("center", "vec3"), Param("axis", "vec3", check=unit_or_nonzero()),
               Param("radius", "float", check=positive), Param("length", "float", check=positive),
               Param("direction", "int", 1, check=direction_check),
               Param("open", "bool", False)]

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.Cylinder(self.center, self.axis, self.radius,
                                                         self.length, self.direction, self.open))


class Rhomboid(Shape):
    """Parallelepiped {corner + s a + t b + u c : 0 <= s, t, u <= 1}; outside,
    the exact distance (faces, edges, corners); inside, minus the distance to
    the nearest face. direction=-1: hollow (a box whose interior is free)."""

    _params = [Param("corner", "vec3"), Param("a", "vec3", check=unit_or_nonzero()),
               Param("b", "vec3", check=unit_or_nonzero()),
               Param("c", "vec3", check=unit_or_nonzero()),
               Param("direction", "int", 1, check=direction_check)]

    def _validate(self):
        a, b, c = self.a, self.b, self.c
        volume = abs(float(np.dot(a, np.cross(b, c))))
        if not volume > 1e-10 * np.linalg.norm(a) * np.linalg.norm(b) * np.linalg.norm(c):
            raise ValueError("Rhomboid: parameters 'a', 'b', 'c' must not be coplanar "
                             f"(the parallelepiped has no volume), got a={a.tolist()}, "
                             f"b={b.tolist()}, c={c.tolist()}")
        object.__setattr__(self, "_core", _lbmd.Rhomboid(self.corner, a, b, c, self.direction))


class SimplePore(Shape):
    """A slab of thickness length normal to axis, centred on center, pierced by
    a cylindrical channel of the given radius whose mouths are rounded with
    torus segments of radius smoothing_radius (0 <= smoothing_radius <=
    length/2). The shape is the slab material."""

    _params = [Param("center", "vec3"), Param("axis", "vec3", check=unit_or_nonzero()),
               Param("length", "float", check=positive), Param("radius", "float", check=positive),
               Param("smoothing_radius", "float", check=non_negative)]

    def _validate(self):
        if self.smoothing_radius > 0.5 * self.length:
            raise ValueError("SimplePore: parameter 'smoothing_radius' must be <= length/2 = "
                             f"{0.5 * self.length!r}, got {self.smoothing_radius!r}")
        object.__setattr__(self, "_core", _lbmd.SimplePore(
            self.center, self.axis, self.length, self.radius, self.smoothing_radius))


class Union(Shape):
    """Union of shapes: the signed distance is the smallest of the members'
    distances, the normal that member's. ``u.add(shape)`` or
    ``u.add([s1, s2])``, ``remove``, ``clear``, ``size()``; ``Union(shapes=[...])``
    adds at construction. An empty union occupies nothing (distance +inf)."""

    _params = [Param("shapes", "object", ())]

    def __init__(self, **kwargs):
        values = parse("Union", self._params, kwargs)
        object.__setattr__(self, "_values", {})
        object.__setattr__(self, "_core", _lbmd.Union())
        object.__setattr__(self, "_shapes", [])
        self.add(values["shapes"])

    @staticmethod
    def _each(owner, shape):
        # A Union is itself iterable: a shape is added as one member.
        is_many = isinstance(shape, collections.abc.Iterable) and not isinstance(shape, Shape)
        items = shape if is_many else [shape]
        for s in items:
            if not isinstance(s, Shape):
                raise TypeError(f"Union.{owner}: parameter 'shape' must be a Shape or an "
                                f"iterable of shapes, got {type(s).__name__}")
            yield s

    def add(self, shape):
        """Add a shape, or every shape of an iterable."""
        for s in list(self._each("add", shape)):
            self._core.add(s._core)
            self._shapes.append(s)

    def remove(self, shape):
        """Remove a shape, or every shape of an iterable."""
        for s in list(self._each("remove", shape)):
            if not any(s is m for m in self._shapes):
                raise ValueError("Union.remove: parameter 'shape' is not a member of this union")
            self._core.remove(s._core)
            self._shapes.remove(next(m for m in self._shapes if m is s))

    def clear(self):
        self._core.clear()
        self._shapes.clear()

    def _restore_core(self):
        object.__setattr__(self, "_core", _lbmd.Union())
        for s in self._shapes:
            self._core.add(s._core)

    def size(self):
        return len(self._shapes)

    def __len__(self):
        return len(self._shapes)

    def __iter__(self):
        return iter(list(self._shapes))

    def __getitem__(self, i):
        return self._shapes[i]

    @property
    def shapes(self):
        return list(self._shapes)

    def get_params(self):
        return {"shapes": list(self._shapes)}

    def __repr__(self):
        return f"Union(shapes={self._shapes!r})"


class Extrusion(Shape):
    """A 2D layout extruded along z: the solid is S x [z0, z1], where S is the
    interior of the closed ``polygons`` (each an (N, 2) array of vertices in
    the xy plane) by the even-odd rule: a polygon inside another is a hole,
    one inside a hole an island. Polygons must not cross, overlap or touch
    along an edge (they may share single vertices). ``direction=-1``: the
    complement, e.g. channels drawn as polygons, closed by a floor at z0 and a
    ceiling at z1, with the fluid inside. Distance and normal are exact.
    Layout files: :meth:`from_dxf`, :meth:`from_svg`, :meth:`from_mask`."""

    _params = [Param("polygons", "object"), Param("z", "object"),
               Param("direction", "int", 1, check=direction_check)]

    def __init__(self, *args, **kwargs):
        if args:
            raise TypeError("Extrusion: parameters are keywords, e.g. Extrusion(polygons=[...], z=[z0, z1])")
        values = parse("Extrusion", self._params, kwargs)
        object.__setattr__(self, "_values", _extrusion_values("Extrusion", values))
        object.__setattr__(self, "_names", [])
        self._validate()

    def _validate(self):
        object.__setattr__(self, "_core", _lbmd.Extrusion(
            list(self.polygons), self.z[0], self.z[1], self.direction, list(self._names)))

    @classmethod
    def _from_layout(cls, source, polygons, names, z, direction):
        """A shape from a file's polygons; errors name the file (`source`) and
        the polygon's entity (`names`)."""
        self = cls.__new__(cls)
        values = parse("Extrusion", cls._params, {"polygons": polygons, "z": z, "direction": direction})
        object.__setattr__(self, "_values", _extrusion_values("Extrusion", values))
        object.__setattr__(self, "_names", list(names))
        try:
            self._validate()
        except ValueError as e:
            raise ValueError(f"{source}: {e}") from None
        return self

    @classmethod
    def from_dxf(cls, path, z, layer=None, scale=1.0, tolerance=0.01, origin=(0.0, 0.0), direction=1):
        """The closed contours of a DXF file (ezdxf): closed LWPOLYLINE/POLYLINE
        (bulges), CIRCLE, ELLIPSE, closed SPLINE, and loops chained from LINE,
        ARC and open polylines whose ends meet; curves flattened so that no
        point is farther than ``tolerance`` (in file units) from the curve.
        ``layer``: only that layer. Coordinates: file units * scale + origin."""
        from . import layouts
        polygons, names = layouts.read_dxf(path, layer=layer, scale=scale, tolerance=tolerance,
                                           origin=origin)
        return cls._from_layout(path, polygons, names, z, direction)

    @classmethod
    def from_svg(cls, path, z, scale=1.0, tolerance=0.01, origin=(0.0, 0.0), direction=1):
        """The closed subpaths and shapes of an SVG file (svgelements), in the
        drawing's user units (those of its viewBox) after transforms, y
        flipped so that the drawing appears upright (y = bottom of the viewBox
        - y_svg); curves flattened to ``tolerance`` (user units).
        Coordinates: units * scale + origin."""
        from . import layouts
        polygons, names = layouts.read_svg(path, scale=scale, tolerance=tolerance, origin=origin)
        return cls._from_layout(path, polygons, names, z, direction)

    @classmethod
    def from_mask(cls, path, pixel_size, z, threshold=0.5, solid="black", origin=(0.0, 0.0),
                  direction=1):
        """The pixel regions of an image (PIL; grey levels below ``threshold``
        * 255 are black) as polygons along the exact pixel edges; ``solid``:
        which colour is the shape ("black" or "white"). The image's bottom-left
        corner is at ``origin``, a pixel is ``pixel_size`` wide; diagonal
        neighbours are separate regions (4-connected); transparent pixels
        count as white."""
        from . import layouts
        polygons, names = layouts.read_mask(path, pixel_size=pixel_size, threshold=threshold,
                                            solid=solid, origin=origin)
        return cls._from_layout(path, polygons, names, z, direction)

    def get_params(self):
        return {"polygons": [p.copy() for p in self.polygons], "z": self.z.copy(),
                "direction": self.direction}

    def __repr__(self):
        n = sum(len(p) for p in self.polygons)
        return (f"Extrusion(polygons=<{len(self.polygons)} polygon(s), {n} vertices>, "
                f"z={self.z.tolist()}, direction={self.direction})")


def _extrusion_values(owner, values):
    """polygons as a list of (N, 2) float arrays (copies) and z as [z0, z1]."""
    polygons = values["polygons"]
    if isinstance(polygons, np.ndarray) and polygons.ndim == 2:
        polygons = [polygons]  # one polygon
    if isinstance(polygons, (str, bytes)) or not isinstance(polygons, collections.abc.Iterable):
        raise TypeError(f"{owner}: parameter 'polygons' must be a list of (N, 2) vertex arrays, "
                        f"got {type(polygons).__name__}")
    out = []
    for k, p in enumerate(polygons):
        try:
            arr = np.array(p, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"{owner}: parameter 'polygons', polygon {k} must be an (N, 2) array "
                            f"of numbers, got {p!r}") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ValueError(f"{owner}: parameter 'polygons', polygon {k} must be an (N, 2) array "
                             f"of vertices, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{owner}: parameter 'polygons', polygon {k} has vertices that are not finite")
        out.append(arr)
    if not out:
        raise ValueError(f"{owner}: parameter 'polygons' must hold at least one polygon, got none")
    try:
        z = np.array(values["z"], dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{owner}: parameter 'z' must be [z0, z1], got {values['z']!r}") from None
    if z.shape != (2,) or not np.all(np.isfinite(z)) or not z[0] < z[1]:
        raise ValueError(f"{owner}: parameter 'z' must be [z0, z1] with finite z0 < z1, got {values['z']!r}")
    return {"polygons": out, "z": z, "direction": values["direction"]}


class SurfaceMesh(Shape):
    """The volume enclosed by a closed triangulated surface: ``file=`` (STL,
    ASCII or binary; OBJ, PLY, VTK, ... through meshio) or ``vertices=`` (N x 3)
    and ``triangles=`` (M x 3 vertex ids). Coordinates are ``scale * x +
    offset``. The surface must be closed, manifold, consistently oriented and
    without degenerate triangles (a ValueError names the first bad edge or
    triangle); one whose triangles all face inward is turned outward with a
    warning. Signed distance: exact distance to the nearest triangle (a
    bounding-box tree), sign from angle-weighted pseudo-normals (Bærentzen &
    Aanæs 2005). The vertices and triangles (outward) are kept as parameters,
    so the shape pickles without its file."""

    _params = [Param("file", "object", None), Param("vertices", "object", None),
               Param("triangles", "object", None), Param("scale", "float", 1.0, check=positive),
               Param("offset", "vec3", None), Param("direction", "int", 1, check=direction_check)]

    def __init__(self, *args, **kwargs):
        import os
        import warnings
        from .surface_io import mesh_arrays, read_surface  # the file readers live there
        if args:
            raise TypeError("SurfaceMesh: parameters are keywords, e.g. SurfaceMesh(file=...) "
                            "or SurfaceMesh(vertices=..., triangles=...)")
        values = parse("SurfaceMesh", self._params, kwargs)
        if values["offset"] is None:
            values["offset"] = np.zeros(3)
        if values["file"] is not None:
            if values["vertices"] is not None or values["triangles"] is not None:
                raise TypeError("SurfaceMesh: give either parameter 'file' or 'vertices' and "
                                "'triangles', not both")
            try:
                values["file"] = os.fspath(values["file"])
            except TypeError:
                raise TypeError("SurfaceMesh: parameter 'file' must be a path, got "
                                f"{values['file']!r}") from None
            values["vertices"], values["triangles"] = read_surface(values["file"])
        elif values["vertices"] is None or values["triangles"] is None:
            raise TypeError("SurfaceMesh: missing parameter 'file', or 'vertices' and 'triangles'")
        values["vertices"], values["triangles"] = mesh_arrays(values["vertices"],
                                                             values["triangles"])
        object.__setattr__(self, "_values", values)
        self._validate()
        if self._core.inverted:
            where = f"file {values['file']!r}" if values["file"] else "the given triangles"
            warnings.warn(f"SurfaceMesh: the triangles of {where} face inward (negative "
                          "enclosed volume); turned outward", stacklevel=2)
            values["triangles"] = np.ascontiguousarray(self._core.triangles, dtype=np.int32)

    def _validate(self):
        vertices = self.scale * self.vertices + self.offset
        object.__setattr__(self, "_core", _lbmd.SurfaceMesh(vertices, self.triangles,
                                                            self.direction))

    @property
    def volume(self):
        """The enclosed volume (scaled)."""
        return float(self._core.volume)

    def __repr__(self):
        source = f"file={self.file!r}" if self.file else "vertices=..., triangles=..."
        return (f"SurfaceMesh({source}, {len(self.vertices)} vertices, {len(self.triangles)} "
                f"triangles, scale={self.scale!r}, offset={self.offset.tolist()!r}, "
                f"direction={self.direction!r})")

