#!/usr/bin/env python3
"""Generate the meshes shipped in src/pyoif/oif/meshes (run with /usr/bin/python3).

    maintainer/generate_meshes.py [output_folder]

Spheres (radius 1): icosahedron subdivided k times, new nodes projected on
the sphere (10 * 4^k + 2 nodes: 162, 642, 2562).

Red blood cells (radius 1 in x and y; scale with OifCellType(resize=...)):
the biconcave discocyte of Evans & Fung (1972),

    z(r) = +/- (1/2) sqrt(1 - (r/R0)^2) (c0 + c1 (r/R0)^2 + c2 (r/R0)^4),
    R0 = 3.91 um, c0 = 0.81 um, c1 = 7.83 um, c2 = -4.39 um,

(E. A. Evans and Y.-C. Fung, "Improved measurements of the erythrocyte
geometry", Microvasc. Res. 4, 335-347, 1972), here divided by R0 so that
r/R0 = s in [0, 1]: z = +/- sqrt(1 - s^2) g(s^2), g(q) = C0 + C1 q + C2 q^2,
C_i = c_i / (2 R0). A point of the unit sphere (x, y, z) maps onto the RBC
as (x, y, z g(x^2 + y^2)) (smooth; z = cos(alpha), s = sin(alpha)). Nodes
are placed on a spherical Fibonacci spiral whose polar spacing follows the
RBC's cumulative area (so the RBC nodes are evenly spread), triangulated
by the convex hull on the sphere (a spherical Delaunay triangulation), then
smoothed a few times tangentially on the RBC surface, every node projected
exactly onto it.

Triangles are written in PyOIF's orientation: (B - A) x (C - A) points into
the cell, as in ESPResSo's object_in_fluid meshes.
"""
import os
import sys

import numpy as np
from scipy.spatial import ConvexHull

R0_UM = 3.91
C_UM = (0.81, 7.83, -4.39)
C = tuple(c / (2.0 * R0_UM) for c in C_UM)

SPHERE_LEVELS = (2, 3, 4)
RBC_NODES = (162, 374, 642, 1002, 2562)


def g(q):
    return C[0] + C[1] * q + C[2] * q * q


def dg(q):
    return C[1] + 2.0 * C[2] * q


def rbc_profile(alpha):
    """(rho, z) of the RBC meridian at polar parameter alpha in [0, pi]."""
    s = np.sin(alpha)
    return s, np.cos(alpha) * g(s * s)


def rbc_profile_derivative(alpha):
    s, c = np.sin(alpha), np.cos(alpha)
    return c, -s * g(s * s) + c * dg(s * s) * 2.0 * s * c


def rbc_point(alpha, phi):
    rho, z = rbc_profile(alpha)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=-1)


def project_to_rbc(p, alpha_guess=None):
    """(alpha, phi) of the RBC surface point nearest to each p (N x 3): the
    nearest point of a surface of revolution lies in the point's meridian
    plane, so this is a 1D minimisation over alpha (grid, then Newton)."""
    phi = np.arctan2(p[:, 1], p[:, 0])
    rho_p = np.hypot(p[:, 0], p[:, 1])
    z_p = p[:, 2]
    if alpha_guess is None:
        grid = np.linspace(0.0, np.pi, 4001)
        gr, gz = rbc_profile(grid)
        d = (gr[None, :] - rho_p[:, None]) ** 2 + (gz[None, :] - z_p[:, None]) ** 2
        alpha = grid[np.argmin(d, axis=1)]
    else:
        alpha = alpha_guess.copy()
    h = 1e-6
    for _ in range(30):
        def dist2(a):
            r, z = rbc_profile(a)
            return (r - rho_p) ** 2 + (z - z_p) ** 2
        d1 = (dist2(alpha + h) - dist2(alpha - h)) / (2 * h)
        d2 = (dist2(alpha + h) - 2 * dist2(alpha) + dist2(alpha - h)) / (h * h)
        step = np.where(d2 > 0, d1 / np.where(d2 > 0, d2, 1.0), 0.0)
        step = np.clip(step, -0.05, 0.05)
        alpha = np.clip(alpha - step, 0.0, np.pi)
        if np.max(np.abs(step)) < 1e-13:
            break
    return alpha, phi


def rbc_area_cdf(n=20001):
    """Cumulative RBC surface area fraction F(alpha) (surface of revolution:
    dA = 2 pi rho sqrt(rho'^2 + z'^2) dalpha)."""
    alpha = np.linspace(0.0, np.pi, n)
    rho, _ = rbc_profile(alpha)
    dr, dz = rbc_profile_derivative(alpha)
    dens = rho * np.hypot(dr, dz)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(alpha))])
    return alpha, cdf / cdf[-1]


