"""Cells packed to a haematocrit before a run: e.g.
``oif.pack_cells(system, rbc_type, haematocrit=0.45, boundaries=[tube], seed=1)``
fills a tube with red cells at 45 % of its volume, and
``oif.pack_cells(system, [rbc, big], haematocrit=0.3, fractions=[0.9, 0.1], ...)``
mixes two types (examples that run: doc/oif.md, "Packing cells").

Method: force-biased growth of rigid cells (the C++ ``RigidPacker``,
src/core/packing/). The cells start at half their size at random places
and orientations; every iteration each cell is pushed out of the cells and
walls it overlaps (a node's overlap is read from the other cell's level
set, a grid of its signed distance, so one lookup per node), moved and
turned by the mean overlap of its contacts with some momentum, and all
cells grow while the mean overlap is small, until they have their full
size and no node is closer than ``clearance`` to another cell's surface or
``wall_clearance`` to a boundary. Why this method: the cells keep their
reference shape exactly, so their volume and surface are the reference
values (a grown deformable cell would carry the stress of its growth into
the run), no fluid or membrane force is computed (so 1000 red cells pack in
seconds), and the result is checked exactly on the meshes afterwards. Why
not random placement (``oif.seed_cells``): it jams near a haematocrit of
0.2, because a new cell needs an empty hole of its own size.

The clearance defaults to what the advised contact (``oif.contact_settings``)
needs: every node of one cell at least the contact's offset plus a margin
away from every node of another, so the first step of a run starts with
every contact within its range.

After packing, the meshes are checked exactly: winding numbers of the nodes
near another cell (no node inside another cell), node-to-node distances
between cells and the nodes' signed distances to the boundaries. The
result is the list of OifCells with ``report``: the reached haematocrit,
the counts, the iterations and seconds, and the checks.
"""
import time

import numpy as np

from lbmd.validation import is_whole_number as _is_int

from . import mesh_io
from .seeding import (SeedingError, _count, _length, _per_type, _ptype, _region, _shares, _signed_distances,
                      _unit_axis, fluid_volume, rotation_to_angles)


#: the cells' size at the start of the growth (the C++ packer's default)
START_SCALE = 0.5


class PackingError(SeedingError):
    """The cells could not be packed (too dense for the geometry, or too large)."""


class PackedCells(list):
    """The OifCells a packing created (a list), with ``report``: a dict of
    what was reached and checked."""
    report = None


def covering_radius(cell_type):
    """The largest distance from a point on the cell type's relaxed surface
    to the nearest node of its triangle (the circumradius of an acute
    triangle, half the longest edge of an obtuse one): a node of another
    cell that keeps at least this far from every node of this one cannot
    pass through its surface."""
    x = cell_type.mesh._nodes
    t = cell_type.mesh._topo.triangles
    a, b, c = x[t[:, 0]], x[t[:, 1]], x[t[:, 2]]
    la, lb, lc = (np.linalg.norm(u, axis=1) for u in (b - c, c - a, a - b))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.maximum(np.maximum(la, lb), lc)
    obtuse = la ** 2 + lb ** 2 + lc ** 2 < 2 * longest ** 2
    return float(np.max(np.where(obtuse, 0.5 * longest, la * lb * lc / (4 * area))))


def _quaternion(rng):
    """Uniform random unit quaternion (w, x, y, z) (Shoemake 1992)."""
    u1, u2, u3 = rng.random(3)
    return np.array([np.sqrt(u1) * np.cos(2 * np.pi * u3), np.sqrt(1 - u1) * np.sin(2 * np.pi * u2),
                     np.sqrt(1 - u1) * np.cos(2 * np.pi * u2), np.sqrt(u1) * np.sin(2 * np.pi * u3)])


def _axis_quaternion(axis, angle):
    half = 0.5 * angle
    return np.concatenate([[np.cos(half)], np.sin(half) * axis])


def _shapes(boundaries):
    if boundaries is None:
        return []
    if hasattr(boundaries, "calc_dist"):
        return [boundaries]
    if not isinstance(boundaries, (list, tuple)):
        raise TypeError(f"pack_cells: parameter 'boundaries' must be a list of shapes, got "
                        f"{type(boundaries).__name__}")
    out = list(boundaries)
    for i, b in enumerate(out):
        if getattr(b, "_core", None) is None:
            raise TypeError(f"pack_cells: parameter 'boundaries': item {i} is not an lbmd shape, got "
                            f"{type(b).__name__}")
    return out


