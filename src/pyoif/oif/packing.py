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

Where rigid cells jam before their full size (in tubes and between walls
above a haematocrit of about 0.35: the wall layer and the contacts'
clearance leave no room for rigid discs), the deformable stage takes over
(``deformable=True``, the default): the rigid packing is settled a little
smaller than where it jammed, the cells are made there as deformable OIF
cells with their own moduli (divided alike, see _swell) in a scratch System of their own (no
fluid, no thermal noise; a friction damps them) and swell to their
reference volume and surface under the advised contact (hard_contact,
which no squeeze crosses) — at the advised strength while they swell
fast, at a twentieth of it for the last per cent — and under the walls'
contact, until every cell's volume and surface are within
SWELL_TOLERANCE of the reference. The cells end deformed as blood cells
are at that haematocrit, at their reference volume and surface, and
carry the elastic stress of that shape into the run. The rigid stage does
most of the work first, at no membrane cost; the swelling then only has
to find room for the last few per cent of the cells' volume. Why a twentieth of the contact's strength at the end: at the full strength
the contacts between all the cells at 0.45 keep the most squeezed cells
1-2 % below their reference surface (measured, D 20 um tube); weaker, the
gaps are smaller and the cells reach their reference, still with every
node at least the contact's offset from the other cells (nothing crossed).

