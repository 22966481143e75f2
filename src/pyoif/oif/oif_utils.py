"""Helper functions with the names of PyOIF's ``object_in_fluid.oif_utils``:
vector geometry of single triangles and dihedral angles, the elastic force
formulas of the model (doc/model.md, eqs. 3-7) for one element, and
legacy-VTK output of shapes (rhomboid, cylinder, pore) for ParaView.

The mesh-wide, vectorised versions live in ``oif.geometry``; these take
single points (lists or arrays of 3 numbers) as PyOIF's did.
"""
import math
import os

import numpy as np

from lbmd.validation import real_number as _real_number, vector3 as _vector3

from . import vtk as _vtk

small_epsilon = 1e-9
large_number = 1e7
output_precision = 14


def custom_str(realn):
    """A float with PyOIF's fixed output precision (14 decimals)."""
    return "{:.{prec}f}".format(realn, prec=output_precision)


def get_triangle_normal(a, b, c):
    """(b - a) x (c - a), not normalised."""
    a, b, c = (np.asarray(x, dtype=float) for x in (a, b, c))
    return np.cross(b - a, c - a)


def norm(vect):
    return float(np.linalg.norm(np.asarray(vect, dtype=float)))


def vec_distance(a, b):
    return norm(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def area_triangle(a, b, c):
    return 0.5 * norm(get_triangle_normal(a, b, c))


def angle_btw_triangles(P1, P2, P3, P4):
    """Angle between triangles (P2, P1, P3) and (P2, P3, P4) sharing the edge
    P2 P3: pi for a flat pair, in (0, 2 pi), the side decided by P4."""
    from .geometry import dihedral_angles
    pts = np.array([P1, P2, P3, P4], dtype=float)
    return float(dihedral_angles(pts, np.array([[0, 1, 2, 3]]))[0])


def angle_btw_vectors(a, b):
    """Angle between two vectors in [0, pi]."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    cos = np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(math.acos(min(1.0, max(-1.0, cos))))


def discard_epsilon(x):
    """0 for ``|x| < small_epsilon``, else x."""
    return 0.0 if -small_epsilon < x < small_epsilon else x


def oif_neo_hookean_nonlin(lambd):
    """Neo-Hookean factor kappa(lambda) = (lambda^0.5 + lambda^-2.5) /
    (lambda + lambda^-3) of the stretching force (model eq. 3; Dupin et al.
    2007, eq. 19)."""
    return (lambd ** 0.5 + lambd ** -2.5) / (lambd + lambd ** -3.0)


def oif_calc_stretching_force(ks, pA, pB, dist0, dist):
    """Force on A from the neo-Hookean spring AB (eq. 3); B gets minus it."""
    pA, pB = np.asarray(pA, dtype=float), np.asarray(pB, dtype=float)
    fac = ks * oif_neo_hookean_nonlin(dist / dist0) * (dist - dist0)
    return fac * (pB - pA) / dist


def oif_calc_linear_stretching_force(ks, pA, pB, dist0, dist):
    """Force on A from the linear spring AB (eq. 3 with kappa = 1)."""
    pA, pB = np.asarray(pA, dtype=float), np.asarray(pB, dtype=float)
    return ks * (dist - dist0) * (pB - pA) / dist


def oif_calc_bending_force(kb, pA, pB, pC, pD, phi0, phi):
    """PyOIF's bending force estimate for the far corners A and D of the
    triangle pair (A, B, C), (B, C, D): 6 numbers (force on A, on D), each
    k_b (phi - phi0)/phi0 along the unit normal of its triangle."""
    n1 = get_triangle_normal(pB, pA, pC)
    n2 = get_triangle_normal(pB, pC, pD)
    fac = kb * (phi - phi0) / phi0
    f1 = fac * n1 / np.linalg.norm(n1)
    f2 = fac * n2 / np.linalg.norm(n2)
    return [*f1, *f2]


def oif_calc_local_area_force(kal, pA, pB, pC, A0, A):
    """Local area force (eq. 5) on A, B, C: 9 numbers."""
    pA, pB, pC = (np.asarray(x, dtype=float) for x in (pA, pB, pC))
    centroid = (pA + pB + pC) / 3.0
    t = [centroid - p for p in (pA, pB, pC)]
    fac = kal * (A - A0) / sum(float(np.dot(x, x)) for x in t)
    return [c for x in t for c in fac * x]


def oif_calc_global_area_force(kag, pA, pB, pC, Ag0, Ag):
    """Global area force (eq. 6, without the 1/S_cell0 normalisation as in
    PyOIF's helper) on A, B, C of one triangle: 9 numbers."""
    pA, pB, pC = (np.asarray(x, dtype=float) for x in (pA, pB, pC))
    centroid = (pA + pB + pC) / 3.0
    t = [centroid - p for p in (pA, pB, pC)]
    fac = kag * area_triangle(pA, pB, pC) * (Ag - Ag0) / sum(float(np.dot(x, x)) for x in t)
    return [c for x in t for c in fac * x]


def oif_calc_volume_force(kv, pA, pB, pC, V0, V):
    """Volume force (eq. 7) on each node of the triangle (A, B, C), PyOIF
    orientation (normal inward): k_v (V - V0)/V0 S n / 3."""
    n = get_triangle_normal(pA, pB, pC)
    dn = np.linalg.norm(n)
    return kv * (V - V0) / V0 * area_triangle(pA, pB, pC) * n / (dn * 3.0)


# ---------------------------------------------------------------------------
# VTK output of shapes (legacy ASCII polydata; ParaView opens it)
# ---------------------------------------------------------------------------
def _shape_value(owner, shape, name, kind):
    """A shape's attribute, checked: kind 'vec' (3 finite numbers), 'dir'
    (3 finite numbers, not all zero) or 'pos' (a finite number > 0)."""
    if isinstance(shape, (str, bytes, os.PathLike)) or not hasattr(shape, name):
        raise TypeError(f"{owner}: the shape argument must be a shape with '{name}' (e.g. "
                        f"lbmd.shapes.{'Rhomboid' if owner.endswith('rhomboid') else 'Cylinder'}), "
                        f"got {type(shape).__name__}")
    return _checked(owner, name, getattr(shape, name), kind)


def _checked(owner, name, value, kind):
    """TypeError for what is not numbers, ValueError for bad values (as the
    lbmd parameters)."""
    if kind in ("pos", "nonneg"):
        return _real_number(f"{owner}: '{name}'", value, kind)
    arr = _vector3(f"{owner}: '{name}'", value)
    if kind == "dir" and not np.any(arr != 0):
        raise ValueError(f"{owner}: '{name}' must not be the zero vector (it is a direction)")
    return arr


def output_vtk_rhomboid(rhom_shape, out_file):
    """The 6 faces of a Rhomboid(corner, a, b, c) as quads."""
    owner = "output_vtk_rhomboid"
    corner = _shape_value(owner, rhom_shape, "corner", "vec")
    a, b, c = (_shape_value(owner, rhom_shape, k, "dir") for k in ("a", "b", "c"))
    if abs(np.dot(np.cross(a, b), c)) <= 1e-12 * np.linalg.norm(a) * np.linalg.norm(b) * np.linalg.norm(c):
        raise ValueError(f"{owner}: edge vectors a, b, c are coplanar (the rhomboid has no volume)")
    pts = np.array([corner, corner + a, corner + a + b, corner + b,
                    corner + c, corner + a + c, corner + a + b + c, corner + b + c])
    quads = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [0, 4, 7, 3], [1, 2, 6, 5]]
    _vtk.write_polydata(out_file, pts, polygons=quads)
    return 0


def _perpendicular_basis(axis):
    axis = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return axis, e1, np.cross(axis, e1)


def output_vtk_cylinder(cyl_shape, n, out_file):
    """A Cylinder(center, axis, radius, length) as n side quads and two n-gon
    caps; any axis direction (PyOIF supported only axes along z)."""
    owner = "output_vtk_cylinder"
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise ValueError(f"{owner}: parameter 'n' must be an integer >= 3, got {n!r}")
    center = _shape_value(owner, cyl_shape, "center", "vec")
    axis, e1, e2 = _perpendicular_basis(_shape_value(owner, cyl_shape, "axis", "dir"))
    radius = _shape_value(owner, cyl_shape, "radius", "pos")
    length = _shape_value(owner, cyl_shape, "length", "pos")
    phi = 2.0 * np.pi * np.arange(n) / n
    ring = radius * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
    bottom = center - 0.5 * length * axis + ring
    top = center + 0.5 * length * axis + ring
    pts = np.vstack([bottom, top])
    polys = [list(range(n)), list(range(n, 2 * n))]
    polys += [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    _vtk.write_polydata(out_file, pts, polygons=polys)
    return 0


def output_vtk_lines(lines, out_file):
    """Line segments, each row (x1, y1, z1, x2, y2, z2)."""
    try:
        lines = np.asarray(lines, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("output_vtk_lines: 'lines' must be rows of 6 numbers (x1, y1, z1, x2, y2, z2)") from None
    if lines.size % 6 or not np.all(np.isfinite(lines)):
        raise ValueError(f"output_vtk_lines: 'lines' must be rows of 6 finite numbers (x1, y1, z1, x2, y2, z2), "
                         f"got shape {lines.shape}")
    lines = lines.reshape(-1, 6)
    pts = lines.reshape(-1, 3)
    _vtk.write_polydata(out_file, pts, lines=[[2 * i, 2 * i + 1] for i in range(len(lines))])
    return 0


def output_vtk_pore(axis, length, outer_rad_left, outer_rad_right, pos, rad_left, rad_right,
                    smoothing_radius, m, out_file):
    """A SimplePore-like channel through a wall: the inner surface of
    revolution (left radius to right radius over `length`) with rounded
    (torus) entrances of `smoothing_radius`, discretised with 2 m sections
    around and m along each rounding; any axis direction."""
    owner = "output_vtk_pore"
    if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or m < 2:
        raise ValueError(f"{owner}: parameter 'm' must be an integer >= 2, got {m!r}")
    axis, e1, e2 = _perpendicular_basis(_checked(owner, "axis", axis, "dir"))
    pos = _checked(owner, "pos", pos, "vec")
    length = _checked(owner, "length", length, "pos")
    rad_left = _checked(owner, "rad_left", rad_left, "pos")
    rad_right = _checked(owner, "rad_right", rad_right, "pos")
    smoothing_radius = _checked(owner, "smoothing_radius", smoothing_radius, "nonneg")
    outer_rad_left = _checked(owner, "outer_rad_left", outer_rad_left, "pos")
    outer_rad_right = _checked(owner, "outer_rad_right", outer_rad_right, "pos")
    # the annuli that close the faces run from the rounded entrance out to the outer radius
    for side, inner, outer in (("left", rad_left, outer_rad_left), ("right", rad_right, outer_rad_right)):
        if outer <= inner + smoothing_radius:
            raise ValueError(f"{owner}: outer_rad_{side} ({outer!r}) must be larger than rad_{side} + "
                             f"smoothing_radius ({inner + smoothing_radius!r})")
    n = 2 * m
    # profile (x along the axis, r radius): left rounding, straight part, right rounding
    prof = []
    for j in range(m + 1):  # left entrance: quarter circle from the wall face to the bore
        t = 0.5 * np.pi * j / m
        prof.append((-0.5 * length - smoothing_radius * np.cos(t),
                     rad_left + smoothing_radius * (1.0 - np.sin(t))))
    for j in range(m + 1):
        t = 0.5 * np.pi * j / m
        prof.append((0.5 * length + smoothing_radius * np.sin(t),
                     rad_right + smoothing_radius * (1.0 - np.cos(t))))
    # outer radii close the pore's faces as annuli
    prof = [(prof[0][0], outer_rad_left)] + prof + [(prof[-1][0], outer_rad_right)]
    phi = 2.0 * np.pi * np.arange(n) / n
    pts = []
    for x, r in prof:
        pts.extend(pos + x * axis + r * (np.cos(p) * e1 + np.sin(p) * e2) for p in phi)
    polys = []
    for j in range(len(prof) - 1):
        for i in range(n):
            polys.append([j * n + i, j * n + (i + 1) % n, (j + 1) * n + (i + 1) % n, (j + 1) * n + i])
    _vtk.write_polydata(out_file, np.array(pts), polygons=polys)
    return 0
