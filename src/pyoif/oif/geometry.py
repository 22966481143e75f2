"""Vectorised mesh geometry on numpy arrays (nodes N x 3, index arrays).

Conventions as in PyOIF: a triangle (A, B, C) stored in the mesh has its
normal (B - A) x (C - A) pointing into the cell; a bending "angle" is a row
(A, B, C, D) of two triangles sharing the edge BC, with A and D the far
corners, and its size is the one of PyOIF's ``angle_btw_triangles``
(pi for a flat pair, in (0, 2 pi)).
"""
import numpy as np
from lbmd.interactions import membrane_angles

from .mesh_io import signed_volume


def triangle_normals(nodes, tris):
    """Unnormalised (B - A) x (C - A) of every row (A, B, C)."""
    a, b, c = nodes[tris[:, 0]], nodes[tris[:, 1]], nodes[tris[:, 2]]
    return np.cross(b - a, c - a)


def triangle_areas(nodes, tris):
    return 0.5 * np.linalg.norm(triangle_normals(nodes, tris), axis=1)


def surface(nodes, tris):
    return float(triangle_areas(nodes, tris).sum())


def volume(nodes, tris):
    """Enclosed volume for PyOIF-oriented triangles (inward normals):
    minus mesh_io.signed_volume (divergence theorem, positions relative to
    one node, as the engine takes them)."""
    return 0.0 - signed_volume(nodes, np.asarray(tris))  # 0.0 - x: never -0.0


def dihedral_angles(nodes, angles):
    """PyOIF's angle between triangles (P2, P1, P3) and (P2, P3, P4) for rows
    (P1, P2, P3, P4): pi for a flat pair, below pi when P4 lies on the side of
    (P1 - P2) x (P3 - P2), in [0, 2 pi). Computed by the engine's membrane
    component, the function its bending force (eq. 4) measures angles with, so
    that a relaxed mesh is exactly at its reference angles."""
    return membrane_angles(nodes, angles)


def edge_lengths(nodes, edges):
    return np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)


def rotation_matrix(rotate):
    """PyOIF's rotation by angles (a, b, c) about x, y, z: R = Rz(c) Ry(b) Rx(a)."""
    ca, sa = np.cos(rotate[0]), np.sin(rotate[0])
    cb, sb = np.cos(rotate[1]), np.sin(rotate[1])
    cc, sc = np.cos(rotate[2]), np.sin(rotate[2])
    rz = np.array([[cc, -sc, 0.0], [sc, cc, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
    return rz @ ry @ rx


def max_pair_distance(points):
    """Largest distance between two points (the cell's diameter): exact, via
    the candidates on the convex hull when scipy is there."""
    pts = np.asarray(points)
    if len(pts) > 60:
        try:
            from scipy.spatial import ConvexHull
            pts = pts[ConvexHull(pts).vertices]
        except Exception:  # degenerate (flat) point sets or no scipy: all pairs
            pass
    best = 0.0
    for i in range(0, len(pts), 256):  # blocks keep memory small
        d = np.linalg.norm(pts[i:i + 256, None, :] - pts[None, :, :], axis=2)
        best = max(best, float(d.max()))
    return best
