"""Random placement of many cells in a geometry, without overlaps.

    cells = oif.seed_cells(system, [rbc_type, rare_type], counts=[40, 1],
                           boundaries=[wall_bottom, wall_top, obstacle],
                           particle_types=[0, 1], seed=12)
    cells = oif.seed_cells(system, rbc_type, haematocrit=0.04, boundaries=walls, seed=3)

Cells are placed one by one at uniformly random centres (inside `region`)
with uniformly random orientations, and a placement is kept only if

- every node is at least `margin` outside every boundary shape (signed
  distance, positive where the fluid is),
- every node is at least `gap` from every node of the cells placed before
  (minimum image across periodic box faces), where `gap` is at least 1.2 x
  the longer of the two meshes' longest edges: two triangulated surfaces
  that intersect always have a pair of nodes closer than that, so no two
  cells interpenetrate,
- the new cell's centre is not inside another cell and no other cell's
  centre is inside the new one (one cell swallowing a small one).

The same `seed` gives the same cells. When the next cell cannot be placed
in `max_attempts` tries, ``SeedingError`` says how many were placed and
which haematocrit that is.
"""
import numpy as np

from . import mesh_io


class SeedingError(ValueError):
    """The requested cells do not fit (too many, too large, too little room)."""


def _random_rotation(rng):
    """Uniform random rotation (Shoemake's quaternion method) as a matrix."""
    u1, u2, u3 = rng.random(3)
    q = np.array([np.sqrt(1 - u1) * np.sin(2 * np.pi * u2), np.sqrt(1 - u1) * np.cos(2 * np.pi * u2),
                  np.sqrt(u1) * np.sin(2 * np.pi * u3), np.sqrt(u1) * np.cos(2 * np.pi * u3)])
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def rotation_to_angles(rot):
    """PyOIF's rotate=(a, b, c) (R = Rz(c) Ry(b) Rx(a)) of a rotation matrix."""
    b = -np.arcsin(np.clip(rot[2, 0], -1.0, 1.0))
    a = np.arctan2(rot[2, 1], rot[2, 2])
    c = np.arctan2(rot[1, 0], rot[0, 0])
    return np.array([a, b, c])


def _signed_distance(shape):
    """Fast signed distance of a point to an lbmd shape (its C++ object
    directly, without per-call argument checks) or any object with calc_dist."""
    core = getattr(shape, "_core", None)
    if core is not None and hasattr(core, "calc_dist"):
        return lambda p: core.calc_dist(p)[0]
    return lambda p: shape.calc_dist(p)[0]


def _min_image(d, box, periodic):
    d = d.copy()
    d[..., periodic] -= box[periodic] * np.round(d[..., periodic] / box[periodic])
    return d


def _winding_number(point, nodes, outward_tris):
    """Generalised winding number of a closed surface around point (1 inside,
    0 outside): the solid angle of every triangle over 4 pi (Van Oosterom &
    Strackee 1983)."""
    a = nodes[outward_tris[:, 0]] - point
    b = nodes[outward_tris[:, 1]] - point
    c = nodes[outward_tris[:, 2]] - point
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la
           + np.einsum("ij,ij->i", c, a) * lb)
    return float(np.sum(2.0 * np.arctan2(num, den)) / (4.0 * np.pi))