def _confined_axes(shapes, lo, hi, box, clearance):
    """Per axis: the fluid inside (lo, hi) outside every shape spans less
    than the box length minus the clearance (sampled on a grid of about
    1/40 of the region's shortest side)."""
    confined = np.zeros(3, dtype=bool)
    if not shapes:
        return confined
    spacing = max(float(np.min(hi - lo)) / 40.0, 1e-9)
    counts = np.maximum(np.round((hi - lo) / spacing).astype(int), 1)
    steps = (hi - lo) / counts
    axes = [l + (np.arange(c) + 0.5) * st for l, c, st in zip(lo, counts, steps)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    fluid = np.ones(len(grid), dtype=bool)
    for shape in shapes:
        fluid &= _signed_distances(shape)(grid) > 0.0
    if not fluid.any():
        return confined
    extent = np.ptp(grid[fluid], axis=0) + 2.0 * steps  # the cells' half a step beyond either end
    return extent + clearance < box


def pack_cells(system, cell_types, haematocrit=None, counts=None, fractions=None, boundaries=(), region=None,
               particle_types=None, particle_mass=1.0, seed=None, clearance=None, wall_clearance=None,
               rotation_axis=None, max_iterations=20000, create=True, exclusion_neighbours=True,
               self_cell_cutoff=None):
    """Pack cells of the given types (one OifCellType or a list) to a
    haematocrit (volume fraction of the fluid inside `region`, outside
    `boundaries`) or to `counts`, each at its exact reference shape; returns
    a PackedCells list of OifCell (create=False: of (type index, origin,
    rotate) placements) with ``report``.

    fractions: shares of the cell volume per type (default equal).
    boundaries: the shapes that bound the fluid (walls, tubes, obstacles,
    extrusions from CAD layouts). region: (lo, hi) corners the cells stay
    in (default the box). clearance: least distance of a node from another
    cell's surface (default: the advised contact's offset plus a margin,
    see the module's docstring); wall_clearance: least signed distance of a
    node from every boundary (default 0.25 um). rotation_axis: None (random
    orientations) or an axis about which alone the cells are turned at the
    start (e.g. discs stacked like coins in a narrow tube). seed: the same
    seed gives the same cells. Raises PackingError, naming the haematocrit
    reached, when the cells do not fit.
    """
    from lbmd import _lbmd
    import lbmd
    from .oif_classes import OifCell, OifCellType, _exclusion_rings, _real
    t_start = time.perf_counter()
    if not isinstance(system, lbmd.System):
        raise TypeError(f"pack_cells: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
    types = [cell_types] if isinstance(cell_types, OifCellType) else (
        list(cell_types) if isinstance(cell_types, (list, tuple)) else [])
    if not types or not all(isinstance(t, OifCellType) for t in types):
        raise TypeError("pack_cells: parameter 'cell_types' must be an OifCellType or a list of them")
    for i, t in enumerate(types):
        if t.system is not system:
            raise ValueError(f"pack_cells: cell type {i} belongs to another lbmd.System than parameter 'system'")
    k = len(types)
    particle_types = _per_type("particle_types", particle_types, k, _ptype, 0)
    particle_mass = _real("pack_cells", "particle_mass", particle_mass, "pos")
    _exclusion_rings("pack_cells", exclusion_neighbours)
    if seed is not None and (not _is_int(seed) or seed < 0):
        raise TypeError(f"pack_cells: parameter 'seed' must be an integer >= 0 or None, got {seed!r}")
    if not _is_int(max_iterations) or max_iterations < 1:
        raise TypeError(f"pack_cells: parameter 'max_iterations' must be an integer >= 1, got {max_iterations!r}")
    if not isinstance(create, (bool, np.bool_)):
        raise TypeError(f"pack_cells: parameter 'create' must be True or False, got {create!r}")
    axis = _unit_axis("pack_cells", rotation_axis)
    shapes = _shapes(boundaries)
    if len(system.part):
        raise ValueError(f"pack_cells: the system already holds {len(system.part)} particles, which the packing "
                         f"would not see; pack every cell type in one call (list them in 'cell_types') before "
                         f"adding other cells or particles")
    from .contacts import packing_clearance
    clearance = _length("clearance", clearance, "pack_cells")
    clearance = packing_clearance(types) if clearance is None else clearance
    wall_clearance = _length("wall_clearance", wall_clearance, "pack_cells")
    wall_clearance = 0.25 if wall_clearance is None else wall_clearance
    lo, hi = _region(system, region)
    box = np.asarray(system.box_l, dtype=float)
    periodic = np.asarray(system.periodicity, dtype=bool)
    vols = np.array([t.volume0 for t in types])
    v_fluid = fluid_volume(system, shapes, (lo, hi))
    if (counts is None) == (haematocrit is None):
        raise TypeError("pack_cells: give exactly one of 'counts' and 'haematocrit'")
    if counts is not None:
        counts = _per_type("counts", counts, k, _count, 0)
    else:
        if (isinstance(haematocrit, (bool, np.bool_)) or not isinstance(haematocrit, (int, float, np.floating))
                or not 0 < haematocrit < 1):
            raise ValueError(f"pack_cells: parameter 'haematocrit' must be a number in (0, 1), got {haematocrit!r}")
        fr = _shares("pack_cells", fractions, k)
        counts = [int(round(haematocrit * v_fluid * f / v)) for f, v in zip(fr, vols)]
    n = int(sum(counts))
    if n == 0:
        raise PackingError(f"pack_cells: no cells to pack (the haematocrit of a fluid volume {v_fluid:.4g} is "
                           f"less than one cell of volume {vols.min():.4g})")
    target = float(np.dot(counts, vols)) / v_fluid
    if target >= 0.74:
        raise PackingError(f"pack_cells: {n} cells fill {target:.3f} of the fluid volume {v_fluid:.4g}; rigid "
                           f"cells cannot be packed beyond about 0.6-0.7")

    # the packer: one level set per type (its nodes about their centroid)
    packer = _lbmd.RigidPacker()
    centroids = []
    for t in types:
        nodes = t.mesh._nodes
        centroid = nodes.mean(axis=0)
        centroids.append(centroid)
        extent = np.ptp(nodes, axis=0)
        spacing = float(min(0.15, extent.min() / 16.0)) if extent.min() > 0 else 0.15
        packer.add_type(nodes - centroid, mesh_io.outward(t.mesh._topo.triangles), spacing)
    for s in shapes:
        packer.add_boundary(s._core)

    # random start: centres in the fluid (by the boundaries' signed distance),
    # at least half the thinnest cell's width apart (minimum image): two
    # shrunken cells about one centre push each other symmetrically and
    # would not separate; larger cells first, types interleaved
    # reproducibly by the seed
    rng = np.random.default_rng(seed)
    order = sorted((i for i in range(k) for _ in range(counts[i])), key=lambda i: -vols[i])
    centres = np.empty((n, 3))
    quats = np.empty((n, 4))
    dist_fns = [_signed_distances(s) for s in shapes]
    apart = 0.5 * START_SCALE * min(float(np.ptp(t.mesh._nodes, axis=0).min()) for t in types)
    filled = 0
    for _ in range(1000):
        cand = lo + rng.random((4 * n, 3)) * (hi - lo)
        ok = np.ones(len(cand), dtype=bool)
        for f in dist_fns:
            ok &= f(cand) > 0.5 * wall_clearance
        for c in cand[ok]:
            if filled:
                d = centres[:filled] - c
                d[:, periodic] -= box[periodic] * np.round(d[:, periodic] / box[periodic])
                if np.einsum("ij,ij->i", d, d).min() < apart * apart:
                    continue
            centres[filled] = c
            filled += 1
            if filled == n:
                break
        if filled == n:
            break
    else:
        raise PackingError("pack_cells: found no room in the fluid inside the region to start the cells in; "
                           "check 'region' and 'boundaries'")
    for b, ti in enumerate(order):
        quats[b] = (_quaternion(rng) if axis is None else _axis_quaternion(axis, 2 * np.pi * rng.random()))
    packer.set_bodies(np.asarray(order, dtype=np.int32), centres, quats)
    # a periodic axis across which the boundaries confine the fluid to less
    # than the box (a tube across a periodic box): no cell can meet its own
    # image there, so the packer treats it as closed (its box faces lie
    # outside the fluid)
    packer_periodic = periodic & ~_confined_axes(shapes, lo, hi, box, clearance)
    settings = dict(box=box.tolist(), periodic=packer_periodic.tolist(), clearance=clearance,
                    wall_clearance=wall_clearance, max_iterations=int(max_iterations), final_tolerance=0.05,
                    start_scale=START_SCALE,
                    seed=int(seed or 0))
    if region is not None:
        settings["region"] = [lo.tolist(), hi.tolist()]
    result = packer.run(settings)
    check = packer.check(settings)
    reached = target * result["scale"] ** 3
    report = dict(haematocrit=target, counts=list(counts), fluid_volume=v_fluid, clearance=clearance,
                  wall_clearance=wall_clearance, iterations=result["iterations"], converged=result["converged"],
                  worst_overlap=result["worst_overlap"], worst_wall_overlap=result["worst_wall_overlap"],
                  nodes_inside_cells=check["nodes_inside_cells"], min_node_distance=check["min_node_distance"],
                  min_wall_distance=check["min_wall_distance"], pack_seconds=time.perf_counter() - t_start)
    if not result["converged"]:
        raise PackingError(
            f"pack_cells: {n} cells (haematocrit {target:.3f}) did not fit in {result['iterations']} iterations: "
            f"they reached {result['scale']:.3f} of their size (haematocrit {reached:.3f}) with nodes "
            f"{result['worst_overlap']:.3g} closer to other cells than the clearance {clearance:.3g} and "
            f"{result['worst_wall_overlap']:.3g} closer to the walls than {wall_clearance:.3g}. Lower the "
            f"haematocrit, enlarge the geometry, lower the clearance, align the cells (rotation_axis) or "
            f"raise max_iterations")
    centres = packer.centres()
    rotations = packer.rotations()
    placements = []
    for b, ti in enumerate(order):
        rot = rotations[b]
        placements.append((ti, centres[b] - rot @ centroids[ti], rotation_to_angles(rot)))
    out = PackedCells()
    out.report = report
    if not create:
        out.extend(placements)
        return out
    try:
        for ti, origin, angles in placements:
            out.append(OifCell(cell_type=types[ti], particle_type=particle_types[ti], origin=origin, rotate=angles,
                               particle_mass=particle_mass, exclusion_neighbours=exclusion_neighbours,
                               self_cell_cutoff=self_cell_cutoff, check_overlaps=False))
    except BaseException:
        for c in out:
            c._discard()
        raise
    report["seconds"] = time.perf_counter() - t_start
    return out