After packing, the meshes are checked exactly: winding numbers of the nodes
near another cell (no node inside another cell), node-to-node distances
between cells and the nodes' signed distances to the boundaries. The
result is the list of OifCells with ``report``: the reached haematocrit,
the counts, the iterations and seconds, and the checks.
"""
import time

import numpy as np

from lbmd import shapes as lbshapes
from lbmd.validation import is_whole_number as _is_int

from . import mesh_io
from .seeding import (SeedingError, _count, _length, _per_type, _ptype, _region, _shares, _signed_distances,
                      _unit_axis, fluid_volume, rotation_to_angles)


#: the cells' size at the start of the growth (the C++ packer's default)
START_SCALE = 0.5
#: rigid iterations without growth or the worst overlap falling by
#: STALL_OVERLAP_DROP after which the rigid cells count as jammed (and the
#: deformable stage takes over). A D 40 um tube at 0.45 crept on at 1 % per
#: 1000 iterations for 11000 iterations (380 s) before it stopped rigid.
STALL_ITERATIONS, STALL_OVERLAP_DROP = 1000, 0.05
#: the sizes, relative to where the rigid cells jammed, tried in turn for
#: the clean rigid packing the deformable stage starts from
SWELL_START = (0.99, 0.98, 0.96, 0.94, 0.92, 0.9, 0.87, 0.84)
#: below this rigid size the cells are too dense to swell (their volume
#: would have to double): PackingError
SWELL_LEAST_SCALE = 0.8
#: the deformable stage: every cell's volume and surface within this
#: relative deviation of the reference (below the 0.5 % promised)
SWELL_TOLERANCE = 0.0045
#: its time step, node mass and Langevin friction (kT 0). The swelling is
#: overdamped, so its steps go as friction / time step: 0.5 and 0.1 swell a
#: D 20 um tube at 0.45 in 1800 steps; at a time step of 0.2 or a friction
#: of 0.25 the first steps' push closed a contact below its guard gap. The
#: time step is halved while the settings check's membrane trial finds it
#: unstable for a cell type's moduli; a contact overrun restarts the stage
#: at SWELL_FRICTION_RETRY times the friction.
SWELL_TIME_STEP, SWELL_MASS, SWELL_FRICTION = 0.1, 1.0, 0.5
SWELL_FRICTION_RETRY = (1.0, 4.0, 16.0)
#: the contact's force scale in the deformable stage, relative to the
#: advised one: the advised contact while the cells swell fast (a weak one
#: is too stiff for the time step under that push: an overdamped contact
#: holds a push up to about sqrt(2 a cutoff friction / dt)), a twentieth of it
#: from when the mean volume deficit is below SWELL_WEAKEN_AT (or after
#: SWELL_WEAKEN_AFTER steps)
SWELL_CONTACT_SCALE = 0.05
#: the global moduli the stage's settings were measured with (the PyOIF
#: paper's RBC, kag 0.7 and kv 0.9): the cells' moduli are divided by the
#: largest ratio of a type's kv or kag to these
SWELL_REFERENCE = dict(kag=0.7, kv=0.9)
SWELL_WEAKEN_AT, SWELL_WEAKEN_AFTER = 0.01, 1000
#: steps between the checks of the volumes and surfaces
SWELL_CHECK_EVERY = 100


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
        if not isinstance(b, lbshapes.Shape):
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
               self_cell_cutoff=None, deformable=True, max_swell_steps=20000):
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
    see the module's docstring; a scene with stiffened contacts or light
    nodes passes ``oif.contacts.packing_clearance(types, scale, time_step,
    node_mass)``, so that its contacts start above their guard gap;
    deformed cells keep half the margin beyond the contact's offset);
    wall_clearance: least signed distance of a node from every boundary
    (default 0.25 um; deformed cells keep half of it). rotation_axis: None (random
    orientations) or an axis about which alone the cells are turned at the
    start (e.g. discs stacked like coins in a narrow tube). seed: the same
    seed gives the same cells. deformable: where rigid cells jam, swell
    deformable cells from a slightly smaller rigid packing (the module's
    docstring) for at most max_swell_steps steps (4x and 16x that on a
    retry at a higher friction after a contact overrun); create=False
    then refuses (the placements of deformed cells are not origins and
    rotations; a swollen cell's origin and rotation stay those of its
    rigid placement). Under mpirun with seed None, rank 0's seed is used
    on every rank. Raises PackingError, naming the haematocrit reached, when
    the cells do not fit.
    """
    import lbmd
    from lbmd.packing import RigidPacker, check_meshes
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
    for name, flag in (("create", create), ("deformable", deformable)):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"pack_cells: parameter '{name}' must be True or False, got {flag!r}")
    if not _is_int(max_swell_steps) or max_swell_steps < 1:
        raise TypeError(f"pack_cells: parameter 'max_swell_steps' must be an integer >= 1, got "
                        f"{max_swell_steps!r}")
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
    packer = RigidPacker()
    centroids = []
    for t in types:
        nodes = t.mesh._nodes
        centroid = nodes.mean(axis=0)
        centroids.append(centroid)
        extent = np.ptp(nodes, axis=0)
        spacing = float(min(0.15, extent.min() / 16.0)) if extent.min() > 0 else 0.15
        packer.add_type(nodes - centroid, mesh_io.outward(t.mesh._topo.triangles), spacing)
    for s in shapes:
        packer.add_boundary(s)

    # random start: centres in the fluid (by the boundaries' signed distance),
    # at least half the thinnest cell's width apart (minimum image): two
    # shrunken cells about one centre push each other symmetrically and
    # would not separate; larger cells first, types interleaved
    # reproducibly by the seed
    if seed is None and lbmd.size > 1:
        # every rank must add the same cells: one seed, drawn on rank 0
        seed = lbmd.comm.bcast(int(np.random.SeedSequence().entropy % (2 ** 63)), root=0)
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
                    # stop a jammed rigid packing early only where the deformable stage takes over
                    stall_iterations=STALL_ITERATIONS if deformable and create else 0,
                    stall_overlap_drop=STALL_OVERLAP_DROP,
                    seed=int(seed or 0))
    if region is not None:
        settings["region"] = [lo.tolist(), hi.tolist()]
    result = packer.run(settings)
    reached = target * result["scale"] ** 3
    report = dict(haematocrit=target, counts=list(counts), fluid_volume=v_fluid, clearance=clearance,
                  wall_clearance=wall_clearance, iterations=result["iterations"], converged=result["converged"],
                  rigid_converged=result["converged"], worst_overlap=result["worst_overlap"],
                  worst_wall_overlap=result["worst_wall_overlap"], method="rigid")
    too_dense = (f"pack_cells: {n} cells (haematocrit {target:.3f}) did not fit in {result['iterations']} "
                 f"iterations: rigid, they reached {result['scale']:.3f} of their size (haematocrit "
                 f"{reached:.3f}) with nodes {result['worst_overlap']:.3g} closer to other cells than the "
                 f"clearance {clearance:.3g} and {result['worst_wall_overlap']:.3g} closer to the walls than "
                 f"{wall_clearance:.3g}")
    advice = ("Lower the haematocrit, enlarge the geometry, lower the clearance, align the cells "
              "(rotation_axis) or raise max_iterations")
    swell_scale = None
    if not result["converged"]:
        if not deformable:
            raise PackingError(f"{too_dense}. {advice}, or let the cells deform (deformable=True)")
        if not result["jammed"]:
            raise PackingError(f"{too_dense}; they were still growing when max_iterations ran out. {advice}")
        if not create:
            raise PackingError(f"{too_dense}; deformed cells cannot be given as placements (create=False): "
                               f"pack with create=True")
        # settle the rigid cells a little smaller than where they jammed
        for shrink in SWELL_START:
            swell_scale = shrink * result["scale"]
            if swell_scale < SWELL_LEAST_SCALE:
                break
            # every node at least 0.99 of the clearance from the others: the
            # deformable stage's contacts start within their range
            settled = packer.run(dict(settings, start_scale=swell_scale, final_scale=swell_scale,
                                      max_iterations=1000, stall_iterations=0, final_tolerance=0.01))
            report["iterations"] += settled["iterations"]
            if settled["converged"]:
                break
        else:
            raise PackingError(f"{too_dense}; no smaller rigid packing to swell deformable cells from settled "
                               f"(down to {swell_scale:.3f} of their size). {advice}")
        if swell_scale < SWELL_LEAST_SCALE:
            raise PackingError(f"{too_dense}; too dense to swell deformable cells from (their volume would have "
                               f"to grow by more than {1 / SWELL_LEAST_SCALE ** 3 - 1:.0%}). {advice}")
        report.update(method="rigid+deformable", rigid_scale=swell_scale, rigid_haematocrit=target * swell_scale ** 3)
    centres = packer.centres()
    rotations = packer.rotations()
    placements = []
    for b, ti in enumerate(order):
        rot = rotations[b]
        placements.append((ti, centres[b] - rot @ centroids[ti], rotation_to_angles(rot)))
    if swell_scale is None:
        check = packer.check(settings)
        report.update(nodes_inside_cells=check["nodes_inside_cells"], min_node_distance=check["min_node_distance"],
                      min_wall_distance=check["min_wall_distance"])
    else:
        swollen = _swell(system, types, order, centres, rotations, swell_scale, shapes, lo, hi, clearance,
                         wall_clearance, int(max_swell_steps), report, packer_periodic)
        # the exact check of the deformed meshes, before any cell is made
        nodes = np.concatenate(swollen)
        first = np.concatenate([[0], np.cumsum([len(x) for x in swollen])]).astype(int).tolist()
        check = check_meshes(nodes, first, [int(ti) for ti in order],
                             [mesh_io.outward(t.mesh._topo.triangles) for t in types],
                             shapes, settings, clearance + 1.0)
        report.update(nodes_inside_cells=check["nodes_inside_cells"], min_node_distance=check["min_node_distance"],
                      min_wall_distance=check["min_wall_distance"])
        if check["nodes_inside_cells"] or check["min_wall_distance"] < 0.0:
            raise PackingError(f"pack_cells: the swollen cells failed the exact check: "
                               f"{check['nodes_inside_cells']} nodes inside other cells, closest node "
                               f"{check['min_wall_distance']:.3g} from a wall; please report this")
    report["pack_seconds"] = time.perf_counter() - t_start
    out = PackedCells()
    out.report = report
    if not create:
        out.extend(placements)
        return out
    try:
        for b, (ti, origin, angles) in enumerate(placements):
            out.append(OifCell(cell_type=types[ti], particle_type=particle_types[ti], origin=origin, rotate=angles,
                               particle_mass=particle_mass, exclusion_neighbours=exclusion_neighbours,
                               self_cell_cutoff=self_cell_cutoff, check_overlaps=False))
            if swell_scale is not None:
                out[-1].particles.pos = swollen[b]
    except BaseException:
        for c in out:
            c._discard()
        raise
    report["seconds"] = time.perf_counter() - t_start
    return out