def fluid_volume(system, boundaries, region=None, spacing=None):
    """Volume of the part of `region` ((lo, hi) corners, default the box)
    outside every boundary shape: a grid of cubes, each counted with the
    fraction clip(1/2 + d/spacing, 0, 1) from the signed distance d of its
    centre (exact for planes parallel to the grid, second order otherwise)."""
    lo, hi = _region(system, region)
    if not boundaries:
        return float(np.prod(hi - lo))
    spacing = spacing or max(float(np.min(hi - lo)) / 40.0, 1e-9)
    counts = np.maximum(np.round((hi - lo) / spacing).astype(int), 1)
    steps = (hi - lo) / counts
    axes = [l + (np.arange(c) + 0.5) * st for l, c, st in zip(lo, counts, steps)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    fraction = np.ones(len(grid))
    for shape in boundaries:
        dist = _signed_distance(shape)
        d = np.array([dist(p) for p in grid])
        fraction = np.minimum(fraction, np.clip(0.5 + d / steps.min(), 0.0, 1.0))
    return float(np.prod(steps) * fraction.sum())


def _region(system, region):
    box = np.asarray(system.box_l, dtype=float)
    if region is None:
        return np.zeros(3), box
    lo, hi = (np.asarray(x, dtype=float) for x in region)
    if lo.shape != (3,) or hi.shape != (3,) or not np.all(hi > lo):
        raise ValueError(f"seed_cells: parameter 'region' must be two corners (lo, hi) with hi > lo, got {region!r}")
    return lo, hi


def seed_cells(system, cell_types, counts=None, haematocrit=None, fractions=None, boundaries=(), region=None,
               particle_types=None, particle_mass=1.0, seed=None, margin=None, gap=None, max_attempts=2000,
               exclusion_neighbours=True, self_cell_cutoff=None, create=True):
    """Place cells of the given types (one OifCellType or a list) at random,
    without overlaps; returns the list of OifCell (or, create=False, the
    list of (type index, origin, rotate) placements).

    counts: number of cells per type (int or list), or haematocrit: target
    volume fraction of the fluid (inside `region`, outside `boundaries`),
    split between types by `fractions` of the cell volume (default equal).
    particle_types: particle type per cell type (default 0 for all).
    margin: least node distance from boundaries (default 0.5 x the longest
    edge). gap: least node distance between cells (default 1.2 x longest edge).
    """
    from .oif_classes import OifCell, OifCellType
    types = [cell_types] if isinstance(cell_types, OifCellType) else list(cell_types)
    if not types or not all(isinstance(t, OifCellType) for t in types):
        raise TypeError("seed_cells: parameter 'cell_types' must be an OifCellType or a list of them")
    k = len(types)
    if particle_types is None:
        particle_types = [0] * k
    elif np.ndim(particle_types) == 0:
        particle_types = [int(particle_types)] * k
    if len(particle_types) != k:
        raise ValueError(f"seed_cells: parameter 'particle_types' needs {k} values, got {particle_types!r}")
    boundaries = list(boundaries)
    lo, hi = _region(system, region)
    vols = np.array([t.volume0 for t in types])
    if (counts is None) == (haematocrit is None):
        raise TypeError("seed_cells: give exactly one of 'counts' and 'haematocrit'")
    v_fluid = None
    if counts is not None:
        counts = [int(counts)] * k if np.ndim(counts) == 0 else [int(c) for c in counts]
        if len(counts) != k or min(counts) < 0:
            raise ValueError(f"seed_cells: parameter 'counts' needs {k} values >= 0, got {counts!r}")
    else:
        if not 0 < haematocrit < 1:
            raise ValueError(f"seed_cells: parameter 'haematocrit' must be in (0, 1), got {haematocrit!r}")
        fr = np.ones(k) / k if fractions is None else np.asarray(fractions, dtype=float)
        if fr.shape != (k,) or np.any(fr < 0) or fr.sum() <= 0:
            raise ValueError(f"seed_cells: parameter 'fractions' needs {k} values >= 0, got {fractions!r}")
        fr = fr / fr.sum()
        v_fluid = fluid_volume(system, boundaries, (lo, hi))
        counts = [int(round(haematocrit * v_fluid * f / v)) for f, v in zip(fr, vols)]
        if sum(counts) == 0:
            raise SeedingError(f"seed_cells: haematocrit {haematocrit} of a fluid volume {v_fluid:.4g} is "
                               f"less than one cell (cell volume {vols.min():.4g})")
        # random close packing of deformable discs is far below 1; beyond ~0.6 rigid placement cannot work
        if sum(c * v for c, v in zip(counts, vols)) > 0.6 * v_fluid:
            raise SeedingError(f"seed_cells: haematocrit {haematocrit} cannot be reached by random placement "
                               f"of undeformed cells (at most about 0.6 of the fluid volume {v_fluid:.4g}); "
                               f"seed fewer cells and compress, or enlarge the geometry")
    longest = max(t.mesh.max_edge_length() for t in types)
    margin = 0.5 * longest if margin is None else float(margin)
    gap = 1.2 * longest if gap is None else max(float(gap), 1.2 * longest)
    rng = np.random.default_rng(seed)
    box = np.asarray(system.box_l, dtype=float)
    periodic = np.asarray(system.periodicity, dtype=bool)

    # order: larger cells first (harder to place), types interleaved reproducibly
    order = sorted((i for i in range(k) for _ in range(counts[i])), key=lambda i: -vols[i])
    placed = []  # (type index, origin, rotation matrix, nodes, centre, radius)
    for n_done, ti in enumerate(order):
        t = types[ti]
        rel0 = t.mesh.positions()
        centre0 = rel0.mean(axis=0)
        radius = float(np.linalg.norm(rel0 - centre0, axis=1).max())
        outward_tris = mesh_io.outward(t.mesh.triangle_ids)
        for attempt in range(max_attempts):
            rot = _random_rotation(rng)
            centre = lo + rng.random(3) * (hi - lo)
            nodes = (rel0 - centre0) @ rot.T + centre
            if boundaries and not _clear_of_boundaries(nodes, centre, radius, boundaries, margin):
                continue
            if not periodic.all():
                inside = np.all((nodes >= 0) | periodic, axis=1) & np.all((nodes <= box) | periodic, axis=1)
                if not inside.all():
                    continue
            if _overlaps(nodes, centre, radius, outward_tris, placed, gap, box, periodic):
                continue
            placed.append((ti, centre - rot @ centre0, rot, nodes, centre, radius, outward_tris))
            break
        else:
            v_placed = sum(vols[p[0]] for p in placed)
            what = (f" (haematocrit {v_placed / v_fluid:.4f} of the target {haematocrit})"
                    if v_fluid else "")
            raise SeedingError(f"seed_cells: could not place cell {n_done + 1} of {len(order)} in "
                               f"{max_attempts} random tries; placed {len(placed)}{what}. Use fewer or "
                               f"smaller cells, a smaller margin/gap, or a larger region")
    placements = [(p[0], p[1], rotation_to_angles(p[2])) for p in placed]
    if not create:
        return placements
    cells = []
    for ti, origin, angles in placements:
        cells.append(OifCell(cell_type=types[ti], particle_type=particle_types[ti], origin=origin,
                             rotate=angles, particle_mass=particle_mass,
                             exclusion_neighbours=exclusion_neighbours, self_cell_cutoff=self_cell_cutoff))
    return cells


def _clear_of_boundaries(nodes, centre, radius, boundaries, margin):
    for shape in boundaries:
        dist = _signed_distance(shape)
        d = dist(centre)
        if d > radius + margin:
            continue  # the whole cell is far from this shape
        if d < -radius:
            return False
        if min(dist(p) for p in nodes) < margin:
            return False
    return True


def _overlaps(nodes, centre, radius, outward_tris, placed, gap, box, periodic):
    for (_, _, _, other, oc, orad, otris) in placed:
        dc = _min_image(centre - oc, box, periodic)
        if np.linalg.norm(dc) >= radius + orad + gap:
            continue
        shift = (centre - oc) - dc  # bring the other cell next to this one
        o = other + shift
        d = nodes[:, None, :] - o[None, :, :]
        if np.einsum("ijk,ijk->ij", d, d).min() < gap * gap:
            return True
        if _winding_number(centre, o, otris) > 0.5 or _winding_number(oc + shift, nodes, outward_tris) > 0.5:
            return True
    return False

