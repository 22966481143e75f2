"""Compound cells: a nucleus inside a cell, inner particles filling a cell,
and clusters of cells held together by adhesion (doc/compound-cells.md).

- ``oif.add_nucleus(cell, nucleus_type, particle_type)``: a smaller OIF cell
  at the cell's centre, kept inside by the advised hard_contact between the
  two membranes (a repulsion that diverges as the gap closes, which no
  finite squeeze crosses; it acts from inside as from outside, since it
  needs no normals).
- ``OifCell(..., inner_particles=N)``: N particles spread through the cell's
  inside, caged by the same contact with the membrane's nodes (their own
  molecule id, so the contact acts), coupled to the fluid like every
  particle: they move with the cell and its interior.
- ``oif.CellCluster(cell_type, n_cells, centroid, ...)`` (``oif.BiCluster``
  for two, the PyOIF forks' name): cells built around a centroid, each with
  its own particle type, held by a Morse adhesion between different cells
  and kept apart by the hard_contact; ``deform(force)`` pulls the cluster
  apart, ``save_cluster``/``load_cluster`` store and restore it.

The PyOIF group's forks add these to ESPResSo's object_in_fluid (nucleated
cells, inner particles, cell clusters); this is the same idea written for
this engine, with the contacts it advises.
"""
import json
import math

import numpy as np

from . import contacts as _contacts

#: Morse adhesion between the cells of a cluster, by default (the engine's
#: units: 1e-15 J, 1/um, um): its largest pull per node pair,
#: eps alpha / 2 = 0.2 pN, a fiftieth of the contact's force scale, its
#: minimum ADHESION_REACH beyond the contact's range and its reach
#: ADHESION_RANGE beyond that. A node feels every node of the other cell in
#: reach: five times stronger (eps 0.001, reach 2) pulled the nodes of two
#: spheres of radius 3 (ks 0.05) into spikes that crossed within 1.2 us;
#: with these the pair flattens into a contact zone and rests
ADHESION_EPS, ADHESION_ALPHA, ADHESION_REACH, ADHESION_RANGE = 0.0002, 2.0, 0.25, 1.0


def _cell_nodes_and_triangles(cell):
    return np.asarray(cell.mesh.positions(), dtype=float), np.asarray(cell.cell_type.mesh._topo.triangles)


def _inside(points, nodes, triangles):
    from .oif_classes import _winding
    return _winding(np.asarray(points, dtype=float), nodes, triangles) > 0.5


def _nearest_distance(points, nodes):
    """Per point, the distance to the nearest node (unfolded positions)."""
    from scipy.spatial import cKDTree
    return cKDTree(np.asarray(nodes, dtype=float)).query(np.asarray(points, dtype=float))[0]


def _contact(cell_types, scale):
    settings = _contacts.contact_settings(cell_types)["cell"]
    settings["a"] *= float(scale)
    return settings


# -- nucleus ----------------------------------------------------------------------
def add_nucleus(cell, nucleus_type, particle_type, particle_mass=None, rotate=None, scale=1.0):
    """A nucleus: an OifCell of `nucleus_type` (a smaller mesh, stiffer
    moduli) at `cell`'s centre, particle type `particle_type`, and the
    advised hard_contact (times `scale`, as oif.set_contacts) between the
    cell's and the nucleus's particle types, which keeps it inside. Refused
    (ValueError) when the nucleus does not lie inside the cell with the
    contact's range (offset + cutoff) free all round. Returns the nucleus;
    ``cell.nucleus`` and ``nucleus.host`` name each other."""
    from .oif_classes import OifCell, OifCellType
    owner = "add_nucleus"
    if not isinstance(cell, OifCell):
        raise TypeError(f"{owner}: parameter 'cell' must be an oif.OifCell, got {type(cell).__name__}")
    if not isinstance(nucleus_type, OifCellType):
        raise TypeError(f"{owner}: parameter 'nucleus_type' must be an oif.OifCellType, got "
                        f"{type(nucleus_type).__name__}")
    if nucleus_type.system is not cell.system:
        raise ValueError(f"{owner}: the nucleus type belongs to another System than the cell")
    if getattr(cell, "nucleus", None) is not None:
        raise ValueError(f"{owner}: cell {cell.cell_id} already has a nucleus (cell {cell.nucleus.cell_id})")
    scale = _contacts.check_scale(owner, scale)
    nodes, triangles = _cell_nodes_and_triangles(cell)
    centre = nodes.mean(axis=0)
    placed = nucleus_type.mesh._placed_positions(centre, None if rotate is None else np.asarray(rotate, float))
    contact = _contact([cell.cell_type, nucleus_type], scale)
    reach = contact["offset"] + contact["cutoff"]
    outside = int(np.count_nonzero(~_inside(placed, nodes, triangles)))
    gap = float(_nearest_distance(placed, nodes).min())
    if outside or gap <= reach:
        raise ValueError(f"{owner}: the nucleus does not fit in cell {cell.cell_id}: "
                         + (f"{outside} of its {len(placed)} nodes lie outside the cell" if outside else
                            f"its nodes come within {gap:.3g} of the cell's, and the contact that keeps it "
                            f"inside needs more than {reach:.3g} (offset {contact['offset']:g} + cutoff "
                            f"{contact['cutoff']:g})")
                         + "; use a smaller nucleus (resize) or a larger cell")
    mass = cell.particle_mass if particle_mass is None else particle_mass
    nucleus = OifCell(cell_type=nucleus_type, particle_type=particle_type, origin=centre, particle_mass=mass,
                      rotate=rotate, check_overlaps=False)
    cell.system.non_bonded_inter[cell.particle_type, int(particle_type)].hard_contact.set_params(**contact)
    cell.nucleus, nucleus.host = nucleus, cell
    return nucleus


