"""Random placement of many cells in a geometry, without overlaps: e.g.
``oif.seed_cells(system, [rbc_type, rare_type], counts=[40, 1],
boundaries=[wall_bottom, wall_top, obstacle], particle_types=[0, 1], seed=12)``
places 40 cells of one type and one of another, and
``oif.seed_cells(system, rbc_type, haematocrit=0.04, boundaries=walls, seed=3)``
fills the box to a haematocrit (examples that run: doc/oif.md).

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
  centre is inside the new one (one cell swallowing a small one),
- the same holds for the particles and OifCells already in the system
  (every particle is an obstacle at distance `gap`; the gap to an existing
  cell also covers that cell's longest edge),
- no periodic extent reaches the box length (a cell would overlap its own
  periodic image; see OifCell).

A `gap` below the safe minimum is raised to it silently (documented
behaviour, kept for existing scripts).

The same `seed` gives the same cells. When the next cell cannot be placed
in `max_attempts` tries, ``SeedingError`` says how many were placed and
which haematocrit that is.
"""
import numbers

import numpy as np

from lbmd.validation import INT32_MAX, is_whole_number as _is_int

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


def _rotation_about(axis, angle):
    """Rotation by `angle` about the unit vector `axis` (Rodrigues' formula)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def rotation_to_angles(rot):
    """PyOIF's rotate=(a, b, c) (R = Rz(c) Ry(b) Rx(a)) of a rotation matrix."""
    b = -np.arcsin(np.clip(rot[2, 0], -1.0, 1.0))
    a = np.arctan2(rot[2, 1], rot[2, 2])
    c = np.arctan2(rot[1, 0], rot[0, 0])
    return np.array([a, b, c])


def _signed_distance(shape):
    """Signed distance of a point to an lbmd shape or any object with
    calc_dist."""
    return lambda p: shape.calc_dist(p)[0]


def _signed_distances(shape):
    """Signed distances of an (n, 3) array of points to a shape, in one call
    where it has signed_distances (lbmd shapes: exact, the values calc_dist
    gives), else point by point."""
    if hasattr(shape, "signed_distances"):
        return shape.signed_distances
    dist = _signed_distance(shape)
    return lambda points: np.array([dist(p) for p in points], dtype=float)


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
        d = _signed_distances(shape)(grid)
        fraction = np.minimum(fraction, np.clip(0.5 + d / steps.min(), 0.0, 1.0))
    return float(np.prod(steps) * fraction.sum())


def _region(system, region):
    box = np.asarray(system.box_l, dtype=float)
    if region is None:
        return np.zeros(3), box
    msg = f"seed_cells: parameter 'region' must be two corners (lo, hi) of 3 finite numbers with hi > lo, got {region!r}"
    try:
        if len(region) != 2:
            raise ValueError(msg)
        raw = [np.asarray(x) for x in region]
    except (TypeError, ValueError):
        raise ValueError(msg) from None
    if any(r.dtype.kind not in "iuf" or r.shape != (3,) for r in raw):
        raise ValueError(msg)
    lo, hi = (r.astype(float) for r in raw)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
        raise ValueError(msg)
    return lo, hi


def _per_type(name, value, k, check, default):
    """One value per cell type: None -> default, a scalar -> repeated, or a
    list of k; each passed through check(name, item)."""
    if value is None:
        return [default] * k
    if np.ndim(value) == 0 and not isinstance(value, (list, tuple)):
        return [check(name, value)] * k
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
        raise TypeError(f"seed_cells: parameter '{name}' must be a number or a list of {k}, got {value!r}")
    items = list(value)
    if len(items) != k:
        raise ValueError(f"seed_cells: parameter '{name}' needs {k} values (one per cell type), got {value!r}")
    return [check(name, x) for x in items]


