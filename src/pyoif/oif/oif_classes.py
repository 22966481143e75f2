"""The object-in-fluid cell model with PyOIF's classes and keywords.

``OifCellType`` reads and checks a relaxed mesh once, computes every
reference value (edge lengths, dihedral angles, triangle areas, surface,
volume) as numpy arrays and registers one ``OifLocalForces``, one
``OifGlobalForces`` and (``normal=True``) one ``OifOutDirection`` bonded
interaction for all its cells. ``OifCell`` adds a cell's particles and all
its bonds with a few bulk engine calls. The PyOIF objects FixedPoint,
PartPoint, Edge, Triangle, Angle and ThreeNeighbors are views created on
demand (``mesh.points``, ``mesh.triangles``, ...) for scripts that use them.

Orientation: stored triangles follow PyOIF's files, (B - A) x (C - A)
pointing into the cell; the engine's triangle bonds get them outward.
"""
import itertools
import os

import numpy as np

import lbmd
from lbmd import cell_registry
from lbmd.file_output import replace_atomically
from lbmd.particle_data import ParticleHandle
from lbmd.validation import check_not_metres as _check_not_metres, INT32_MAX as _INT32_MAX, is_whole_number as _is_int, real_number as _real_number, vector3 as _vector3

from . import geometry as geo
from . import mesh_io
from . import vtk as _vtk
from .settings_check import cell_settings
from .oif_utils import (small_epsilon, custom_str, vec_distance, get_triangle_normal, area_triangle,
                        angle_btw_triangles, angle_btw_vectors)

#: PyOIF's exclusion_neighbours=True excluded the first and second mesh neighbours
DEFAULT_EXCLUSION_RINGS = 2


def _real(owner, name, value, check=None):
    return _real_number(f"{owner}: parameter '{name}'", value, check)


def _vec3(owner, name, value, positive=False):
    return _vector3(f"{owner}: parameter '{name}'", value, positive)


def _check_system(owner, system):
    if not isinstance(system, lbmd.System):
        raise TypeError(f"{owner}: parameter 'system' must be an lbmd.System, got {type(system).__name__}")


def live_cells(system):
    """The OifCells of `system` whose particles are all still theirs, by
    cell_id: every complete OifCell registers with lbmd.cell_registry, so
    that the engine (system.cells) and seeding see the cells already there."""
    return [c for c in system.cells if isinstance(c, OifCell)]



def _exclusion_rings(owner, exclusion_neighbours):
    """Number of edge rings excluded from self-cell contacts."""
    if isinstance(exclusion_neighbours, (bool, np.bool_)):
        return DEFAULT_EXCLUSION_RINGS if exclusion_neighbours else 0
    if _is_int(exclusion_neighbours) and exclusion_neighbours >= 0:
        return int(exclusion_neighbours)
    raise TypeError(f"{owner}: parameter 'exclusion_neighbours' must be True, False or a "
                    f"number of edge rings >= 0, got {exclusion_neighbours!r}")


def _node_ids(owner, name, ids, n):
    """A list of mesh node ids in 0..n-1 (TypeError for a non-list)."""
    if isinstance(ids, (str, bytes)) or not isinstance(ids, (list, tuple, range, np.ndarray)):
        raise TypeError(f"{owner}: parameter '{name}' must be a list of node ids, got {ids!r}")
    ids = list(np.asarray(ids).ravel()) if isinstance(ids, np.ndarray) else list(ids)
    for i in ids:
        if not _is_int(i) or not 0 <= i < n:
            raise ValueError(f"{owner}: parameter '{name}' must hold node ids in 0..{n - 1}, got {i!r}")
    return [int(i) for i in ids]


def check_periodic_extent(owner, system, pos, longest_edge, what="the cell", box=None, periodic=None):
    """Raise ValueError, before anything is added, for a cell the engine
    cannot represent on a periodic axis: one at least a box length wide
    overlaps its own periodic image, and a mesh whose edges reach a quarter
    of the box length has bonds (an edge and its two wing nodes, up to two
    edge lengths from the bond's owner) that the nearest-image convention
    would cut (the membrane pass falls back to it for a cell whose unfolded
    positions jumped). Cells between half and a whole box length are fine:
    the membrane pass takes a cell's nodes unfolded, relative to its first
    node (src/core/interactions/membrane/membrane_model.hpp). box: a box
    length and periodicity to check against other than the system's (a
    change of them)."""
    box = np.asarray(system.box_l if box is None else box, dtype=float)
    periodic = np.asarray(system.periodicity if periodic is None else periodic, dtype=bool)
    extent = pos.max(axis=0) - pos.min(axis=0)
    for axis in range(3):
        if not periodic[axis]:
            continue
        xyz = "xyz"[axis]
        if extent[axis] >= box[axis]:
            raise ValueError(f"{owner}: {what} spans {extent[axis]:.6g} along {xyz}, not less than the periodic "
                             f"box length {box[axis]:.6g} (box_l[{axis}]): it would overlap its own periodic "
                             f"image. Use a longer box along {xyz}, a non-periodic {xyz} axis, or a smaller cell")
        if 2.0 * longest_edge >= 0.5 * box[axis]:
            raise ValueError(f"{owner}: the mesh's longest edge {longest_edge:.6g} is not less than a quarter of "
                             f"the periodic box length {box[axis]:.6g} along {xyz} (box_l[{axis}]): membrane "
                             f"bonds reach two edges from their owner node and use the nearest periodic image. "
                             f"Use a finer mesh or a longer box")


# ---------------------------------------------------------------------------
# point / edge / triangle / angle views (PyOIF API)
# ---------------------------------------------------------------------------
def check_closed_extent(owner, system, pos, what="the cell", box=None, periodic=None):
    """Raise ValueError, before anything is added, for a cell reaching out of
    the box along an axis that is not periodic: there is no image to fold
    its nodes into. ESPResSo 4.1's own OIF test builds a cell wider than its
    box; doc/porting.md says how to port such a scene."""
    box = np.asarray(system.box_l if box is None else box, dtype=float)
    periodic = np.asarray(system.periodicity if periodic is None else periodic, dtype=bool)
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    for axis in range(3):
        if periodic[axis] or (lo[axis] >= 0.0 and hi[axis] <= box[axis]):
            continue
        xyz = "xyz"[axis]
        wider = hi[axis] - lo[axis] > box[axis]
        raise ValueError(
            f"{owner}: {what} spans {xyz} = {lo[axis]:.6g}..{hi[axis]:.6g}, out of the box 0..{box[axis]:.6g} "
            f"along {xyz}, which is not periodic (box_l[{axis}]). "
            + (f"It is wider than the box: make box_l[{axis}] at least {hi[axis] - lo[axis]:.6g} (plus the "
               f"walls' room) and place it inside; ESPResSo 4.1 ran such cells with nodes outside the box "
               f"(doc/porting.md, 'Cells wider than the box')" if wider else
               f"Move its origin so that it lies inside (origin {xyz} within "
               f"{pos[:, axis].mean() - lo[axis]:.6g}..{box[axis] - (hi[axis] - pos[:, axis].mean()):.6g})"))


#: the local area strain above which a cell's time counts as damaging
#: (oif.update_damage): in the flagship's flow (Ca 0.6) an RBC's largest
#: local area strain is 0.1-0.2 all along and reaches 0.7 only where the
#: cells are squeezed at the island's apex; 5 % counted every moment of
#: every cell, 30 % picks out the squeezes
DAMAGE_AREA_STRAIN = 0.3


class CellDamage:
    """A cell's damage record over time, after Gusenbauer, Tothova, Mazza,
    Brandl, Schrefl, Jancigova & Cimrak, "Cell damage index as computational
    indicator for blood cell activation and damage", Artif. Organs 42, 746
    (2018), who measure a cell's mechanical load by the change of its
    membrane's surface area. Here, per cell: `time_above`, the time its
    largest local area strain (any triangle's abs(A / A0 - 1)) spent above
    `threshold` (default DAMAGE_AREA_STRAIN, 30 %), summed between the samples
    oif.update_damage takes (each interval counted by its start: exact to one
    sampling interval per crossing); `peak_strain`, the largest such strain
    seen; `samples`, how many were taken."""

    def __init__(self, threshold=None):
        self.threshold = DAMAGE_AREA_STRAIN if threshold is None else float(threshold)
        self.time_above = 0.0
        self.peak_strain = 0.0
        self.samples = 0
        self._last = None  # (time, strain) of the previous sample

    def update(self, time, strain):
        if self._last is not None:
            t0, s0 = self._last
            if time < t0:
                raise ValueError(f"CellDamage.update: time {time:g} is before the previous sample's {t0:g}")
            if s0 > self.threshold:
                self.time_above += time - t0
        self.peak_strain = max(self.peak_strain, float(strain))
        self._last = (float(time), float(strain))
        self.samples += 1

    def __repr__(self):
        return (f"CellDamage(threshold={self.threshold:g}, time_above={self.time_above:g}, "
                f"peak_strain={self.peak_strain:.4g}, samples={self.samples})")


def update_damage(cells, time, threshold=None):
    """Sample every cell's largest local area strain at `time` (the
    system's time) into its CellDamage record (cell.damage): call it at each
    output of the run loop. `threshold` (a fraction; default 30 %) is fixed
    at a cell's first sample."""
    if isinstance(cells, OifCell):
        cells = [cells]
    if isinstance(time, bool) or not isinstance(time, (int, float, np.floating, np.integer)) \
            or not np.isfinite(time):
        raise TypeError(f"update_damage: parameter 'time' must be a finite number, got {time!r}")
    if threshold is not None and not (isinstance(threshold, (int, float)) and not isinstance(threshold, bool)
                                      and 0 < threshold < 1):
        raise ValueError(f"update_damage: parameter 'threshold' is a strain, a fraction in (0, 1), got "
                         f"{threshold!r}")
    cells = list(cells)
    # every cell checked before any is sampled: a refused call changes nothing
    for c in cells:
        if not isinstance(c, OifCell):
            raise TypeError(f"update_damage: parameter 'cells' must hold oif.OifCell, got {type(c).__name__}")
        record = getattr(c, "_damage", None)
        if record is None:
            continue
        if threshold is not None and float(threshold) != record.threshold:
            raise ValueError(f"update_damage: cell {c.cell_id} is tracked with threshold {record.threshold:g}, "
                             f"not {threshold:g} (a record keeps its first threshold)")
        if record._last is not None and float(time) < record._last[0]:
            raise ValueError(f"update_damage: time {float(time):g} is before cell {c.cell_id}'s previous sample "
                             f"at {record._last[0]:g}")
    strains = [c.max_area_strain() for c in cells]
    for c, strain in zip(cells, strains):
        if getattr(c, "_damage", None) is None:
            c._damage = CellDamage(threshold)
        c._damage.update(float(time), strain)