# -- inner particles ------------------------------------------------------------
def inner_points(nodes, triangles, count, clearance):
    """`count` points spread evenly through a closed mesh's inside, each more
    than `clearance` from every node: candidates on a cubic grid fine enough
    to give at least four per point, then farthest-point sampling from the
    one nearest the centre (deterministic)."""
    nodes = np.asarray(nodes, dtype=float)
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    from . import geometry as geo
    volume = geo.volume(nodes, triangles)
    spacing = (abs(volume) / (8.0 * count)) ** (1.0 / 3.0)
    grid = np.zeros((0, 3))
    for _ in range(12):
        if np.prod((hi - lo) / spacing) > 2e5:  # finer would not find room that is not there
            break
        axes = [np.arange(a + 0.5 * spacing, b, spacing) for a, b in zip(lo, hi)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        if len(grid):
            grid = grid[_nearest_distance(grid, nodes) > clearance]
        if len(grid):
            grid = grid[_inside(grid, nodes, triangles)]
        if len(grid) >= 4 * count:
            break
        spacing *= 0.7
    if len(grid) < count:
        return None  # (also when the loop stopped before the first grid: grid is then empty)
    centre = nodes.mean(axis=0)
    chosen = [int(np.argmin(np.linalg.norm(grid - centre, axis=1)))]
    distance = np.linalg.norm(grid - grid[chosen[0]], axis=1)
    while len(chosen) < count:
        k = int(np.argmax(distance))
        chosen.append(k)
        distance = np.minimum(distance, np.linalg.norm(grid - grid[k], axis=1))
    return grid[chosen]


def add_inner_particles(cell, count, particle_type=None, scale=1.0):
    """`count` inner particles for `cell` (OifCell(inner_particles=...) calls
    this): spread through its inside beyond the contact's range from the
    membrane, of the cell's node mass, particle type `particle_type`
    (default the cell's), with a molecule id of their own (the next cell id)
    so that the hard_contact between them and the membrane acts; that
    contact is set (the advised one, times `scale`) where the pair of types
    has none yet. Returns their ids."""
    owner = "OifCell"
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
        raise ValueError(f"{owner}: parameter 'inner_particles' must be a whole number >= 0, got {count!r}")
    if count == 0:
        return []
    system = cell.system
    ptype = cell.particle_type if particle_type is None else int(particle_type)
    contact = _contact(cell.cell_type, scale)
    nodes, triangles = _cell_nodes_and_triangles(cell)
    points = inner_points(nodes, triangles, int(count), contact["offset"] + contact["cutoff"])
    if points is None:
        raise ValueError(f"{owner}: {count} inner particles do not fit in the cell beyond the contact's range "
                         f"({contact['offset'] + contact['cutoff']:.3g} from the membrane); ask fewer")
    mol = int(system.max_oif_objects)
    inner = system.part.add(pos=points, type=ptype, mass=float(cell.particle_mass), mol_id=mol)
    system.max_oif_objects = mol + 1
    pair = system.non_bonded_inter[cell.particle_type, ptype].hard_contact
    if not pair.get_params().get("cutoff", 0.0) > 0.0:
        pair.set_params(**contact)
    return [int(i) for i in inner.id]


# -- clusters --------------------------------------------------------------------
class CellCluster:
    """n cells of one type around a centroid, held together by adhesion.

    ``CellCluster(cell_type, n_cells, centroid, particle_types=None,
    gap=None, adhesion=None, particle_mass=1.0, rotate=None, scale=1.0)``

    Two cells sit side by side along x, more on a ring in the xy plane,
    their meshes `gap` apart (default: the adhesion's minimum). Each cell
    has its own particle type (`particle_types`, default 0, 1, ...): the
    Morse adhesion (``adhesion``: a dict of lbmd's morse parameters eps,
    alpha, rmin, cutoff; default ADHESION_*, rmin beyond the contact) acts
    between nodes of different cells only, and the advised hard_contact
    (times `scale`) between every pair of the types keeps the membranes
    apart. ``cells``: the OifCells; ``deform(force)``: pull the two ends
    apart; ``release()``; ``separation()``; ``save_cluster(path)`` /
    ``load_cluster(path)``."""

    def __init__(self, cell_type, n_cells, centroid, particle_types=None, gap=None, adhesion=None,
                 particle_mass=1.0, rotate=None, scale=1.0):
        from .oif_classes import OifCell, OifCellType, _vec3
        owner = type(self).__name__
        if not isinstance(cell_type, OifCellType):
            raise TypeError(f"{owner}: parameter 'cell_type' must be an oif.OifCellType, got "
                            f"{type(cell_type).__name__}")
        if isinstance(n_cells, bool) or not isinstance(n_cells, (int, np.integer)) or n_cells < 1:
            raise ValueError(f"{owner}: parameter 'n_cells' must be a whole number >= 1, got {n_cells!r}")
        centroid = _vec3(owner, "centroid", centroid)
        scale = _contacts.check_scale(owner, scale)
        types = list(range(n_cells)) if particle_types is None else [int(t) for t in particle_types]
        if len(types) != n_cells or len(set(types)) != n_cells:
            raise ValueError(f"{owner}: parameter 'particle_types' must give {n_cells} different types (one per "
                             f"cell: the adhesion acts between different types only), got {particle_types!r}")
        contact = _contact(cell_type, scale)
        reach = contact["offset"] + contact["cutoff"]
        morse = dict(eps=ADHESION_EPS, alpha=ADHESION_ALPHA, rmin=reach + ADHESION_REACH,
                     cutoff=reach + ADHESION_REACH + ADHESION_RANGE)
        if adhesion is not None:
            unknown = set(adhesion) - set(morse)
            if unknown:
                raise ValueError(f"{owner}: parameter 'adhesion' has unknown keys {sorted(unknown)}; expected "
                                 f"eps, alpha, rmin, cutoff (lbmd's morse)")
            morse.update({k: float(v) for k, v in adhesion.items()})
        gap = morse["rmin"] if gap is None else float(gap)
        if not gap > reach:
            raise ValueError(f"{owner}: parameter 'gap' ({gap:g}) must exceed the contact's range {reach:g}: the "
                             f"membranes would start inside each other's contact")
        system = cell_type.system
        placed = cell_type.mesh._placed_positions(np.zeros(3), None if rotate is None else _vec3(owner, "rotate",
                                                                                                  rotate))
        half_width = 0.5 * float(np.ptp(placed[:, 0]))
        if n_cells == 1:
            offsets = [np.zeros(3)]
        elif n_cells == 2:
            offsets = [np.array([-(half_width + 0.5 * gap), 0, 0]), np.array([half_width + 0.5 * gap, 0, 0])]
        else:
            ring = (2.0 * half_width + gap) / (2.0 * math.sin(math.pi / n_cells))
            offsets = [ring * np.array([math.cos(2 * math.pi * k / n_cells), math.sin(2 * math.pi * k / n_cells), 0])
                       for k in range(n_cells)]
        self.system, self.cell_type, self.particle_types = system, cell_type, types
        self.adhesion, self.contact, self.gap = morse, contact, gap
        self.cells = []
        try:
            for t, off in zip(types, offsets):
                self.cells.append(OifCell(cell_type=cell_type, particle_type=t, origin=centroid + off,
                                          particle_mass=particle_mass, rotate=rotate))
        except BaseException:
            for c in self.cells:
                c._discard()
            raise
        for i, ti in enumerate(types):
            for tj in types[i:]:
                system.non_bonded_inter[ti, tj].hard_contact.set_params(**contact)
                if ti != tj:
                    system.non_bonded_inter[ti, tj].morse.set_params(**morse)
        self._pulled = []

    def centres(self):
        return np.array([c.get_origin() for c in self.cells])

    def separation(self):
        """The largest distance between two of the cells' centres."""
        c = self.centres()
        return float(max((np.linalg.norm(a - b) for i, a in enumerate(c) for b in c[i + 1:]), default=0.0))

    def deform(self, force, fraction=0.1):
        """Pull the cluster apart: a total force `force` (the engine's units,
        nN) on the `fraction` of nodes of the two outermost cells farthest
        out along the line between them, in opposite directions (as optical
        tweezers or a micropipette would). Replaces an earlier deform."""
        if not (isinstance(force, (int, float, np.floating)) and not isinstance(force, bool)
                and math.isfinite(force) and force >= 0):
            raise ValueError(f"{type(self).__name__}.deform: parameter 'force' must be a number >= 0, got {force!r}")
        if not (isinstance(fraction, (int, float)) and 0 < fraction <= 0.5):
            raise ValueError(f"{type(self).__name__}.deform: parameter 'fraction' must be in (0, 0.5], got "
                             f"{fraction!r}")
        if len(self.cells) < 2:
            raise ValueError(f"{type(self).__name__}.deform: a cluster of one cell has nothing to pull apart")
        self.release()
        centres = self.centres()
        i, j = max(((a, b) for a in range(len(centres)) for b in range(a + 1, len(centres))),
                   key=lambda ab: np.linalg.norm(centres[ab[0]] - centres[ab[1]]))
        axis = (centres[j] - centres[i]) / np.linalg.norm(centres[j] - centres[i])
        for cell, sign in ((self.cells[i], -1.0), (self.cells[j], 1.0)):
            pos = cell.mesh.positions()
            reach = (pos - pos.mean(axis=0)) @ axis * sign
            picked = np.argsort(-reach)[:max(1, int(round(fraction * len(pos))))]
            parts = cell.particles
            ext = np.zeros((len(pos), 3))
            ext[picked] = sign * axis * float(force) / len(picked)
            parts.ext_force = ext
            self._pulled.append(cell)

    def release(self):
        """Take away the force of deform."""
        for cell in self._pulled:
            if cell.is_live():
                cell.particles.ext_force = np.zeros((cell.get_n_nodes(), 3))
        self._pulled = []

    def save_cluster(self, path):
        """The cluster's node positions (unfolded) and its settings, as JSON."""
        from lbmd.file_output import write_text
        data = dict(cell_type_nodes=self.cell_type.mesh.get_n_nodes(), particle_types=self.particle_types,
                    adhesion=self.adhesion, contact=self.contact, gap=self.gap,
                    positions=[c.mesh.positions().tolist() for c in self.cells])
        write_text(path, json.dumps(data) + "\n", f"{type(self).__name__}.save_cluster")

    def load_cluster(self, path):
        """Put the cells' nodes where save_cluster wrote them (a cluster of
        the same cell type and number of cells)."""
        owner = f"{type(self).__name__}.load_cluster"
        try:
            with open(path) as f:
                data = json.load(f)
        except OSError as e:
            raise ValueError(f"{owner}: cannot read {path}: {e.strerror}") from None
        except ValueError as e:
            raise ValueError(f"{owner}: {path} is not a saved cluster (JSON): {e}") from None
        positions = data.get("positions") if isinstance(data, dict) else None
        if not isinstance(positions, list) or len(positions) != len(self.cells):
            raise ValueError(f"{owner}: {path} holds {len(positions) if isinstance(positions, list) else 'no'} "
                             f"cells, this cluster {len(self.cells)}")
        arrays = [np.asarray(p, dtype=float) for p in positions]
        for k, (cell, a) in enumerate(zip(self.cells, arrays)):
            if a.shape != (cell.get_n_nodes(), 3) or not np.all(np.isfinite(a)):
                raise ValueError(f"{owner}: {path}: cell {k} has positions of shape {a.shape}, expected "
                                 f"({cell.get_n_nodes()}, 3) finite numbers")
        for cell, a in zip(self.cells, arrays):
            cell.particles.pos = a


class BiCluster(CellCluster):
    """Two cells held by adhesion (the PyOIF forks' name):
    ``BiCluster(cell_type, centroid, **kwargs)`` is
    ``CellCluster(cell_type, 2, centroid, **kwargs)``."""

    def __init__(self, cell_type, centroid, **kwargs):
        super().__init__(cell_type, 2, centroid, **kwargs)