def _count(name, x):
    # no truncation: 2.7 cells is a mistake, not 2 cells
    if not _is_int(x):
        raise TypeError(f"seed_cells: parameter '{name}' must hold whole numbers of cells (integers), got {x!r}")
    if x < 0:
        raise ValueError(f"seed_cells: parameter '{name}' must hold numbers of cells >= 0, got {x!r}")
    return int(x)


def _ptype(name, x):
    if not _is_int(x):
        raise TypeError(f"seed_cells: parameter '{name}' must hold particle types (integers >= 0), got {x!r}")
    if not 0 <= x <= INT32_MAX:
        raise ValueError(f"seed_cells: parameter '{name}' must hold particle types in 0..{INT32_MAX}, got {x!r}")
    return int(x)


def _length(name, x, owner="seed_cells"):
    """margin/gap (pack_cells: clearances): None (default) or a finite
    distance >= 0 (NaN would silently switch the overlap checks off)."""
    if x is None:
        return None
    if isinstance(x, np.ndarray) and x.ndim == 0:
        x = x.item()  # np.array(1.0) as 1.0
    if not isinstance(x, numbers.Real) or isinstance(x, (bool, np.bool_)):
        raise TypeError(f"{owner}: parameter '{name}' must be a number (or None for the default), got {x!r}")
    if not np.isfinite(x) or x < 0:
        raise ValueError(f"{owner}: parameter '{name}' must be finite and >= 0, got {x!r}")
    return float(x)


def _unit_axis(owner, rotation_axis):
    """None, or rotation_axis as a unit vector (a non-zero vector of 3 finite numbers)."""
    if rotation_axis is None:
        return None
    try:
        axis = np.asarray(rotation_axis, dtype=float)
    except (TypeError, ValueError):
        axis = np.zeros(0)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.linalg.norm(axis) > 0:
        raise ValueError(f"{owner}: parameter 'rotation_axis' must be None or a non-zero vector of 3 "
                         f"finite numbers, got {rotation_axis!r}")
    return axis / np.linalg.norm(axis)