def fibonacci_directions(n, cdf=None):
    """n points (alpha, phi) on a Fibonacci spiral; alpha spaced so that the
    cumulative area fraction (uniform sphere if cdf is None) is (i + 0.5)/n."""
    u = (np.arange(n) + 0.5) / n
    if cdf is None:
        alpha = np.arccos(1.0 - 2.0 * u)
    else:
        alpha = np.interp(u, cdf[1], cdf[0])
    phi = np.mod(np.arange(n) * np.pi * (3.0 - np.sqrt(5.0)), 2.0 * np.pi)
    return alpha, phi


def sphere_hull_triangles(alpha, phi):
    """Triangles (outward) of the convex hull of the unit-sphere points."""
    pts = np.stack([np.sin(alpha) * np.cos(phi), np.sin(alpha) * np.sin(phi), np.cos(alpha)], axis=1)
    tris = ConvexHull(pts).simplices.copy()
    n = np.cross(pts[tris[:, 1]] - pts[tris[:, 0]], pts[tris[:, 2]] - pts[tris[:, 0]])
    inward = np.einsum("ij,ij->i", n, pts[tris].mean(axis=1)) < 0
    tris[inward] = tris[inward][:, [0, 2, 1]]
    return tris


def neighbours(tris, n):
    nb = [set() for _ in range(n)]
    for a, b, c in tris:
        nb[a].update((b, c))
        nb[b].update((a, c))
        nb[c].update((a, b))
    return [np.array(sorted(x)) for x in nb]


def rbc_mesh(n_nodes, smoothing_steps=60, relax=0.3):
    alpha, phi = fibonacci_directions(n_nodes, rbc_area_cdf())
    tris = sphere_hull_triangles(alpha, phi)
    nb = neighbours(tris, n_nodes)
    pos = rbc_point(alpha, phi)
    for _ in range(smoothing_steps):
        # Laplacian smoothing: move each node towards its neighbours' mean,
        # then back onto the surface (tangential in effect)
        target = np.array([pos[x].mean(axis=0) for x in nb])
        moved = pos + relax * (target - pos)
        alpha, phi = project_to_rbc(moved, alpha)
        pos = rbc_point(alpha, phi)
    return pos, tris


def icosphere(level):
    t = (1.0 + np.sqrt(5.0)) / 2.0
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
             (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(v, dtype=float) / np.linalg.norm(v) for v in verts]
    for _ in range(level):
        cache = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]
        new = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    pos = np.array(verts)
    tris = np.array(faces, dtype=np.int64)
    n = np.cross(pos[tris[:, 1]] - pos[tris[:, 0]], pos[tris[:, 2]] - pos[tris[:, 0]])
    assert np.all(np.einsum("ij,ij->i", n, pos[tris].mean(axis=1)) > 0)  # outward
    return pos, tris


def quality(pos, tris):
    e = np.concatenate([np.linalg.norm(pos[tris[:, i]] - pos[tris[:, (i + 1) % 3]], axis=1) for i in range(3)])
    angles = []
    for i in range(3):
        u = pos[tris[:, (i + 1) % 3]] - pos[tris[:, i]]
        v = pos[tris[:, (i + 2) % 3]] - pos[tris[:, i]]
        angles.append(np.degrees(np.arccos(np.einsum("ij,ij->i", u, v) /
                                           (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1)))))
    angles = np.concatenate(angles)
    return e.min() / e.mean(), e.max() / e.mean(), angles.min()


def write(folder, name, pos, tris_outward):
    tris = tris_outward[:, [0, 2, 1]]  # PyOIF orientation: normals into the cell
    np.savetxt(os.path.join(folder, f"{name}nodes.dat"), pos, fmt="%.15g")
    np.savetxt(os.path.join(folder, f"{name}triangles.dat"), tris, fmt="%d")
    lo, hi, amin = quality(pos, tris)
    print(f"{name}: {len(pos)} nodes, {len(tris)} triangles, edge min/mean {lo:.2f}, "
          f"max/mean {hi:.2f}, smallest triangle angle {amin:.1f} deg")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "src", "pyoif", "oif", "meshes")
    os.makedirs(folder, exist_ok=True)
    for level in SPHERE_LEVELS:
        pos, tris = icosphere(level)
        write(folder, f"sphere{len(pos)}", pos, tris)
    for n in RBC_NODES:
        pos, tris = rbc_mesh(n)
        write(folder, f"rbc{n}", pos, tris)


if __name__ == "__main__":
    main()