class OverlapWarning(UserWarning):
    """A new OifCell placed over another cell or inside a wall (the run
    would stop with membrane_crossing or wall_penetration, or push the
    membranes apart violently)."""


def _winding(points, nodes, triangles):
    """Per point: |winding number| of the closed surface (about 1 inside,
    0 outside); Van Oosterom and Strackee's solid angle per triangle, in
    blocks of points to bound the memory."""
    out = np.zeros(len(points))
    corners = [nodes[triangles[:, k]] for k in range(3)]
    for start in range(0, len(points), 32):
        p = points[start:start + 32, None]
        a, b, c = (x[None] - p for x in corners)
        la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
        num = np.einsum("pti,pti->pt", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("pti,pti->pt", a, b) * lc + np.einsum("pti,pti->pt", b, c) * la
               + np.einsum("pti,pti->pt", c, a) * lb)
        out[start:start + 32] = np.abs(np.arctan2(num, den).sum(axis=1)) / (2 * np.pi)
    return out


def lb_gamma(n_nodes, surface, visc, dens):
    """PyOIF's coupling friction per node for a mesh of n_nodes on a
    membrane of this surface, in a fluid of this kinematic viscosity and
    density (the engine's units): the drag of a 393-node sphere of surface
    201.06 calibrated at visc 1.5 to 5.9, dens 1 to 6 (Jancigova, Tothova et
    al.), scaled by node density (the same total friction per area)."""
    return (393.0 / n_nodes) * np.sqrt(surface / 201.0619) * (
        (5.6 - 1.82) / (5.853658537 - 1.5) * (visc - 1.5)
        + (10 - 1.82) / (6 - 1.025) * (dens - 1.025) + 1.82)


def _warn_overlaps(owner, system, pos, triangles, cell_id):
    """Warn (OverlapWarning) when nodes of a new cell lie inside an existing
    cell or that cell's nodes inside the new one, or the new cell's nodes
    inside a non-penetrable constraint's shape or a lattice boundary's. Cheap: bounding boxes first,
    then a winding number only for the nodes in the other cell's box;
    periodic images are not looked at. Lattice boundaries count as walls
    too."""
    import warnings
    from .seeding import _signed_distances  # (seeding imports this module)
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    hits = []
    for c in live_cells(system):
        other = c.mesh.positions()
        olo, ohi = other.min(axis=0), other.max(axis=0)
        if np.any(olo > hi) or np.any(ohi < lo):
            continue
        # the nodes in the other's box, and the centre: two cells placed at one
        # origin have every node on the other's surface (winding about 1/2,
        # either side of the test), their centres well inside each other
        mine = np.vstack([pos, pos.mean(axis=0)])
        mine = mine[np.all((mine >= olo) & (mine <= ohi), axis=1)]
        theirs = np.vstack([other, other.mean(axis=0)])
        theirs = theirs[np.all((theirs >= lo) & (theirs <= hi), axis=1)]
        if (len(mine) and np.any(_winding(mine, other, c.cell_type.mesh._topo.triangles) > 0.5)) or \
                (len(theirs) and np.any(_winding(theirs, pos, triangles) > 0.5)):
            hits.append(f"cell {c.cell_id}")
    for k, con in enumerate(system.constraints):
        shape = getattr(con, "shape", None)
        if shape is None or getattr(con, "penetrable", False):
            continue
        n_in = int(np.count_nonzero(_signed_distances(shape)(pos) <= 0.0))  # is_inside, all at once
        if n_in:
            hits.append(f"constraint {k} ({type(shape).__name__}, {n_in} of its nodes inside)")
    # the fluid's walls too (a wall may be a lattice boundary only); a shape
    # that is also a constraint's is named once
    constraint_shapes = [getattr(con, "shape", None) for con in system.constraints]
    for k, boundary in enumerate(getattr(system, "lbboundaries", ())):
        shape = boundary.shape
        if any(shape is other for other in constraint_shapes):
            continue
        n_in = int(np.count_nonzero(_signed_distances(shape)(pos) <= 0.0))
        if n_in:
            hits.append(f"lattice boundary {k} ({type(shape).__name__}, {n_in} of its nodes inside)")
    if hits:
        warnings.warn(f"{owner}: the new cell (cell_id {cell_id}) overlaps " + ", ".join(hits)
                      + "; place it elsewhere (oif.seed_cells places cells without overlaps)",
                      OverlapWarning, stacklevel=3)


class FixedPoint:
    """A mesh node not connected to a particle (the cell type's relaxed mesh)."""

    def __init__(self, pos, id):
        if isinstance(id, bool) or not isinstance(id, (int, np.integer)):
            raise TypeError(f"FixedPoint: id must be an integer, got {id!r}")
        pos = _vec3("FixedPoint", "pos", pos)
        self.x, self.y, self.z = (float(c) for c in pos)
        self.id = int(id)
        self.neighbour_ids = []

    def get_pos(self):
        return np.array([self.x, self.y, self.z])

    def get_id(self):
        return self.id

    def __repr__(self):
        return f"FixedPoint(id={self.id}, pos={[self.x, self.y, self.z]})"


class PartPoint:
    """A mesh node of a cell: a view of its particle."""

    def __init__(self, part, id, part_id):
        if not isinstance(part, ParticleHandle):
            raise TypeError(f"PartPoint: part must be a particle handle, got {type(part).__name__}")
        self.part = part
        self.id = int(id)
        self.part_id = int(part_id)
        self.neighbour_ids = []

    def get_pos(self):
        return self.part.pos

    def get_part_id(self):
        return self.part_id

    def get_vel(self):
        return self.part.v

    def get_mass(self):
        return self.part.mass

    def get_type(self):
        return self.part.type

    def get_force(self):
        return self.part.f

    def set_pos(self, pos):
        self.part.pos = pos

    def set_vel(self, vel):
        self.part.v = vel

    def set_force(self, force):
        self.part.ext_force = force

    def kill_motion(self):
        self.part.fix = [True, True, True]

    def unkill_motion(self):
        self.part.fix = [False, False, False]

    def __repr__(self):  # no position: reading it is a collective query under MPI
        return f"PartPoint(id={self.id}, part_id={self.part_id})"


def _check_points(owner, pts):
    for p in pts:
        if not isinstance(p, (FixedPoint, PartPoint)):
            raise TypeError(f"{owner}: arguments must be FixedPoint or PartPoint, got {type(p).__name__}")


class Edge:
    def __init__(self, A, B):
        _check_points("Edge", (A, B))
        self.A, self.B = A, B

    def length(self):
        return vec_distance(self.A.get_pos(), self.B.get_pos())

    def __repr__(self):
        return f"Edge({self.A.id}, {self.B.id})"


class Triangle:
    """Triangle (A, B, C); (B - A) x (C - A) points into the cell."""

    def __init__(self, A, B, C):
        _check_points("Triangle", (A, B, C))
        self.A, self.B, self.C = A, B, C

    def area(self):
        return area_triangle(self.A.get_pos(), self.B.get_pos(), self.C.get_pos())

    def __repr__(self):
        return f"Triangle({self.A.id}, {self.B.id}, {self.C.id})"


class Angle:
    """Two triangles (A, B, C) and (B, C, D) sharing the edge BC."""

    def __init__(self, A, B, C, D):
        _check_points("Angle", (A, B, C, D))
        self.A, self.B, self.C, self.D = A, B, C, D

    def size(self):
        return angle_btw_triangles(self.A.get_pos(), self.B.get_pos(), self.C.get_pos(), self.D.get_pos())

    def __repr__(self):
        return f"Angle({self.A.id}, {self.B.id}, {self.C.id}, {self.D.id})"


class ThreeNeighbors:
    """Three well-spread neighbours of a node; their plane's normal
    (B - A) x (C - A) points out of the cell."""

    def __init__(self, A, B, C):
        _check_points("ThreeNeighbors", (A, B, C))
        self.A, self.B, self.C = A, B, C

    def outer_normal(self):
        return get_triangle_normal(self.A.get_pos(), self.B.get_pos(), self.C.get_pos())

    def __repr__(self):
        return f"ThreeNeighbors({self.A.id}, {self.B.id}, {self.C.id})"