def _shares(owner, fractions, k):
    """The volume shares of k cell types (default equal), normalised to 1."""
    try:
        fr = np.ones(k) / k if fractions is None else np.asarray(fractions, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: parameter 'fractions' needs {k} numbers, got {fractions!r}") from None
    if fr.shape != (k,) or not np.all(np.isfinite(fr)) or np.any(fr < 0) or fr.sum() <= 0:
        raise ValueError(f"{owner}: parameter 'fractions' needs {k} finite values >= 0, got {fractions!r}")
    return fr / fr.sum()


def _min_width(nodes):
    """Smallest extent of the point set over many directions (close to the
    narrowest width of the shape in any orientation)."""
    rel = nodes - nodes.mean(axis=0)
    k = np.arange(400) + 0.5
    theta = np.arccos(1.0 - k / 400.0)  # half sphere of directions (Fibonacci lattice)
    phi = np.pi * (1.0 + 5.0 ** 0.5) * k
    dirs = np.stack([np.cos(phi) * np.sin(theta), np.sin(phi) * np.sin(theta), np.cos(theta)], axis=1)
    _, _, vt = np.linalg.svd(rel, full_matrices=False)  # principal axes: the narrowest is usually one
    proj = rel @ np.vstack([dirs, vt]).T
    return float((proj.max(axis=0) - proj.min(axis=0)).min())


def _existing_obstacles(system):
    """(KD-tree of all particles already in the system, periodic-aware, or
    None; list of live OifCells of this system as placed-cell entries)."""
    from .oif_classes import live_cells
    parts = system.part.all()
    tree = None
    if len(parts):
        from scipy.spatial import cKDTree
        box = np.asarray(system.box_l, dtype=float)
        periodic = np.asarray(system.periodicity, dtype=bool)
        pos = _fold(np.asarray(parts.pos, dtype=float), box, periodic)
        tree = cKDTree(pos, boxsize=np.where(periodic, box, 0.0) if periodic.any() else None)
    cells = []
    for c in live_cells(system):
        nodes = c.mesh.positions()
        centre = nodes.mean(axis=0)
        radius = float(np.linalg.norm(nodes - centre, axis=1).max())
        # the gap to this cell must also cover its own longest edge (see the module docstring)
        cells.append(((None, None, None, nodes, centre, radius, mesh_io.outward(c.mesh.triangle_ids)),
                      1.2 * c.max_edge_length()))
    return tree, cells


def _fold(pos, box, periodic):
    """Positions folded into [0, box) along periodic axes (cKDTree's torus)."""
    pos = pos.copy()
    pos[:, periodic] = np.mod(pos[:, periodic], box[periodic])
    # np.mod can round up to exactly box for tiny negative inputs
    pos[:, periodic] = np.where(pos[:, periodic] >= box[periodic], 0.0, pos[:, periodic])
    return pos


def seed_cells(system, cell_types, counts=None, haematocrit=None, fractions=None, boundaries=(), region=None,
               particle_types=None, particle_mass=1.0, seed=None, margin=None, gap=None, max_attempts=2000,
               exclusion_neighbours=True, self_cell_cutoff=None, create=True, rotation_axis=None):
    """Place cells of the given types (one OifCellType or a list) at random,
    without overlaps; returns the list of OifCell (or, create=False, the
    list of (type index, origin, rotate) placements).

    counts: number of cells per type (int or list), or haematocrit: target
    volume fraction of the fluid (inside `region`, outside `boundaries`),
    split between types by `fractions` of the cell volume (default equal).
    boundaries: list of shapes (a single shape is taken as a list of one).
    particle_types: particle type per cell type (default 0 for all).
    margin: least node distance from boundaries (default 0.5 x the longest
    edge). gap: least node distance between cells (default 1.2 x longest
    edge; a smaller gap is raised to that safe minimum). rotation_axis:
    None (default) turns every cell by a uniform random rotation; a vector
    turns each cell only about that axis, by a uniform random angle, so the
    cell type's mesh axes keep their direction otherwise: e.g. (0, 0, 1) for
    RBC meshes (discs in the mesh's x-y plane) lays the discs flat between
    walls normal to z, which packs far more cells into a low channel than
    random orientations (a start as in a settled sample). Particles already
    in the system (other cells, tracers) are obstacles: new nodes keep at
    least `gap` from them, and no new cell is placed inside an existing
    cell or around one. All arguments are checked before anything is
    created; if creating the cells fails, the cells created by this call
    are removed again.
    """
    from .oif_classes import OifCell, OifCellType, _exclusion_rings, _real
    import lbmd
    if not isinstance(system, lbmd.System):
        raise TypeError(f"seed_cells: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
    if isinstance(cell_types, OifCellType):
        types = [cell_types]
    elif isinstance(cell_types, (list, tuple)):
        types = list(cell_types)
    else:
        types = []
    if not types or not all(isinstance(t, OifCellType) for t in types):
        raise TypeError("seed_cells: parameter 'cell_types' must be an OifCellType or a list of them")
    for i, t in enumerate(types):
        if t.system is not system:
            raise ValueError(f"seed_cells: cell type {i} belongs to another lbmd.System than parameter "
                             f"'system'; create the cell types on the system you seed")
    k = len(types)
    particle_types = _per_type("particle_types", particle_types, k, _ptype, 0)
    particle_mass = _real("seed_cells", "particle_mass", particle_mass, "pos")
    _exclusion_rings("seed_cells", exclusion_neighbours)
    if self_cell_cutoff is not None:
        _real("seed_cells", "self_cell_cutoff", self_cell_cutoff, "nonneg")
    if not isinstance(create, (bool, np.bool_)):
        raise TypeError(f"seed_cells: parameter 'create' must be True or False, got {create!r}")
    if seed is not None and (not _is_int(seed) or seed < 0):
        raise TypeError(f"seed_cells: parameter 'seed' must be an integer >= 0 or None, got {seed!r}")
    if not _is_int(max_attempts) or max_attempts < 1:
        raise TypeError(f"seed_cells: parameter 'max_attempts' must be an integer >= 1, got {max_attempts!r}")
    seed = None if seed is None else int(seed)
    max_attempts = int(max_attempts)
    rotation_axis = _unit_axis("seed_cells", rotation_axis)
    margin, gap = _length("margin", margin), _length("gap", gap)
    if boundaries is None:
        boundaries = []
    elif hasattr(boundaries, "calc_dist"):  # one shape
        boundaries = [boundaries]
    elif isinstance(boundaries, (list, tuple)):
        boundaries = list(boundaries)
    else:
        raise TypeError(f"seed_cells: parameter 'boundaries' must be a list of shapes, got "
                        f"{type(boundaries).__name__}")
    for i, b in enumerate(boundaries):
        if not callable(getattr(b, "calc_dist", None)):
            raise TypeError(f"seed_cells: parameter 'boundaries': item {i} is not a shape (no calc_dist), "
                            f"got {type(b).__name__}")
    lo, hi = _region(system, region)
    vols = np.array([t.volume0 for t in types])
    if (counts is None) == (haematocrit is None):
        raise TypeError("seed_cells: give exactly one of 'counts' and 'haematocrit'")
    box = np.asarray(system.box_l, dtype=float)
    periodic = np.asarray(system.periodicity, dtype=bool)
    # a type at least a box length wide in every orientation would overlap its
    # own periodic image (see OifCell), and its edges must stay below a
    # quarter of the box (nearest-image bonds): refused before any placement
    for i, t in enumerate(types):
        width = _min_width(t.mesh.positions())
        for axis in np.nonzero(periodic & (width >= box))[0]:
            raise ValueError(f"seed_cells: cell type {i} spans at least {width:.6g} in any orientation, not "
                             f"less than the periodic box length {box[axis]:.6g} along {'xyz'[axis]} "
                             f"(box_l[{axis}]): it would overlap its own periodic image. Use a longer box, "
                             f"a non-periodic axis or smaller cells")
        for axis in np.nonzero(periodic & (2.0 * t.mesh.max_edge_length() >= 0.5 * box))[0]:
            raise ValueError(f"seed_cells: cell type {i}'s longest edge {t.mesh.max_edge_length():.6g} is not "
                             f"less than a quarter of the periodic box length {box[axis]:.6g} along "
                             f"{'xyz'[axis]}: membrane bonds use the nearest periodic image")
    v_fluid = None
    # random close packing of deformable discs is far below 1; beyond ~0.6 rigid placement cannot work
    packing = 0.6
    if counts is not None:
        counts = _per_type("counts", counts, k, _count, 0)
        need = float(np.dot(counts, vols))
        v_region = float(np.prod(hi - lo))
        # fail fast (before building a list of 10**9 placements): the region volume bounds
        # the fluid volume; the exact fluid volume is worth its grid only for a close call
        v_avail = v_region
        if boundaries and need > 0.1 * packing * v_region:
            v_avail = fluid_volume(system, boundaries, (lo, hi))
        if need > packing * v_avail:
            raise SeedingError(f"seed_cells: {sum(counts)} cells of total volume {need:.4g} cannot be placed "
                               f"at random in the available volume {v_avail:.4g} (at most about {packing} of "
                               f"it); seed fewer cells or enlarge the region")
    else:
        if (not isinstance(haematocrit, numbers.Real) or isinstance(haematocrit, (bool, np.bool_))
                or not 0 < haematocrit < 1):
            raise ValueError(f"seed_cells: parameter 'haematocrit' must be in (0, 1) (a number), got {haematocrit!r}")
        fr = _shares("seed_cells", fractions, k)
        v_fluid = fluid_volume(system, boundaries, (lo, hi))
        counts = [int(round(haematocrit * v_fluid * f / v)) for f, v in zip(fr, vols)]
        if sum(counts) == 0:
            raise SeedingError(f"seed_cells: haematocrit {haematocrit} of a fluid volume {v_fluid:.4g} is "
                               f"less than one cell (cell volume {vols.min():.4g})")
        if sum(c * v for c, v in zip(counts, vols)) > packing * v_fluid:
            raise SeedingError(f"seed_cells: haematocrit {haematocrit} cannot be reached by random placement "
                               f"of undeformed cells (at most about {packing} of the fluid volume {v_fluid:.4g}); "
                               f"seed fewer cells and compress, or enlarge the geometry")
    longest = max(t.mesh.max_edge_length() for t in types)
    margin = 0.5 * longest if margin is None else margin
    # below 1.2 x the longest edge two meshes can interpenetrate without a close
    # node pair, so a smaller gap is raised to that minimum (documented above)
    gap = 1.2 * longest if gap is None else max(gap, 1.2 * longest)
    rng = np.random.default_rng(seed)
    tree, existing = _existing_obstacles(system)

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
            rot = (_random_rotation(rng) if rotation_axis is None
                   else _rotation_about(rotation_axis, 2.0 * np.pi * rng.random()))
            centre = lo + rng.random(3) * (hi - lo)
            nodes = (rel0 - centre0) @ rot.T + centre
            if np.any(periodic & (nodes.max(axis=0) - nodes.min(axis=0) >= box)):
                continue  # in this orientation the cell would overlap its own periodic image
            if boundaries and not _clear_of_boundaries(nodes, centre, radius, boundaries, margin):
                continue
            if not periodic.all():
                inside = np.all((nodes >= 0) | periodic, axis=1) & np.all((nodes <= box) | periodic, axis=1)
                if not inside.all():
                    continue
            if tree is not None and np.any(tree.query(_fold(nodes, box, periodic), k=1,
                                                      distance_upper_bound=gap)[0] < gap):
                continue  # too close to a particle already in the system
            if any(_overlaps(nodes, centre, radius, outward_tris, [entry], max(gap, own_gap), box, periodic)
                   for entry, own_gap in existing):
                continue  # too close to, inside or around a cell already in the system
            if _overlaps(nodes, centre, radius, outward_tris, placed, gap, box, periodic):
                continue
            placed.append((ti, centre - rot @ centre0, rot, nodes, centre, radius, outward_tris))
            break
        else:
            v_placed = sum(vols[p[0]] for p in placed)
            what = (f" (haematocrit {v_placed / v_fluid:.4f} of the target {haematocrit})"
                    if v_fluid else "")
            n_existing = len(system.part)
            others = (f"; the {n_existing} particles already in the system are obstacles too"
                      if n_existing else "")
            raise SeedingError(f"seed_cells: could not place cell {n_done + 1} of {len(order)} in "
                               f"{max_attempts} random tries; placed {len(placed)}{what}{others}. Use fewer or "
                               f"smaller cells, a smaller margin/gap, or a larger region")
    placements = [(p[0], p[1], rotation_to_angles(p[2])) for p in placed]
    if not create:
        return placements
    cells = []
    try:
        for ti, origin, angles in placements:
            cells.append(OifCell(cell_type=types[ti], particle_type=particle_types[ti], origin=origin,
                                 rotate=angles, particle_mass=particle_mass,
                                 exclusion_neighbours=exclusion_neighbours, self_cell_cutoff=self_cell_cutoff))
    except BaseException:
        for c in cells:  # all or nothing: the cells this call created go again
            c._discard()
        raise
    return cells


def _clear_of_boundaries(nodes, centre, radius, boundaries, margin):
    for shape in boundaries:
        dist = _signed_distance(shape)
        d = dist(centre)
        if d > radius + margin:
            continue  # the whole cell is far from this shape
        if d < -radius:
            return False
        if _signed_distances(shape)(nodes).min() < margin:
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