def _swell(system, types, order, centres, rotations, scale, shapes, lo, hi, clearance, wall_clearance, max_steps,
           report, packer_periodic):
    """The deformable stage (the module's docstring): the rigid cells at
    `scale` made deformable in a scratch System and swollen to their
    reference volume and surface; returns each cell's node positions
    (unfolded) and adds its figures to `report`."""
    import warnings
    import lbmd
    from .settings_check import membrane_trial
    from .contacts import contact_offset, contact_settings, guard_gap, set_contacts
    from .oif_classes import OifCell
    t0 = time.perf_counter()
    box = np.asarray(system.box_l, dtype=float)
    periodic = np.asarray(system.periodicity, dtype=bool)
    scratch = lbmd.System(box_l=box.tolist(), periodicity=periodic.tolist())
    scratch.__dict__["_settings_checked"] = True  # a scratch run: nothing to check
    scratch.cell_drift_tolerance = 1e9  # the stage judges the volumes and surfaces itself
    # the moduli normalised to the published RBC's global moduli by the
    # least stiff type's ratio (a scene
    # that stiffens its membranes to keep the capillary number at a faster
    # flow, as the flagship does 27x, swells as the published cells do):
    # scaling every modulus and the contacts alike leaves the shapes the
    # cells take unchanged and keeps the stage's time step and contacts
    # in the range measured
    ratios = [max(t.kv / SWELL_REFERENCE["kv"], t.kag / SWELL_REFERENCE["kag"]) for t in types]
    stiffness = min((r for r in ratios if r > 0), default=1.0)  # a stiffer type keeps its ratio to the others
    copies = [t.copy_to(scratch, kvisc=0.0,  # the friction damps; no dashpots needed
                        **{k: getattr(t, k) / stiffness for k in ("ks", "kslin", "kb", "kal", "kag", "kv")})
              for t in types]
    # the time step: halved while a cell type's membrane is unstable at it
    dt = SWELL_TIME_STEP
    for t, copy in zip(types, copies):
        for attempt in range(6):
            if attempt:
                dt *= 0.5
            if membrane_trial(copy, dt, SWELL_MASS, SWELL_FRICTION * SWELL_FRICTION_RETRY[0]) == "stable":
                break
        else:
            raise PackingError(f"pack_cells: the deformable stage found no stable time step down to {dt:.3g} "
                               f"for a cell type's moduli (divided by {stiffness:.3g}: ks {copy.ks:g}, kb "
                               f"{copy.kb:g}, kv {copy.kv:g}); deformable=False packs rigid cells only")
    scratch.time_step = dt
    scratch.cell_system.skin = 0.3
    k = len(types)
    wall_type = k
    cells = []
    for b, ti in enumerate(order):
        centroid = types[ti].mesh._nodes.mean(axis=0)
        cell = OifCell(cell_type=copies[ti], particle_type=int(ti), origin=centres[b] - rotations[b] @ centroid,
                       rotate=rotation_to_angles(rotations[b]), particle_mass=SWELL_MASS, check_overlaps=False)
        x = cell.particles.pos
        cell.particles.pos = centres[b] + (x - centres[b]) * scale
        cells.append(cell)
    walls = list(shapes)
    for d in range(3):  # the region's faces and the box faces of non-periodic axes
        if not periodic[d] or hi[d] - lo[d] < box[d]:
            # the rigid packer keeps the wall clearance from these faces on
            # the axes it packs as closed, none on the periodic ones: there
            # the wall stands the wall clearance beyond the face
            out = 0.0 if not packer_periodic[d] else wall_clearance
            normal = np.eye(3)[d]
            walls += [lbshapes.Wall(normal=normal.tolist(), dist=float(lo[d]) - out),
                      lbshapes.Wall(normal=(-normal).tolist(), dist=-float(hi[d]) - out)]
    for w in walls:
        scratch.constraints.add(shape=w, particle_type=wall_type)
    # the cells' contact holds their nodes half the packing's margin beyond
    # the advised offset (so that a run's contacts start above their guard
    # gap, oif.contacts.packing_clearance), the walls' contact half the
    # wall clearance off the walls
    offset = contact_offset(types)
    cell_offset = offset + 0.5 * (clearance - offset)
    # the rigid settle leaves 0.99 of the clearance: the first steps need
    # the gaps to the stage's contacts above twice their guard gap
    guard = guard_gap(contact_settings(types)["cell"]["a"], dt, SWELL_MASS)
    if 0.99 * clearance - cell_offset < 2.0 * guard or 0.5 * wall_clearance - 0.01 * clearance < 2.0 * guard:
        raise PackingError(f"pack_cells: the deformable stage needs parameter 'clearance' ({clearance:.3g}) at "
                           f"least {(0.5 * offset + 2.0 * guard) / 0.49:.3g} (the contact's offset {offset:.3g} plus a "
                           f"margin) and 'wall_clearance' ({wall_clearance:.3g}) at least "
                           f"{2.0 * (2.0 * guard + 0.01 * clearance):.3g}")

    def contacts(scale):
        contact = set_contacts(scratch, copies, particle_types=list(range(k)), wall_types=[wall_type], scale=scale)
        for ti in range(k):
            for tj in range(ti, k):
                scratch.non_bonded_inter[ti, tj].hard_contact.set_params(**dict(contact["cell"], offset=cell_offset))
            scratch.non_bonded_inter[ti, wall_type].hard_contact.set_params(
                **dict(contact["wall"], offset=0.5 * wall_clearance))
    start = [np.array(c.particles.pos) for c in cells]
    v0 = np.array([types[ti].volume0 for ti in order])
    a0 = np.array([types[ti].surface0 for ti in order])
    total = 0
    for retry in SWELL_FRICTION_RETRY:
        friction = SWELL_FRICTION * retry
        scratch.thermostat.set_langevin(kT=0.0, gamma=friction, seed=1)
        for c, x in zip(cells, start):
            c.particles.pos = x
            c.particles.v = np.zeros_like(x)
        contacts(1.0)
        weak = False
        steps = 0
        try:
            while True:
                dv = np.array([c.volume() for c in cells]) / v0 - 1.0
                da = np.array([c.surface() for c in cells]) / a0 - 1.0
                worst = max(np.abs(dv).max(), np.abs(da).max())
                if weak and worst <= SWELL_TOLERANCE:
                    break
                if not weak and (np.abs(dv).mean() <= SWELL_WEAKEN_AT or steps >= SWELL_WEAKEN_AFTER * retry):
                    contacts(SWELL_CONTACT_SCALE)
                    weak = True
                if steps >= max_steps * retry:
                    raise PackingError(f"pack_cells: the deformable cells did not swell to their reference "
                                       f"volume and surface in {steps} steps (worst {np.abs(dv).max():.2%} and "
                                       f"{np.abs(da).max():.2%} off, tolerance {SWELL_TOLERANCE:.1%}); the "
                                       f"haematocrit is too high for this geometry, or raise max_swell_steps")
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    scratch.integrator.run(SWELL_CHECK_EVERY)
                steps += SWELL_CHECK_EVERY
            break
        except lbmd.SimulationInstability as err:
            total += steps
            if retry == SWELL_FRICTION_RETRY[-1]:
                raise PackingError(f"pack_cells: the deformable stage stopped at friction {friction:g} after "
                                   f"{steps} steps: {err}") from err
    total += steps
    dv, da = np.abs(dv).max(), np.abs(da).max()
    report.update(converged=True, swell_steps=total, swell_time_step=dt, swell_friction=friction,
                  swell_moduli_divided_by=stiffness, swell_seconds=time.perf_counter() - t0,
                  worst_volume_deviation=float(dv), worst_surface_deviation=float(da))
    return [np.array(c.particles.pos) for c in cells]