# ---------------------------------------------------------------------------
# topology (shared by a cell type and its cells)
# ---------------------------------------------------------------------------
class _Topology:
    """Index arrays of a checked mesh: triangles (PyOIF order), edges (a < b),
    angles (C, a, b, D) per edge, node adjacency."""

    def __init__(self, triangles, n_nodes):
        self.n_nodes = n_nodes
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        self.edges, he_edge = mesh_io.edge_table(self.triangles)
        t = self.triangles
        src = t.ravel()
        opposite = t[:, [2, 0, 1]].ravel()  # corner opposite to half-edge i -> i+1
        # for edge (a, b), a < b: D is opposite the half-edge a -> b, C opposite b -> a
        # (PyOIF's Mesh: D in the triangle that lists a, b in this cyclic order)
        forward = src == self.edges[he_edge, 0]
        d = np.empty(len(self.edges), dtype=np.int64)
        c = np.empty(len(self.edges), dtype=np.int64)
        d[he_edge[forward]] = opposite[forward]
        c[he_edge[~forward]] = opposite[~forward]
        self.angles = np.stack([c, self.edges[:, 0], self.edges[:, 1], d], axis=1)
        self._neighbours = None
        self._exclusions = {}

    @property
    def neighbour_lists(self):
        if self._neighbours is None:
            nb = [[] for _ in range(self.n_nodes)]
            for a, b in self.edges.tolist():
                nb[a].append(b)
                nb[b].append(a)
            self._neighbours = nb
        return self._neighbours

    def adjacency(self):
        from scipy.sparse import coo_matrix
        e = self.edges
        n = self.n_nodes
        data = np.ones(2 * len(e), dtype=np.int32)
        return coo_matrix((data, (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)).tocsr()

    def ring_pairs(self, rings):
        """Pairs (i < j) of nodes at most `rings` edges apart (breadth-first
        distance on the edge graph)."""
        key = ("rings", rings)
        if key not in self._exclusions:
            if rings <= 0:
                pairs = np.zeros((0, 2), dtype=np.int64)
            else:
                from scipy.sparse import identity
                adj = self.adjacency()
                reach = identity(self.n_nodes, dtype=np.int32, format="csr")
                for _ in range(rings):
                    grown = reach + reach @ adj
                    grown.data[:] = 1
                    # reach only grows: an unchanged count means every node reaches the
                    # whole (connected) mesh, so rings beyond the graph diameter cost nothing
                    if grown.nnz == reach.nnz:
                        break
                    reach = grown
                coo = reach.tocoo()
                mask = coo.row < coo.col
                pairs = np.stack([coo.row[mask], coo.col[mask]], axis=1).astype(np.int64)
            self._exclusions[key] = pairs
        return self._exclusions[key]


# ---------------------------------------------------------------------------
# Mesh
# ---------------------------------------------------------------------------
class Mesh:
    """A triangulated surface: the relaxed mesh of a cell type (nodes are
    FixedPoints) or the mesh of a cell (nodes are particles).

    Arrays: ``triangle_ids`` (M x 3, PyOIF orientation), ``edge_ids`` (E x 2),
    ``angle_ids`` (E x 4 rows (A, B, C, D), shared edge BC),
    ``part_ids`` (N, cells only). Lists of view objects, built on first use:
    ``points``, ``edges``, ``triangles``, ``angles``, ``neighbors``.
    """

    def __init__(self, nodes_file=None, triangles_file=None, system=None, resize=(1.0, 1.0, 1.0),
                 particle_type=-1, particle_mass=1.0, normal=False, check_orientation=True):
        _check_system("Mesh", system)
        for name, f in (("nodes_file", nodes_file), ("triangles_file", triangles_file)):
            if f is not None and (not isinstance(f, (str, os.PathLike)) or isinstance(f, bytes)):
                raise TypeError(f"Mesh: parameter '{name}' must be a file name (string or path), got "
                                f"{type(f).__name__}; for arrays use oif.Mesh.from_arrays")
        # PyOIF's Mesh kept these for its cells; -1 means "not set"
        if not _is_int(particle_type) or not -1 <= particle_type <= _INT32_MAX:
            raise ValueError(f"Mesh: parameter 'particle_type' must be an integer >= 0 (or -1, not set), "
                             f"got {particle_type!r}")
        self.particle_type = int(particle_type)
        self.particle_mass = _real("Mesh", "particle_mass", particle_mass, "pos")
        self.system = system
        self.normal = bool(normal)
        self.nodes_file = None if nodes_file is None else os.fspath(nodes_file)
        self.triangles_file = None if triangles_file in (None, "") else os.fspath(triangles_file)
        self._mol_id = None      # cell meshes: the mol_id all their particles must have
        self._owner = "Mesh"     # how errors name this mesh (a cell's mesh: the cell)
        self._nodes = None       # relaxed node positions (cell type) or None (cell)
        self._parts = None       # ParticleSlice (cell)
        self.part_ids = None
        self._topo = None
        self._views = {}
        self.ids_extremal_points = [0] * 6
        if nodes_file is not None:
            resize = _vec3("Mesh", "resize", resize, positive=True)
            data = mesh_io.read_mesh(nodes_file, self.triangles_file, resize=resize,
                                     check_orientation=bool(check_orientation))
            self._set_arrays(data.nodes, _Topology(data.triangles, len(data.nodes)))
            self.flipped_triangles = data.flipped

    # -- construction -------------------------------------------------------
    def _set_arrays(self, nodes, topo):
        self._nodes = np.ascontiguousarray(nodes, dtype=float)
        self._topo = topo
        self._views = {}
        self.ids_extremal_points = [int(i) for pair in zip(self._nodes.argmin(axis=0),
                                                           self._nodes.argmax(axis=0)) for i in pair]

    @classmethod
    def from_arrays(cls, system, nodes, triangles, check_orientation=True):
        """A mesh from arrays (nodes N x 3, triangles M x 3), checked like a file."""
        m = cls(system=system)
        data = mesh_io.from_arrays(nodes, triangles)
        mesh_io.check_mesh(data, check_orientation=check_orientation)
        m._set_arrays(data.nodes, _Topology(data.triangles, len(data.nodes)))
        m.flipped_triangles = data.flipped
        return m

    def copy(self, origin=None, particle_type=-1, particle_mass=1.0, rotate=None, mol_id=None):
        """A cell's mesh: particles at the (rotated, moved) nodes of this one."""
        return self._cell_mesh(self._placed_positions(origin, rotate), particle_type, particle_mass,
                               particle_type if mol_id is None else mol_id)

    def _placed_positions(self, origin=None, rotate=None):
        """This (relaxed) mesh's nodes rotated by `rotate`, then moved by `origin`."""
        if self._nodes is None:
            self._need_topology()
            raise ValueError(f"{self._owner}: only a cell type's relaxed mesh can be copied")
        pos = self._nodes
        if rotate is not None:
            pos = pos @ geo.rotation_matrix(_vec3("Mesh.copy", "rotate", rotate)).T
            pos = np.where(np.abs(pos) < small_epsilon, 0.0, pos)  # as PyOIF's discard_epsilon
        if origin is not None:
            pos = pos + _vec3("Mesh.copy", "origin", origin)
        return pos

    def _cell_mesh(self, pos, particle_type, particle_mass, mol_id):
        """A mesh sharing this one's topology, with new particles at pos."""
        mesh = Mesh(system=self.system)
        mesh.normal = self.normal
        mesh.nodes_file, mesh.triangles_file = self.nodes_file, self.triangles_file
        mesh._topo = self._topo
        mesh.ids_extremal_points = list(self.ids_extremal_points)
        mesh._parts = self.system.part.add(pos=pos, type=int(particle_type), mass=float(particle_mass),
                                           mol_id=int(mol_id))
        mesh.part_ids = mesh._parts.id
        mesh._mol_id = int(mol_id)
        return mesh

    def _need_topology(self):
        if self._topo is None:
            raise ValueError(f"{self._owner}: this mesh has no nodes and triangles (it was created without "
                             f"nodes_file); give nodes_file and triangles_file, or use oif.Mesh.from_arrays")
        return self._topo

    def _live_parts(self, check_mol_id=True):
        """The cell's particles, after checking (one bulk read of mol_id) that
        they all still exist and (check_mol_id) still belong to this cell:
        after system.part.clear() or a removal the ids may be gone or reused
        by other particles, and computing on those would be silently wrong."""
        parts = self._parts
        try:
            mol = parts.mol_id
        except (ValueError, IndexError) as e:
            if "does not exist" not in str(e):
                raise
            raise RuntimeError(f"{self._owner}: its particles were removed or replaced ({e}); this cell object is "
                               f"stale, create a new cell") from None
        if check_mol_id and self._mol_id is not None:
            bad = np.nonzero(mol != self._mol_id)[0]
            if bad.size:
                raise RuntimeError(f"{self._owner}: its particles were removed or replaced (particle "
                                   f"{int(self.part_ids[bad[0]])} has mol_id {int(mol[bad[0]])}, not "
                                   f"{self._mol_id}); this cell object is stale, create a new cell")
        return parts

    # -- arrays ---------------------------------------------------------------
    @property
    def triangle_ids(self):
        return self._need_topology().triangles

    @property
    def edge_ids(self):
        return self._need_topology().edges

    @property
    def angle_ids(self):
        return self._need_topology().angles

    def positions(self):
        """Node positions (N x 3): unfolded particle positions for a cell."""
        if self._parts is not None:
            return self._live_parts().pos
        self._need_topology()
        return self._nodes.copy()

    # -- PyOIF view lists -------------------------------------------------------
    def _point_list(self):
        if "points" not in self._views:
            nb = self._need_topology().neighbour_lists
            if self._parts is None:
                pts = [FixedPoint(p, i) for i, p in enumerate(self._nodes)]
            else:
                self._live_parts()
                pts = [PartPoint(ParticleHandle(self.system, int(pid)), i, int(pid))
                       for i, pid in enumerate(self.part_ids)]
            for p in pts:
                p.neighbour_ids = list(nb[p.id])
            self._views["points"] = pts
        return self._views["points"]

    @property
    def points(self):
        return self._point_list()

    @property
    def edges(self):
        if "edges" not in self._views:
            p = self._point_list()
            self._views["edges"] = [Edge(p[a], p[b]) for a, b in self.edge_ids.tolist()]
        return self._views["edges"]

    @property
    def triangles(self):
        if "triangles" not in self._views:
            p = self._point_list()
            self._views["triangles"] = [Triangle(p[a], p[b], p[c]) for a, b, c in self.triangle_ids.tolist()]
        return self._views["triangles"]

    @triangles.setter
    def triangles(self, value):
        """Replace the triangle list (as PyOIF scripts may do, e.g. to analyse
        a subset); the mesh's own topology arrays are not changed."""
        value = list(value)
        for t in value:
            if not isinstance(t, Triangle):
                raise TypeError(f"Mesh.triangles: items must be Triangle objects, got {type(t).__name__}")
        self._views["triangles"] = value
        self._triangle_override = np.array([[t.A.id, t.B.id, t.C.id] for t in value],
                                           dtype=np.int64).reshape(-1, 3)

    @property
    def angles(self):
        if "angles" not in self._views:
            p = self._point_list()
            self._views["angles"] = [Angle(p[a], p[b], p[c], p[d]) for a, b, c, d in self.angle_ids.tolist()]
        return self._views["angles"]

    @property
    def neighbors(self):
        """ThreeNeighbors per node (PyOIF's normal=True choice: the three
        neighbours whose unit directions add up to the shortest vector,
        ordered so that their plane's normal points outward)."""
        if "neighbors" not in self._views:
            p = self._point_list()
            if not self.normal:
                self._views["neighbors"] = [ThreeNeighbors(q, q, q) for q in p]
            else:
                pos = self.positions()
                vnormal = self._vertex_normals(pos)
                out = []
                for i, nb in enumerate(self._topo.neighbour_lists):
                    u = pos[nb] - pos[i]
                    u /= np.linalg.norm(u, axis=1)[:, None]
                    best = min(itertools.combinations(range(len(nb)), 3),
                               key=lambda c: np.linalg.norm(u[c[0]] + u[c[1]] + u[c[2]]))
                    a, b, c = (nb[k] for k in best)
                    if np.dot(np.cross(pos[b] - pos[a], pos[c] - pos[a]), vnormal[i]) < 0:
                        b, c = c, b
                    out.append(ThreeNeighbors(p[a], p[b], p[c]))
                self._views["neighbors"] = out
        return self._views["neighbors"]

    def _vertex_normals(self, pos):
        """Area-weighted outward normal at every node."""
        n = -geo.triangle_normals(pos, self.triangle_ids)
        acc = np.zeros_like(pos)
        for k in range(3):
            np.add.at(acc, self.triangle_ids[:, k], n)
        return acc / np.linalg.norm(acc, axis=1)[:, None]

    # -- analysis ---------------------------------------------------------------
    def _analysis_triangles(self):
        return getattr(self, "_triangle_override", self.triangle_ids)

    def get_n_nodes(self):
        return self._need_topology().n_nodes

    def get_n_triangles(self):
        return len(self.triangle_ids)

    def get_n_edges(self):
        return len(self.edge_ids)

    def __repr__(self):
        if self._topo is None:
            return "Mesh(empty)"
        what = f"cell mesh, mol_id {self._mol_id}" if self._mol_id is not None else "relaxed mesh"
        source = f", '{os.path.basename(self.nodes_file)}'" if self.nodes_file else ""
        return f"Mesh({what}{source}, {self._topo.n_nodes} nodes, {len(self._topo.triangles)} triangles)"

    def surface(self):
        return geo.surface(self.positions(), self._analysis_triangles())

    def volume(self):
        """Enclosed volume. For a triangle list replaced by the script (an open
        surface, whose volume is a convention) PyOIF's formula: minus the sum
        of the triangles' z-projected areas times their mean z."""
        if getattr(self, "_triangle_override", None) is None:
            return geo.volume(self.positions(), self._analysis_triangles())
        pos = self.positions()
        tri = pos[self._triangle_override]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        # area * n_z / |n| = |n| / 2 * n_z / |n| = n_z / 2
        return float(0.0 - np.sum(0.5 * n[:, 2] * tri[:, :, 2].mean(axis=1)))

    def _edge_lengths(self):
        if len(self.edge_ids) == 0:
            raise ValueError("Mesh: the mesh has no edges")
        return geo.edge_lengths(self.positions(), self.edge_ids)

    def min_edge_length(self):
        return float(self._edge_lengths().min())

    def max_edge_length(self):
        return float(self._edge_lengths().max())

    def aver_edge_length(self):
        return float(self._edge_lengths().mean())

    def stdev_edge_length(self):
        return float(self._edge_lengths().std(ddof=1))

    def angle_sizes(self):
        """Dihedral angle of every angle_ids row (PyOIF's definition)."""
        return geo.dihedral_angles(self.positions(), self.angle_ids)

    def min_angle(self):
        """(smallest dihedral angle, the ids of its four nodes A, B, C, D):
        the most strongly bent place of the membrane (PyOIF paper's
        extensibility example). Node ids are mesh ids (``part_ids[ids]``
        gives a cell's particle ids)."""
        phi = self.angle_sizes()
        k = int(np.argmin(phi))
        return float(phi[k]), [int(i) for i in self.angle_ids[k]]

    def print_analysis(self):
        print("\t n_nodes: " + str(self.get_n_nodes()))
        print("\t n_triangles: " + str(self.get_n_triangles()))
        print("\t n_edges: " + str(self.get_n_edges()))
        print("\t aver_edge_length: " + str(self.aver_edge_length()))
        print("\t min_edge_length: " + str(self.min_edge_length()))
        print("\t max_edge_length: " + str(self.max_edge_length()))
        print("\t stdev_edge_length: " + str(self.stdev_edge_length()))

    def total_fluid_force(self, lbfluid, friction):
        """Sum over nodes of friction (u - v): the fluid's force on the cell."""
        if not callable(getattr(lbfluid, "get_interpolated_velocity", None)):
            raise TypeError(f"Mesh.total_fluid_force: parameter 'lbfluid' must be a lattice-Boltzmann fluid "
                            f"(with get_interpolated_velocity), got {type(lbfluid).__name__}")
        friction = _real("Mesh.total_fluid_force", "friction", friction, "nonneg")
        pos = self.positions()
        vel = self._parts.v if self._parts is not None else np.zeros_like(pos)
        u = np.array([lbfluid.get_interpolated_velocity(p) for p in pos])
        return friction * (u - vel).sum(axis=0)

    def check_orientation(self):
        """Re-check this mesh's triangles (closed 2-manifold, consistent
        orientation, PyOIF's inward order); fixes orientation in place."""
        data = mesh_io.MeshData(self.positions(), self.triangle_ids, self.nodes_file or "<mesh>",
                                self.triangles_file or "<mesh>")
        mesh_io.check_mesh(data, check_orientation=True)
        self._topo = _Topology(data.triangles, len(data.nodes))
        self._views = {}
        return 0

    def output_mesh_triangles(self, triangles_file=None):
        """Write the (checked, consistently oriented) triangles in PyOIF's format."""
        if triangles_file is None:
            raise ValueError("Mesh.output_mesh_triangles: parameter 'triangles_file' is required")
        mesh_io.write_triangles(triangles_file, self.triangle_ids, "Mesh.output_mesh_triangles")
        return 0

    def output_mesh_nodes(self, nodes_file=None):
        """Write the node positions (relaxed mesh, or a cell's current ones) in PyOIF's format."""
        if nodes_file is None:
            raise ValueError("Mesh.output_mesh_nodes: parameter 'nodes_file' is required")
        mesh_io.write_nodes(nodes_file, self.positions(), "Mesh.output_mesh_nodes")
        return 0

    def mirror(self, mirror_x=0, mirror_y=0, mirror_z=0, out_file_name=""):
        """Write the nodes mirrored along one axis to out_file_name (PyOIF)."""
        if out_file_name == "":
            raise ValueError("Mesh.mirror: parameter 'out_file_name' is required")
        flags = (mirror_x, mirror_y, mirror_z)
        if any(f not in (0, 1) for f in flags):
            raise ValueError(f"Mesh.mirror: mirror_x, mirror_y, mirror_z must be 0 or 1, got {flags}")
        if sum(flags) > 1:
            raise ValueError("Mesh.mirror: mirror along one axis only")
        pos = self.positions()
        pos[:, np.array(flags, dtype=bool)] *= -1.0
        if sum(flags) == 1:
            mesh_io.write_nodes(out_file_name, pos, "Mesh.mirror")
        return 0


# ---------------------------------------------------------------------------
# OifCellType
# ---------------------------------------------------------------------------
class OifCellType:
    """A template for cells: relaxed mesh + elastic moduli.

    ``OifCellType(nodes_file, triangles_file, system, resize=(1, 1, 1),
    ks=0, kslin=0, kb=0, kal=0, kag=0, kv=0, kvisc=0, normal=False,
    check_orientation=True)``

    nodes_file/triangles_file: PyOIF's ``nodes.dat``/``triangles.dat`` (or a
    single Gmsh/STL/OFF file as nodes_file with triangles_file="");
    ``oif.mesh_files("rbc374")`` gives the shipped ones. resize scales x, y,
    z. ks (neo-Hookean) or kslin (linear) stretching, kb bending, kal local
    area, kag global area, kv volume, kvisc membrane viscosity (model eqs.
    3-7). normal=True computes outward node normals each step (needed by
    membrane collision).
    """

    def __init__(self, nodes_file="", triangles_file="", system=None, resize=(1.0, 1.0, 1.0), ks=0.0,
                 kslin=0.0, kb=0.0, kal=0.0, kag=0.0, kv=0.0, kvisc=0.0, normal=False,
                 check_orientation=True):
        owner = "OifCellType"
        _check_system(owner, system)
        for name, f in (("nodes_file", nodes_file), ("triangles_file", triangles_file)):
            if f is not None and (not isinstance(f, (str, os.PathLike)) or isinstance(f, bytes)):
                raise TypeError(f"{owner}: parameter '{name}' must be a file name (string or path), got "
                                f"{type(f).__name__}; for arrays build the files or use oif.Mesh.from_arrays")
        if nodes_file is None or (isinstance(nodes_file, str) and nodes_file == ""):
            raise ValueError(f"{owner}: parameter 'nodes_file' is required")
        if triangles_file in ("", None) and str(nodes_file).lower().endswith(".dat"):
            raise ValueError(f"{owner}: parameter 'triangles_file' is required with a nodes.dat file")
        for name, value in (("normal", normal), ("check_orientation", check_orientation)):
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{owner}: parameter '{name}' must be True or False, got {value!r}")
        moduli = {k: _real(owner, k, v, "nonneg") for k, v in
                  (("ks", ks), ("kslin", kslin), ("kb", kb), ("kal", kal), ("kag", kag), ("kv", kv),
                   ("kvisc", kvisc))}
        if moduli["ks"] != 0 and moduli["kslin"] != 0:
            raise ValueError(f"{owner}: use either 'ks' (neo-Hookean) or 'kslin' (linear) "
                             f"stretching, not both (got ks={ks}, kslin={kslin})")
        self.system = system
        self.resize = tuple(float(x) for x in _vec3(owner, "resize", resize, positive=True))
        self.mesh = Mesh(nodes_file=nodes_file, triangles_file=triangles_file, system=system,
                         resize=self.resize, normal=bool(normal), check_orientation=bool(check_orientation))
        # a cell a few micrometres wide given in metres (resize=(3.9e-6, ...))
        # would fail only in the run, as an inverted triangle
        _check_not_metres(f"{owner}: the cell (mesh times parameter 'resize')",
                          float(np.ptp(np.asarray(self.mesh._nodes, dtype=float), axis=0).max()))
        for k, v in moduli.items():
            setattr(self, k, v)
        self.normal = bool(normal)
        self.check_orientation = bool(check_orientation)

        nodes, topo = self.mesh._nodes, self.mesh._topo
        # reference values of each angle row (A, B, C, D): edge BC, dihedral, areas ABC, DBC
        ang = topo.angles
        self.r0 = geo.edge_lengths(nodes, ang[:, [1, 2]])
        self.phi0 = geo.dihedral_angles(nodes, ang)
        self.A01 = geo.triangle_areas(nodes, ang[:, [0, 1, 2]])
        self.A02 = geo.triangle_areas(nodes, ang[:, [3, 1, 2]])
        self.surface0 = geo.surface(nodes, topo.triangles)
        self.volume0 = geo.volume(nodes, topo.triangles)

        self.local_force_interaction = None
        self.global_force_interaction = None
        self.out_direction_interaction = None
        inter = lbmd.interactions
        if any(moduli[k] != 0 for k in ("ks", "kslin", "kb", "kal", "kvisc")):
            self.local_force_interaction = inter.OifLocalForces(
                r0=float(self.r0[0]), ks=self.ks, kslin=self.kslin, phi0=float(self.phi0[0]), kb=self.kb,
                A01=float(self.A01[0]), A02=float(self.A02[0]), kal=self.kal, kvisc=self.kvisc)
            self.local_bond_id = system.bonded_inter.add(self.local_force_interaction)
        if self.kag != 0 or self.kv != 0:
            self.global_force_interaction = inter.OifGlobalForces(
                A0_g=self.surface0, ka_g=self.kag, V0=self.volume0, kv=self.kv)
            self.global_bond_id = system.bonded_inter.add(self.global_force_interaction)
        if self.normal:
            self.out_direction_interaction = inter.OifOutDirection()
            self.out_direction_bond_id = system.bonded_inter.add(self.out_direction_interaction)

    def copy_to(self, system, **moduli):
        """This type on another lbmd.System: the same relaxed mesh (nodes as
        this type holds them, so an origin and rotation place its cells
        alike), normals and moduli; keyword arguments replace moduli (e.g.
        kvisc=0). For scratch systems: the settings check's membrane trial
        and the deformable stage of oif.pack_cells."""
        import tempfile
        unknown = sorted(set(moduli) - {"ks", "kslin", "kb", "kal", "kag", "kv", "kvisc"})
        if unknown:
            raise TypeError(f"OifCellType.copy_to: unknown moduli {unknown}")
        values = {k: getattr(self, k) for k in ("ks", "kslin", "kb", "kal", "kag", "kv", "kvisc")}
        values.update(moduli)
        with tempfile.TemporaryDirectory() as tmp:
            nf, tf = os.path.join(tmp, "nodes.dat"), os.path.join(tmp, "triangles.dat")
            np.savetxt(nf, self.mesh._nodes, fmt="%.17g")
            np.savetxt(tf, self.mesh._topo.triangles, fmt="%d")
            return OifCellType(nf, tf, system=system, normal=self.normal, check_orientation=False, **values)

    # engine bond rows, in mesh node ids -------------------------------------
    def _local_rows(self):
        """OifLocalForces rows as ESPResSo's PyOIF added them: the bond is owned
        by B (first edge node) with partners A, C, D; per bond (r0, phi0, A01, A02)."""
        ang = self.mesh.angle_ids
        return ang[:, [1, 0, 2, 3]], np.stack([self.r0, self.phi0, self.A01, self.A02], axis=1)

    def _triangle_rows(self):
        """Triangles with outward normals (B - A) x (C - A), for
        OifGlobalForces and OifOutDirection."""
        return mesh_io.outward(self.mesh.triangle_ids)

    @property
    def local_force_interactions(self):
        """PyOIF's list of [interaction, [A, B, C, D]] per angle (one shared
        interaction here; reference values are per bond)."""
        return [[self.local_force_interaction, [a.A, a.B, a.C, a.D]] for a in self.mesh.angles]

    def print_info(self):
        print("\nThe following OifCellType was created: ")
        print("\t nodes_file: " + str(self.mesh.nodes_file))
        print("\t triangles_file: " + str(self.mesh.triangles_file))
        print("\t n_nodes: " + str(self.mesh.get_n_nodes()))
        print("\t n_triangles: " + str(self.mesh.get_n_triangles()))
        print("\t n_edges: " + str(self.mesh.get_n_edges()))
        for k in ("ks", "kslin", "kb", "kal", "kag", "kv", "kvisc"):
            print(f"\t {k}: " + custom_str(getattr(self, k)))
        print("\t normal: " + str(self.normal))
        print("\t resize: " + str(self.resize))
        print("\t surface: " + custom_str(self.surface0))
        print("\t volume: " + custom_str(self.volume0))
        print(" ")

    #: the moduli's terms (also of the energies), and which interaction computes each
    MODULUS_TERMS = (("stretching", "local"), ("bending", "local"), ("local_area", "local"),
                     ("global_area", "global"), ("volume", "global"))
    ENERGY_TERMS = tuple(term for term, _ in MODULUS_TERMS)

    def get_energies(self, cell_id=None):
        """dict cell_id -> dict term -> energy for every cell of this type at
        the current positions, from one pass over the bonds per interaction
        (OifCell.get_energies() gives one cell's; to look at many cells, call
        this once instead). Terms: 'stretching', 'bending', 'local_area',
        'global_area', 'volume' (0.0 where the modulus is off) and 'total'.
        Cells whose moduli are all zero have no bonds and are not listed.
        cell_id: that cell's bonds only (what OifCell.get_energies() uses)."""
        out = {}
        for inter in (self.local_force_interaction, self.global_force_interaction):
            if inter is None:
                continue
            terms = self.system.analysis.oif_energies(inter, -1 if cell_id is None else int(cell_id))
            for term, (mol_ids, values) in terms.items():
                for mol, value in zip(np.asarray(mol_ids).tolist(), np.asarray(values).tolist()):
                    out.setdefault(int(mol), dict.fromkeys(self.ENERGY_TERMS, 0.0))[term] = float(value)
        for energies in out.values():
            energies["total"] = sum(energies[t] for t in self.ENERGY_TERMS)
        return out

    def reference_diameter(self):
        """Largest distance between two nodes of the relaxed mesh (computed
        once)."""
        if "_reference_diameter" not in self.__dict__:
            self.__dict__["_reference_diameter"] = geo.max_pair_distance(self.mesh.positions())
        return self.__dict__["_reference_diameter"]

    def suggest_LBgamma(self, visc=None, dens=None):
        """PyOIF's empirical fluid-coupling friction for this mesh density,
        fluid viscosity and density (lattice units): calibrated on the drag
        of a 393-node sphere of surface 201.06 (Jancigova, Tothova et al.),
        scaled by node density."""
        visc = _real("suggest_LBgamma", "visc", visc, "pos")
        dens = _real("suggest_LBgamma", "dens", dens, "pos")
        gamma = lb_gamma(self.mesh.get_n_nodes(), self.surface0, visc, dens)
        if not gamma > 0:
            # the formula is a linear fit; far below its calibration (visc 1.5, dens 1.025) it goes negative
            raise ValueError(f"suggest_LBgamma: visc={visc!r} and dens={dens!r} are outside the range of the "
                             f"calibration (visc about 1.5 to 5.9, dens about 1 to 6, lattice units): the "
                             f"formula gives {gamma:.4g} <= 0; choose the friction yourself")
        return float(gamma)

    def __repr__(self):
        moduli = ", ".join(f"{k}={getattr(self, k):g}" for k in ("ks", "kslin", "kb", "kal", "kag", "kv", "kvisc")
                           if getattr(self, k) != 0)
        source = f"'{os.path.basename(self.mesh.nodes_file)}', " if self.mesh.nodes_file else ""
        return (f"OifCellType({source}{self.mesh.get_n_nodes()} nodes, resize={list(self.resize)}, "
                f"{moduli or 'no moduli'}, normal={self.normal}, volume0={self.volume0:.6g}, "
                f"surface0={self.surface0:.6g})")

    def exclusion_pairs(self, rings=DEFAULT_EXCLUSION_RINGS, distance=None):
        """Node pairs (i < j, mesh ids) excluded from self-cell contacts: up to
        `rings` edges apart, and (distance) closer than that in the relaxed mesh."""
        pairs = self.mesh._topo.ring_pairs(int(rings))
        if distance is not None and distance > 0:
            key = ("distance", float(distance))
            cache = self.mesh._topo._exclusions
            if key not in cache:
                from scipy.spatial import cKDTree
                close = np.array(sorted(cKDTree(self.mesh._nodes).query_pairs(float(distance))),
                                 dtype=np.int64).reshape(-1, 2)
                cache[key] = close
            pairs = np.unique(np.vstack([pairs, cache[key]]), axis=0)
        return pairs


# ---------------------------------------------------------------------------
# OifCell
# ---------------------------------------------------------------------------
class OifCell:
    """One cell: particles at the nodes of its type's mesh, with all bonds.

    ``OifCell(cell_type, origin, particle_type, particle_mass=1.0,
    rotate=None, exclusion_neighbours=True, self_cell_cutoff=None,
    rotation_ids=(), check_overlaps=True, inner_particles=0,
    inner_particle_type=None)``

    origin: where the mesh's (0, 0, 0) goes; rotate: angles about x, y, z
    (PyOIF's convention); exclusion_neighbours: True (PyOIF: first and second
    mesh neighbours), False, or the number of edge rings to exclude from
    self-cell contacts; self_cell_cutoff: also exclude node pairs closer than
    this in the relaxed mesh (so a self-cell soft sphere with this cutoff is
    silent in the relaxed shape); check_overlaps: warn (OverlapWarning) when
    the new cell overlaps a cell or wall (False: the caller has checked, as
    oif.pack_cells does; the test costs a pass over every cell). Each cell
    gets its own mol_id (``cell_id``), so cells of one particle type still
    collide with each other. inner_particles: that many particles spread
    through the cell's inside, caged by the advised contact with the
    membrane and moving with the cell (``cell.inner_particles``; type
    inner_particle_type, default the cell's; doc/compound-cells.md).
    """

    def __init__(self, cell_type=None, origin=None, particle_type=None, particle_mass=1.0, rotate=None,
                 exclusion_neighbours=True, self_cell_cutoff=None, rotation_ids=(), check_overlaps=True,
                 inner_particles=0, inner_particle_type=None):
        owner = "OifCell"
        # every argument is checked before anything is added to the system
        if not isinstance(cell_type, OifCellType):
            raise TypeError(f"{owner}: parameter 'cell_type' must be an OifCellType, got {type(cell_type).__name__}")
        if origin is None:
            raise TypeError(f"{owner}: missing required parameter 'origin'")
        origin = _vec3(owner, "origin", origin)
        if not _is_int(particle_type) or not 0 <= particle_type <= _INT32_MAX:
            raise TypeError(f"{owner}: parameter 'particle_type' must be an integer in 0..{_INT32_MAX}, "
                            f"got {particle_type!r}")
        particle_mass = _real(owner, "particle_mass", particle_mass, "pos")
        if rotate is not None:
            rotate = _vec3(owner, "rotate", rotate)
        rings = _exclusion_rings(owner, exclusion_neighbours)
        if self_cell_cutoff is not None:
            self_cell_cutoff = _real(owner, "self_cell_cutoff", self_cell_cutoff, "nonneg")
        rotation_ids = _node_ids(owner, "rotation_ids", rotation_ids, cell_type.mesh.get_n_nodes())
        if isinstance(inner_particles, bool) or not isinstance(inner_particles, (int, np.integer)) \
                or inner_particles < 0:
            raise ValueError(f"{owner}: parameter 'inner_particles' must be a whole number >= 0, got "
                             f"{inner_particles!r}")
        if inner_particle_type is not None and (not _is_int(inner_particle_type)
                                                or not 0 <= inner_particle_type <= _INT32_MAX):
            raise TypeError(f"{owner}: parameter 'inner_particle_type' must be an integer in 0..{_INT32_MAX}, "
                            f"got {inner_particle_type!r}")

        system = cell_type.system
        # cell ids never repeat (a stale cell object is recognised by its mol_id);
        # the counter advances only once the cell is complete
        cell_id = int(system.max_oif_objects)
        if cell_id >= _INT32_MAX:  # the counter could not advance past it
            raise ValueError(f"{owner}: no cell ids left (system.max_oif_objects = {cell_id})")
        pos = cell_type.mesh._placed_positions(origin, rotate)
        check_periodic_extent(owner, system, pos, cell_type.mesh.max_edge_length())
        check_closed_extent(owner, system, pos)
        if not isinstance(check_overlaps, (bool, np.bool_)):
            raise TypeError(f"{owner}: parameter 'check_overlaps' must be True or False, got {check_overlaps!r}")
        if check_overlaps:
            _warn_overlaps(owner, system, pos, cell_type.mesh._topo.triangles, cell_id)
        self.cell_type = cell_type
        self.system = system
        self.cell_id = cell_id
        self.particle_type = int(particle_type)
        self.particle_mass = particle_mass
        self.origin = origin
        self.rotate = rotate
        self.exclusion_neighbours = exclusion_neighbours
        self.self_cell_cutoff = self_cell_cutoff
        self.mesh = cell_type.mesh._cell_mesh(pos, particle_type, particle_mass, cell_id)
        self.mesh._owner = f"OifCell (cell_id {cell_id})"
        try:
            self._add_bonds(rings, self_cell_cutoff)
            self.set_rotation(rotation_ids)
        except BaseException:
            self._discard()  # no half-built cell stays behind
            raise
        system.max_oif_objects = cell_id + 1
        self.inner_ids = []
        if inner_particles:
            from .compound import add_inner_particles
            try:
                self.inner_ids = add_inner_particles(self, int(inner_particles), inner_particle_type)
            except BaseException:
                self._discard()
                raise
        cell_registry.register(self)

    def __setstate__(self, state):
        # a cell loaded from a checkpoint (lbmd.checkpoint.load) is live again
        self.__dict__.update(state)
        cell_registry.register(self)

    # -- what the engine asks of a cell (lbmd.cell_registry) ---------------------
    #: the cells' lines of system.check_settings()
    settings_check = staticmethod(cell_settings)

    def is_live(self):
        """True while all the cell's particles are in the System (False once
        removed, e.g. at an outlet)."""
        try:
            self.mesh._live_parts()
        except RuntimeError:
            return False
        return True

    def check_fits(self, box, periodic):
        """ValueError when the cell would overlap its own periodic image (or
        its bonds be cut by the nearest-image convention) in a box of these
        lengths and periodicity (check_periodic_extent)."""
        pos = self.mesh.positions()
        check_periodic_extent("System", self.system, pos, self.cell_type.mesh.max_edge_length(),
                              what=f"cell {self.cell_id}", box=box, periodic=periodic)
        check_closed_extent("System", self.system, pos, what=f"cell {self.cell_id}", box=box, periodic=periodic)

    def remove(self):
        """Takes the cell out of the simulation: its particles go, and with
        them its bonds and exclusions (e.g. at an outlet, oif.CellFlow). The
        object keeps its parameters; its geometry can no longer be read."""
        self.mesh._live_parts().remove()
        self._remove_inner()
        nucleus = getattr(self, "nucleus", None)
        if nucleus is not None and nucleus.is_live():
            nucleus.remove()  # a nucleus goes with its cell (at an outlet too)

    @property
    def inner_particles(self):
        """The inner particles (a ParticleSlice; empty without)."""
        return self.system.part.by_ids(getattr(self, "inner_ids", []))

    def _remove_inner(self):
        ids = [i for i in getattr(self, "inner_ids", []) if self.system.part.exists(i)]
        if ids:
            self.system.part.by_ids(ids).remove()
        self.inner_ids = []

    def _discard(self):
        """Removes the cell's particles (and so their bonds and exclusions)
        while an error is being raised: a failure here must not hide it."""
        try:
            self.mesh._parts.remove()
        except Exception:  # pragma: no cover - the original error is reported
            pass

    def _add_bonds(self, rings, self_cell_cutoff):
        cell_type, system = self.cell_type, self.system
        ids = self.mesh.part_ids
        part = system.part
        if cell_type.local_force_interaction is not None:
            rows, per_bond = cell_type._local_rows()
            part.add_bonds(cell_type.local_force_interaction, ids[rows], per_bond)
        tri_rows = None
        if cell_type.global_force_interaction is not None:
            tri_rows = ids[cell_type._triangle_rows()]
            part.add_bonds(cell_type.global_force_interaction, tri_rows)
        if cell_type.out_direction_interaction is not None:
            if tri_rows is None:
                tri_rows = ids[cell_type._triangle_rows()]
            part.add_bonds(cell_type.out_direction_interaction, tri_rows)
        pairs = cell_type.exclusion_pairs(rings, self_cell_cutoff)
        self.n_exclusions = len(pairs)
        if len(pairs):
            system.part.add_exclusions(ids[pairs])

    # -- particles ----------------------------------------------------------------
    @property
    def particles(self):
        """The cell's particles (lbmd ParticleSlice; .pos, .v, .f in bulk);
        RuntimeError if any of them was removed. (Their mol_id is not
        checked here: this is the low-level handle, e.g. to renumber cells;
        the cell's own methods check it.)"""
        return self.mesh._live_parts(check_mol_id=False)

    @property
    def _parts(self):
        """The particles, checked to be all this cell's (mol_id == cell_id)."""
        return self.mesh._live_parts()

    def get_n_nodes(self):
        return self.mesh.get_n_nodes()

    def get_n_triangles(self):
        return self.mesh.get_n_triangles()

    def get_n_edges(self):
        return self.mesh.get_n_edges()

    def __repr__(self):  # the parameters it was made with: no (collective) particle query
        origin = [float(x) for x in self.origin]
        return (f"OifCell(cell_id={self.cell_id}, {self.mesh.get_n_nodes()} nodes, "
                f"particle_type={self.particle_type}, origin={origin} (at creation))")

    # -- position and motion ---------------------------------------------------
    def get_origin(self):
        """Mean node position (unfolded)."""
        return self.mesh.positions().mean(axis=0)

    def set_origin(self, new_origin=(0.0, 0.0, 0.0)):
        """Move the cell rigidly so that its mean node position is new_origin;
        its inner particles and its nucleus (doc/compound-cells.md) move with it."""
        pos = self.mesh.positions()
        shift = _vec3("OifCell.set_origin", "new_origin", new_origin) - pos.mean(axis=0)
        self._parts.pos = pos + shift
        if getattr(self, "inner_ids", None):
            inner = self.inner_particles
            inner.pos = inner.pos + shift
        nucleus = getattr(self, "nucleus", None)
        if nucleus is not None and nucleus.is_live():
            nucleus.set_origin(nucleus.mesh.positions().mean(axis=0) + shift)

    def get_approx_origin(self):
        """Mean of the six nodes extremal in x, y, z in the relaxed mesh (cheap centre)."""
        return self.mesh.positions()[self.mesh.ids_extremal_points].mean(axis=0)

    def get_origin_folded(self):
        return np.mod(self.get_origin(), self.system.box_l)

    def get_velocity(self):
        return self._parts.v.mean(axis=0)

    def set_velocity(self, new_velocity=(0.0, 0.0, 0.0)):
        self._parts.v = _vec3("OifCell.set_velocity", "new_velocity", new_velocity)

    def set_force(self, new_force=(0.0, 0.0, 0.0)):
        """Constant external force on every node."""
        self._parts.ext_force = _vec3("OifCell.set_force", "new_force", new_force)

    def kill_motion(self):
        self._parts.fix = [True, True, True]

    def unkill_motion(self):
        self._parts.fix = [False, False, False]

    def pos_bounds(self):
        """[x_min, x_max, y_min, y_max, z_min, z_max] of the nodes."""
        pos = self.mesh.positions()
        lo, hi = pos.min(axis=0), pos.max(axis=0)
        return [float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]), float(lo[2]), float(hi[2])]

    # -- shape ------------------------------------------------------------------------
    def surface(self):
        return self.mesh.surface()

    def volume(self):
        return self.mesh.volume()

    def diameter(self):
        """Largest distance between two nodes."""
        return geo.max_pair_distance(self.mesh.positions())

    def reference_diameter(self):
        """The diameter of the relaxed mesh (the cell type's): D / D0 with
        diameter() is the deformation lbmd.visualization colours cells by."""
        return self.cell_type.reference_diameter()

    def min_edge_length(self):
        return self.mesh.min_edge_length()

    def max_edge_length(self):
        return self.mesh.max_edge_length()

    def aver_edge_length(self):
        return self.mesh.aver_edge_length()

    def stdev_edge_length(self):
        return self.mesh.stdev_edge_length()

    def print_mesh_analysis(self):
        return self.mesh.print_analysis()

    def total_fluid_force(self, lbfluid, friction):
        return self.mesh.total_fluid_force(lbfluid, friction)

    def suggest_LBgamma(self, visc=None, dens=None):
        return self.cell_type.suggest_LBgamma(visc=visc, dens=dens)

    # -- rotation tracking (PyOIF) ---------------------------------------------
    def set_rotation(self, ids=()):
        """Remember the current directions (from the centre) of nodes `ids`
        (default: the six extremal nodes) for get_rotation_angles()."""
        ids = _node_ids("OifCell.set_rotation", "ids", ids, self.get_n_nodes())
        self.rot_ids = ids if ids else list(self.mesh.ids_extremal_points)
        pos = self.mesh.positions()
        self.rot_init_pos = pos[self.rot_ids] - pos.mean(axis=0)

    def get_rotation_positions(self):
        pos = self.mesh.positions()
        return pos[self.rot_ids] - pos.mean(axis=0)

    def get_rotation_angles(self):
        """Angle between each remembered node direction and its current one."""
        cur = self.get_rotation_positions()
        return [angle_btw_vectors(a, b) for a, b in zip(self.rot_init_pos, cur)]

    # -- per-cell observables -------------------------------------------------------
    def _reference_lengths_areas(self):
        """The relaxed mesh's edge lengths and triangle areas (cached on the type)."""
        ct = self.cell_type
        if getattr(ct, "_strain_reference", None) is None:
            topo = ct.mesh._topo
            nodes = np.asarray(ct.mesh._nodes, dtype=float)
            ct._strain_reference = (geo.edge_lengths(nodes, topo.edges), geo.triangle_areas(nodes, topo.triangles))
        return ct._strain_reference

    def edge_strains(self):
        """Per mesh edge, its length over its length in the relaxed mesh, minus
        1 (the stretch the stretching force, eq. 1, acts against)."""
        l0, _ = self._reference_lengths_areas()
        return geo.edge_lengths(self.mesh.positions(), self.cell_type.mesh._topo.edges) / l0 - 1.0

    def area_strains(self):
        """Per triangle, its area over its relaxed area, minus 1 (the local
        area change the local area force, eq. 5, acts against)."""
        _, a0 = self._reference_lengths_areas()
        return geo.triangle_areas(self.mesh.positions(), self.cell_type.mesh._topo.triangles) / a0 - 1.0

    def max_edge_strain(self):
        """The largest abs(l / l0 - 1) over the edges: the membrane's largest
        stretch (or compression) now."""
        return float(np.abs(self.edge_strains()).max())

    def max_area_strain(self):
        """The largest abs(A / A0 - 1) over the triangles: the largest local area
        change now, the measure of oif.update_damage."""
        return float(np.abs(self.area_strains()).max())

    def deformation_index(self):
        """Taylor's deformation index D = (a - c) / (a + c), a and c the
        longest and shortest semi-axes, taken proportional to the roots of the
        largest and smallest eigenvalues of the nodes' gyration tensor (exact
        for an ellipsoid whose nodes are an evenly meshed sphere stretched
        along its axes, as a capsule's in shear; 0 for a sphere). A relaxed
        red cell, a disc, has D = 0.357 (rbc374: the spread of its nodes
        through its thickness against across its width); as the disc folds
        or stretches in flow, D changes from there."""
        pos = self.mesh.positions()
        d = pos - pos.mean(axis=0)
        eig = np.clip(np.linalg.eigvalsh(d.T @ d / len(d)), 0.0, None)
        a, c = np.sqrt(eig[-1]), np.sqrt(eig[0])
        return float((a - c) / (a + c)) if a + c > 0 else 0.0

    @property
    def damage(self):
        """The cell's CellDamage record (oif.update_damage fills it; until its
        first sample an empty record at the default threshold, not kept: the
        first update_damage still sets the threshold)."""
        record = getattr(self, "_damage", None)
        return CellDamage() if record is None else record

    # -- output -------------------------------------------------------------------
    def _vtk_triangles(self):
        # outward order so that ParaView's normals point out of the cell
        return mesh_io.outward(self.mesh._analysis_triangles())

    def output_vtk_pos(self, file_name=None, point_data=None):
        """Legacy VTK polydata of the surface at unfolded positions;
        point_data {name: N values or N x 3 vectors} adds per-node data
        (e.g. {"force": cell.particles.f})."""
        if file_name is None:
            raise ValueError("OifCell.output_vtk_pos: parameter 'file_name' is required")
        _vtk.write_triangles(file_name, self.mesh.positions(), self._vtk_triangles(), point_data)

    def output_vtk_pos_folded(self, file_name=None, point_data=None):
        """As output_vtk_pos, the whole cell shifted by box periods so that its
        centre lies in the box (the cell is not cut at the box faces)."""
        if file_name is None:
            raise ValueError("OifCell.output_vtk_pos_folded: parameter 'file_name' is required")
        pos = self.mesh.positions()
        box = np.asarray(self.system.box_l)
        shift = np.floor(pos.mean(axis=0) / box) * box
        _vtk.write_triangles(file_name, pos - shift, self._vtk_triangles(), point_data)

    def append_point_data_to_vtk(self, file_name=None, data_name=None, data=None, first_append=None):
        """Append per-node scalars to a file written by output_vtk_pos* (PyOIF):
        first_append=True starts the POINT_DATA section (the file must not have
        one yet), False adds to the existing one."""
        owner = "OifCell.append_point_data_to_vtk"
        if file_name is None or data is None or data_name is None or first_append is None:
            raise ValueError(f"{owner}: parameters 'file_name', 'data_name', 'data' and 'first_append' "
                             f"are required")
        if not isinstance(first_append, (bool, np.bool_)) and first_append not in (0, 1):
            raise TypeError(f"{owner}: parameter 'first_append' must be True or False, got {first_append!r}")
        if not isinstance(data_name, str) or not data_name or any(c.isspace() for c in data_name):
            raise ValueError(f"{owner}: parameter 'data_name' must be a non-empty string without spaces "
                             f"(VTK names are single words), got {data_name!r}")
        try:
            data = np.asarray(data, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"{owner}: parameter 'data' must be numbers") from None
        n = self.get_n_nodes()
        if data.shape != (n,):
            raise ValueError(f"{owner}: 'data' must have {n} values, got shape {data.shape}")
        if not isinstance(file_name, (str, os.PathLike)) or isinstance(file_name, bytes):
            raise TypeError(f"{owner}: parameter 'file_name' must be a string, got {type(file_name).__name__}")
        # the file's checks and the append on the writing rank, its outcome on
        # every rank (under MPI the other ranks would race with its writes)
        def append():
            if not os.path.isfile(file_name):
                raise ValueError(f"{owner}: '{os.fspath(file_name)}' is not an existing VTK file; write it "
                                 f"first with output_vtk_pos or output_vtk_pos_folded")
            with open(file_name, "r") as f:
                text = f.read()
            # the file's own structure decides: a second POINT_DATA header, or
            # scalars without one, make a file that VTK readers reject
            header = [ln for ln in text.splitlines() if ln.startswith("POINT_DATA")]
            points = [ln for ln in text.splitlines() if ln.startswith("POINTS")]
            if not points or points[0].split()[1:2] != [str(n)]:
                raise ValueError(f"{owner}: '{os.fspath(file_name)}' is not a VTK file of this cell's "
                                 f"{n} nodes "
                                 f"(its POINTS line: {points[0] if points else 'missing'})")
            if first_append and header:
                raise ValueError(f"{owner}: '{os.fspath(file_name)}' already has a POINT_DATA section; pass "
                                 f"first_append=False to add to it")
            if not first_append and not header:
                raise ValueError(f"{owner}: '{os.fspath(file_name)}' has no POINT_DATA section yet; pass "
                                 f"first_append=True for the first data")
            if any(ln.split()[1:2] == [data_name] for ln in text.splitlines()
                   if ln.startswith(("SCALARS", "VECTORS"))):
                raise ValueError(f"{owner}: '{os.fspath(file_name)}' already has data named '{data_name}'")
            # the whole file again, through a temporary file renamed over it:
            # a crash here leaves the previous file, never a half-appended one
            text += f"POINT_DATA {n}\n" if first_append else ""
            text += f"SCALARS {data_name} double 1\nLOOKUP_TABLE default\n"
            text += "\n".join(repr(float(v)) for v in data) + "\n"

            def write_to(tmp):
                with open(tmp, "w") as f:
                    f.write(text)
            replace_atomically(file_name, owner, write_to)

        _vtk.on_writer(append)

    def output_raw_data(self, file_name=None, data=None):
        if file_name is None or data is None:
            raise ValueError("OifCell.output_raw_data: parameters 'file_name' and 'data' are required")
        try:
            data = np.asarray(data, dtype=float)
        except (TypeError, ValueError):
            raise TypeError("OifCell.output_raw_data: parameter 'data' must be numbers") from None
        if data.ndim == 0 or len(data) != self.get_n_nodes():
            raise ValueError(f"OifCell.output_raw_data: 'data' must have {self.get_n_nodes()} rows, got "
                             f"shape {data.shape}")
        _vtk.write_text(file_name, _vtk.format_rows(data), "OifCell.output_raw_data")

    def output_mesh_points(self, file_name=None):
        """Node positions relative to the cell's centre, PyOIF's nodes.dat format
        (a deformed shape to re-seed from with set_mesh_points, or to use as
        a new cell type's nodes_file with the type's triangles)."""
        if file_name is None:
            raise ValueError("OifCell.output_mesh_points: parameter 'file_name' is required")
        pos = self.mesh.positions()
        mesh_io.write_nodes(file_name, pos - pos.mean(axis=0), "OifCell.output_mesh_points")

    output_mesh_nodes = output_mesh_points

    def set_mesh_points(self, file_name=None):
        """Re-seed: put the nodes at the positions saved by output_mesh_points,
        around the cell's current centre."""
        if file_name is None:
            raise ValueError("OifCell.set_mesh_points: parameter 'file_name' is required")
        nodes, lines = mesh_io.read_nodes(file_name)
        if len(nodes) != self.get_n_nodes():
            raise ValueError(f"{file_name}: has {len(nodes)} nodes, the cell has {self.get_n_nodes()}")
        self._parts.pos = nodes + self.get_origin()

    set_mesh_nodes = set_mesh_points

    def print_info(self):
        self.mesh._live_parts()
        print("\nThe following OifCell was created: ")
        print("\t cell_id (mol_id): " + str(self.cell_id))
        print("\t particle_mass: " + custom_str(self.particle_mass))
        print("\t particle_type: " + str(self.particle_type))
        print("\t rotate: " + str(None if self.rotate is None else self.rotate.tolist()))
        print("\t origin: " + " ".join(str(x) for x in self.origin))
        print("\t particle ids: " + f"{self.mesh.part_ids[0]}..{self.mesh.part_ids[-1]}")

    # -- elastic forces ---------------------------------------------------------------

    def elastic_force_arrays(self):
        """dict term -> N x 3 forces on this cell's nodes from the engine, for
        'stretching', 'bending', 'local_area', 'global_area', 'volume' (zeros
        where the modulus is off) and 'total' (their sum)."""
        ct = self.cell_type
        self.mesh._live_parts()  # the engine's forces of reused ids would belong to other particles
        ids = self.mesh.part_ids
        n = len(ids)
        out = {}
        for term, which in OifCellType.MODULUS_TERMS:
            inter = ct.local_force_interaction if which == "local" else ct.global_force_interaction
            f = np.zeros((n, 3))
            if inter is not None:
                fid, forces = self.system.analysis.oif_forces(inter, term, self.cell_id)  # this cell's bonds
                fid = np.asarray(fid)
                forces = np.asarray(forces).reshape(-1, 3)
                index = {int(p): k for k, p in enumerate(fid)}
                sel = np.array([index.get(int(p), -1) for p in ids])
                have = sel >= 0
                f[have] = forces[sel[have]]
            out[term] = f
        out["total"] = sum(out[t] for t in OifCellType.ENERGY_TERMS)
        return out

    def _view_force_arrays(self):
        """As elastic_force_arrays, computed the way ESPResSo 4.2's
        ``OifCell.elastic_forces`` does, from the mesh's current lists: every
        edge (stretching: neo-Hookean ks and linear kslin) and angle
        (bending) of the cell, and only the triangles in ``mesh.triangles``
        (local area; global area and volume with the surface and volume of
        those triangles against the cell type's whole reference surface and
        volume). Used when a script has replaced ``mesh.triangles``; the
        formulas are those of oif_utils (PyOIF's helpers, e.g. the global area
        force without the 1/A0_g of the engine)."""
        ct = self.cell_type
        mesh = self.mesh
        pos = mesh.positions()
        ref = ct.mesh.positions()
        n = len(pos)
        out = {}
        # stretching, over the edges
        e = mesh.edge_ids
        d = pos[e[:, 1]] - pos[e[:, 0]]
        dist = np.linalg.norm(d, axis=1)
        dist0 = np.linalg.norm(ref[e[:, 1]] - ref[e[:, 0]], axis=1)
        lam = dist / dist0
        fac = (ct.ks * (lam ** 0.5 + lam ** -2.5) / (lam + lam ** -3.0) + ct.kslin) * (dist - dist0) / dist
        f = fac[:, None] * d
        acc = np.zeros((n, 3))
        np.add.at(acc, e[:, 0], f)
        np.add.at(acc, e[:, 1], -f)
        out["stretching"] = acc
        # bending, over the angles (A, B, C, D), shared edge BC
        a = mesh.angle_ids
        acc = np.zeros((n, 3))
        if len(a):
            phi = geo.dihedral_angles(pos, a)
            phi0 = geo.dihedral_angles(ref, a)
            pa, pb, pc, pd = (pos[a[:, k]] for k in range(4))
            n1 = np.cross(pa - pb, pc - pb)
            n2 = np.cross(pc - pb, pd - pb)
            fac = ct.kb * (phi - phi0) / phi0
            f1 = fac[:, None] * n1 / np.linalg.norm(n1, axis=1)[:, None]
            f2 = fac[:, None] * n2 / np.linalg.norm(n2, axis=1)[:, None]
            np.add.at(acc, a[:, 0], f1)
            np.add.at(acc, a[:, 1], -0.5 * (f1 + f2))
            np.add.at(acc, a[:, 2], -0.5 * (f1 + f2))
            np.add.at(acc, a[:, 3], f2)
        out["bending"] = acc
        # local area, global area and volume, over the listed triangles
        t = mesh._analysis_triangles()
        tri = pos[t]
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = 0.5 * np.linalg.norm(normals, axis=1)
        area0 = 0.5 * np.linalg.norm(np.cross(ref[t[:, 1]] - ref[t[:, 0]], ref[t[:, 2]] - ref[t[:, 0]]), axis=1)
        to_centroid = tri.mean(axis=1)[:, None, :] - tri
        spread = np.sum(to_centroid ** 2, axis=(1, 2))

        def per_corner(fac):
            acc = np.zeros((n, 3))
            for k in range(3):
                np.add.at(acc, t[:, k], fac[:, None] * to_centroid[:, k])
            return acc
        out["local_area"] = per_corner(ct.kal * (area - area0) / spread)
        out["global_area"] = per_corner(ct.kag * area * (mesh.surface() - ct.mesh.surface()) / spread)
        v0 = ct.mesh.volume()
        fv = (ct.kv * (mesh.volume() - v0) / v0 * area / 3.0)[:, None] * normals / (2.0 * area[:, None])
        acc = np.zeros((n, 3))
        for k in range(3):
            np.add.at(acc, t[:, k], fv)
        out["volume"] = acc
        out["total"] = sum(out[term] for term in OifCellType.ENERGY_TERMS)
        return out

    def get_energies(self):
        """dict term -> this cell's elastic energy at the current positions
        (simulation units) for 'stretching' (eq. 3's neo-Hookean and linear
        parts), 'bending' (eq. 4), 'local_area' (eq. 5), 'global_area' (eq.
        6) and 'volume' (eq. 7), 0.0 where the modulus is off, and 'total'
        (their sum). The membrane viscosity dissipates and has no energy.
        Summed over all cells, the total is the bonded energy of
        ``system.analysis.energy()`` when the cells have no other bonds.
        For all cells of a type at once: ``cell_type.get_energies()``."""
        self.mesh._live_parts()  # a stale cell's mol_id could belong to another cell now
        zero = dict.fromkeys(OifCellType.ENERGY_TERMS, 0.0)
        zero["total"] = 0.0
        return self.cell_type.get_energies(self.cell_id).get(self.cell_id, zero)

    def elastic_forces(self, el_forces=(0, 0, 0, 0, 0, 0), f_metric=(0, 0, 0, 0, 0, 0), vtk_file=None,
                       raw_data_file=None):
        """PyOIF's elastic-force analysis. Flags in the order (ks, kb, kal,
        kag, kv, total): el_forces selects per-node force magnitudes to write
        into vtk_file (as point data) or one force to write as raw x y z rows
        into raw_data_file; f_metric selects sums over nodes of ``|F|``, returned
        as a list of 6 (0 if none selected). The forces are the engine's; if
        the script replaced ``mesh.triangles``, they are those of the current
        lists as ESPResSo 4.2 computes them (see _view_force_arrays)."""
        for name, flags in (("el_forces", el_forces), ("f_metric", f_metric)):
            if isinstance(flags, (str, bytes)) or not isinstance(flags, (list, tuple, np.ndarray)):
                raise TypeError(f"OifCell.elastic_forces: '{name}' must be a list of 6 flags (0 or 1) in "
                                f"the order (ks, kb, kal, kag, kv, total), got {flags!r}")
            if len(flags) != 6 or any(np.ndim(f) != 0 or f not in (0, 1) for f in flags):
                raise ValueError(f"OifCell.elastic_forces: '{name}' must be 6 flags of 0 or 1 in the "
                                 f"order (ks, kb, kal, kag, kv, total), got {flags!r}")
        names = ("stretching", "bending", "local_area", "global_area", "volume", "total")
        if vtk_file is not None and sum(el_forces) == 0:
            raise ValueError("OifCell.elastic_forces: vtk_file needs at least one flag set in el_forces")
        if raw_data_file is not None and sum(el_forces) != 1:
            raise ValueError("OifCell.elastic_forces: raw_data_file takes exactly one force: set one flag "
                             "in el_forces")
        if sum(el_forces) == 0 and sum(f_metric) == 0:
            return 0
        # a script that replaced mesh.triangles analyses those triangles (ESPResSo's way)
        if getattr(self.mesh, "_triangle_override", None) is not None:
            forces = self._view_force_arrays()
        else:
            forces = self.elastic_force_arrays()
        if vtk_file is not None:
            labels = ("ks_f_metric", "kb_f_metric", "kal_f_metric", "kag_f_metric", "kav_f_metric",
                      "total_f_metric")
            data = {labels[i]: np.linalg.norm(forces[names[i]], axis=1) for i in range(6) if el_forces[i]}
            self.output_vtk_pos_folded(vtk_file, point_data=data)
        if raw_data_file is not None:
            i = list(el_forces).index(1)
            self.output_raw_data(raw_data_file, forces[names[i]])
        if sum(f_metric) > 0:
            return [float(np.linalg.norm(forces[names[i]], axis=1).sum()) if f_metric[i] else 0.0
                    for i in range(6)]
        return 0
