"""Shared by the shear-flow validations (capsule_shear.py, rbc_shear.py):
the Couette scene (a cell midway between two LB walls moving at -U and +U,
periodic along the flow x and the vorticity y, gradient z) and the
equivalent-ellipsoid measurement of a triangulated membrane.

Lattice units: agrid 1, time step 0.1, density 1, kinematic viscosity 1.5
(with 1 um, 1 us, 1e-15 kg: the dynamic viscosity 1.5 mPa s of plasma)."""
import math

import numpy as np

import lbmd
from lbmd import lb, lbboundaries, shapes

AGRID, TIME_STEP, DENS, VISC = 1.0, 0.1, 1.0, 1.5  # lattice units; visc is kinematic, eta = DENS * VISC
ETA = DENS * VISC


def couette_system(lx, ly, height):
    """A System for a channel of height `height` (fluid nodes between the
    walls) with one wall node layer on each side: box lx x ly x (height + 2)."""
    system = lbmd.System(box_l=[lx, ly, height + 2.0 * AGRID])
    system.time_step = TIME_STEP
    system.cell_system.skin = 0.2
    return system


def add_couette_flow(system, shear_rate, gamma):
    """The fluid, the two walls moving at -U (bottom) and +U (top) with
    U = shear_rate H / 2 (simple shear of rate `shear_rate` between them),
    and the friction coupling `gamma` of the membrane nodes; returns the fluid."""
    lz = system.box_l[2]
    height = lz - 2.0 * AGRID
    fluid = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TIME_STEP)
    system.actors.add(fluid)
    wall_speed = 0.5 * shear_rate * height
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, 1], dist=AGRID),
                                                    velocity=[-wall_speed, 0, 0]))
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, -1], dist=-(lz - AGRID)),
                                                    velocity=[wall_speed, 0, 0]))
    system.thermostat.set_lb(LB_fluid=fluid, gamma=gamma)
    return fluid


def volume_second_moment(pos, triangles):
    """Volume V, centroid and second moment M = int (x - c)(x - c)^T dV of the
    body enclosed by the triangulated surface (outward normals), from the
    signed tetrahedra (c, p1, p2, p3): int_tet x x^T dV = det/120 (sum_i
    v_i v_i^T + (sum_i v_i)(sum_i v_i)^T) for vertices v_i relative to c."""
    c = pos.mean(axis=0)
    p = pos[triangles] - c  # (T, 3, 3)
    det = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2]))
    vol = det.sum() / 6.0
    # the volume centroid, then the moment about it
    centroid = (det[:, None] * p.sum(axis=1)).sum(axis=0) / 24.0 / vol + c
    p = pos[triangles] - centroid
    det = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2]))
    s = p.sum(axis=1)
    m = (np.einsum("t,tij,tik->jk", det, p, p) + np.einsum("t,tj,tk->jk", det, s, s)) / 120.0
    return vol, centroid, m


def shear_plane_ellipse(pos, triangles):
    """The equivalent ellipsoid's section in the shear plane (x flow, z
    gradient): (semi-axes L >= B, unit long axis (x, z), centroid). The
    eigenvalues of the x-z block of the second moment are V L^2/5 and V B^2/5."""
    vol, centroid, m = volume_second_moment(pos, triangles)
    block = m[np.ix_([0, 2], [0, 2])] / vol  # / vol: independent of the triangles' orientation
    w, v = np.linalg.eigh(block)
    b, length = np.sqrt(5.0 * np.clip(w, 0.0, None))
    return length, b, v[:, 1], centroid


def taylor_deformation(pos, triangles):
    """(D, inclination angle in degrees) of the equivalent ellipsoid in the
    shear plane: D = (L - B)/(L + B), the long axis's angle to the flow in
    (-90, 90]."""
    length, b, axis, _ = shear_plane_ellipse(pos, triangles)
    angle = math.degrees(math.atan2(axis[1], axis[0]))
    angle = (angle + 90.0) % 180.0 - 90.0
    return (length - b) / (length + b), angle
