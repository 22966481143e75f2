"""Cells in and out of a device through its inlets and outlets
(``oif.CellFlow``), between the runs of a script's loop::

    flow = oif.CellFlow(system, [rbc], inlet=([1, 2, 1], [12, 38, 19]), outlet=L - 3,
                        haematocrit=0.1, boundaries=walls, seed=7, particle_mass=m)
    # a T-junction: one inlet box, an outlet on x+ and one on y+
    flow = oif.CellFlow(system, [rbc], inlet=([1, 2, 1], [12, 18, 19]),
                        outlets=[("x+", L - 3), ("y+", W - 3)], haematocrit=0.1, ...)
    for i in range(n_outputs):
        system.integrator.run(steps)
        added, removed = flow.update()

- **Out.** A cell is removed (its particles, bonds and exclusions go; the
  Python object stays, with its last data) once one of its nodes reaches an
  outlet: `outlet` is a plane at that coordinate along `axis`, passed going
  up; `outlets` a list of planes `(face, coordinate)` (face "x+", "y-", …:
  a node at or beyond the coordinate in the face's direction) and of regions
  `(lo, hi)` (a node inside the box). Put a plane a couple of lattice
  spacings before the box's end, so that no node ever wraps round the
  periodic box. `flow.removed` logs (cell id, time), `flow.exits`
  (cell id, time, outlet index), `flow.exit_counts()` the cells per outlet.
- **In.** After the removals, new cells are placed in the `inlet` box (or
  one of a list of boxes; random position and orientation, never
  overlapping other cells or the `boundaries`: oif.seed_cells; their nodes
  start with the fluid's velocity there; keep a box two lattice spacings
  from an open face, whose node plane the inlet rewrites) while that
  inlet's haematocrit (cell volume whose centre is in the box over its
  fluid volume) is below `haematocrit`; or, with `rate` (cells per unit
  time, over all inlets; each cell to an inlet drawn by their fluid
  volumes), as many as are due since the last update; or, with
  `recycle=True`, as many as left (a closed loop with a constant number of
  cells). A cell that cannot be placed now (the inlet is crowded) is tried
  again at the next update.
- Deterministic: the placements come from one random generator seeded with
  `seed`; the same script gives the same cells.
"""
import numpy as np

from .oif_classes import OifCellType
from .seeding import SeedingError, seed_cells

_FACES = {"x-": (0, -1), "x+": (0, 1), "y-": (1, -1), "y+": (1, 1), "z-": (2, -1), "z+": (2, 1)}


def _box(owner, name, value):
    """(lo, hi) of a box given as two 3-vectors with hi > lo."""
    try:
        lo, hi = (np.asarray(v, dtype=float).reshape(3) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: parameter '{name}' must be a box (lo, hi) of two 3-vectors, got {value!r}") \
            from None
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
        raise ValueError(f"{owner}: parameter '{name}' must have hi > lo on every axis, got {value!r}")
    return lo, hi


def _is_box(value):
    try:
        return len(value) == 2 and all(np.asarray(v, dtype=float).shape == (3,) for v in value)
    except (TypeError, ValueError):
        return False


class Outlet:
    """Where cells leave: a plane (face, coordinate) or a region (lo, hi)."""

    def __init__(self, owner, spec, box_l, inlets):
        if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[0], str):
            face, at = spec
            if face not in _FACES:
                raise ValueError(f"{owner}: an outlet plane's face must be one of {', '.join(_FACES)}, "
                                 f"got {face!r}")
            axis, sign = _FACES[face]
            at = float(at)
            if not (np.isfinite(at) and 0.0 <= at <= box_l[axis]):
                raise ValueError(f"{owner}: outlet {face} at {at!r} must lie inside the box (0..{box_l[axis]:g} "
                                 f"along {face[0]})")
            for lo, hi in inlets:
                if (sign > 0 and hi[axis] >= at) or (sign < 0 and lo[axis] <= at):
                    raise ValueError(f"{owner}: outlet {face} at {at:g} must lie beyond every inlet box "
                                     f"(one reaches {hi[axis] if sign > 0 else lo[axis]:g} along {face[0]})")
            self.kind, self.axis, self.sign, self.at = "plane", axis, sign, at
            self.name = f"{face} at {at:g}"
        elif _is_box(spec):
            lo, hi = _box(owner, "outlets", spec)
            for ilo, ihi in inlets:
                if np.all(lo < ihi) and np.all(ilo < hi):
                    raise ValueError(f"{owner}: outlet region {[lo.tolist(), hi.tolist()]} overlaps the inlet box "
                                     f"{[ilo.tolist(), ihi.tolist()]}")
            self.kind, self.lo, self.hi = "region", lo, hi
            self.name = f"region {lo.tolist()}..{hi.tolist()}"
        else:
            raise ValueError(f"{owner}: each outlet must be a plane (face, coordinate), e.g. ('x+', 57.0), or a "
                             f"region (lo, hi) of two 3-vectors, got {spec!r}")

    def reached(self, nodes):
        """Whether any of the nodes (unfolded positions) is at the outlet."""
        if self.kind == "plane":
            x = nodes[:, self.axis]
            return bool(x.max() >= self.at) if self.sign > 0 else bool(x.min() <= self.at)
        return bool(np.any(np.all((nodes >= self.lo) & (nodes <= self.hi), axis=1)))

    def __repr__(self):
        return self.name


class CellFlow:
    def __init__(self, system, cell_types, inlet, outlet=None, axis=0, haematocrit=None, rate=None, recycle=False,
                 fractions=None, boundaries=(), particle_types=None, particle_mass=1.0, seed=None, cells=None,
                 tries=3, outlets=None):
        import lbmd
        if not isinstance(system, lbmd.System):
            raise TypeError(f"CellFlow: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
        types = [cell_types] if isinstance(cell_types, OifCellType) else list(cell_types)
        if not types or not all(isinstance(t, OifCellType) for t in types):
            raise TypeError("CellFlow: parameter 'cell_types' must be an OifCellType or a list of them")
        inlets = [inlet] if _is_box(inlet) else list(inlet) if isinstance(inlet, (list, tuple)) else [inlet]
        if not inlets:
            raise ValueError("CellFlow: parameter 'inlet' must be a box (lo, hi) or a list of boxes, got none")
        inlets = [_box("CellFlow", "inlet", b) for b in inlets]
        if axis not in (0, 1, 2):
            raise ValueError(f"CellFlow: parameter 'axis' must be 0, 1 or 2, got {axis!r}")
        if (outlet is None) == (outlets is None):
            raise ValueError("CellFlow: give exactly one of 'outlet' (a plane along 'axis') and 'outlets' "
                             "(a list of planes and regions)")
        box_l = np.asarray(system.box_l, dtype=float)
        if outlet is not None:
            outlet = float(outlet)
            top = max(hi[axis] for _, hi in inlets)
            if not (np.isfinite(outlet) and top < outlet <= box_l[axis]):
                raise ValueError(f"CellFlow: parameter 'outlet' must lie beyond the inlet box ({top:g}) and "
                                 f"inside the box ({box_l[axis]:g}) along axis {axis}, got {outlet!r}")
            outlets = [("xyz"[axis] + "+", outlet)]
        if isinstance(outlets, tuple) and len(outlets) == 2 and isinstance(outlets[0], str):
            outlets = [outlets]
        self.outlets = [Outlet("CellFlow", spec, box_l, inlets) for spec in outlets]
        if not self.outlets:
            raise ValueError("CellFlow: parameter 'outlets' must name at least one outlet")
        modes = [m for m, v in (("haematocrit", haematocrit), ("rate", rate), ("recycle", recycle or None))
                 if v is not None]
        if len(modes) != 1:
            raise ValueError("CellFlow: give exactly one of haematocrit, rate, recycle=True (got "
                             f"{', '.join(modes) or 'none'})")
        for name, value, upper in (("haematocrit", haematocrit, 0.6), ("rate", rate, np.inf)):
            if value is not None and not (np.isfinite(value) and 0 < value <= upper):
                raise ValueError(f"CellFlow: parameter '{name}' must be in (0, {upper:g}], got {value!r}")
        self.system, self.types, self.axis = system, types, axis
        self.inlets = inlets
        self.inlet = inlets[0]  # (the first; ESPResSo-era scripts read it)
        self.outlet = self.outlets[0].at if self.outlets[0].kind == "plane" else None
        self.haematocrit, self.rate, self.recycle = haematocrit, rate, bool(recycle)
        self.fractions = fractions
        self.boundaries = list(boundaries) if not hasattr(boundaries, "calc_dist") else [boundaries]
        self.particle_types = particle_types if particle_types is not None else [0] * len(types)
        self.particle_mass = particle_mass
        self.rng = np.random.default_rng(seed)
        self.tries = int(tries)
        self.cells = list(cells or [])
        self.removed = []   # (cell_id, time)
        self.exits = []     # (cell_id, time, outlet index)
        self.added = []     # (cell_id, time)
        self._due = 0.0     # rate: the fraction of a cell owed to the inlets
        self._queue = []    # cells owed to the inlets (a type index, or None: drawn)
        self._last_time = system.time
        self._inlet_fluid = [self._fluid_volume(b) for b in inlets]

    def __repr__(self):
        mode = (f"haematocrit={self.haematocrit}" if self.haematocrit is not None else
                f"rate={self.rate}" if self.rate is not None else "recycle=True")
        return (f"CellFlow({mode}, inlets={[[v.tolist() for v in b] for b in self.inlets]}, "
                f"outlets={self.outlets}, {len(self.cells)} cells, added {len(self.added)}, "
                f"removed {len(self.removed)})")

    def exit_counts(self):
        """How many cells left by each outlet (in the order of `outlets`)."""
        counts = [0] * len(self.outlets)
        for _, _, k in self.exits:
            counts[k] += 1
        return counts

    def _fluid_volume(self, box):
        """Fluid volume of an inlet box: the box less the boundaries, on
        a grid of half-spacing points."""
        lo, hi = box
        n = np.maximum(2, np.ceil((hi - lo) / 0.5).astype(int))
        axes = [lo[d] + (np.arange(n[d]) + 0.5) * (hi[d] - lo[d]) / n[d] for d in range(3)]
        pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        inside = np.zeros(len(pts), dtype=bool)
        for shape in self.boundaries:
            inside |= np.array([shape.is_inside(p) for p in pts])
        return float(np.prod(hi - lo) * (1.0 - inside.mean()))

    def inlet_haematocrit(self, inlet=0):
        """Cell volume whose centre lies in inlet box `inlet` (an index into
        `inlets`), over its fluid volume."""
        lo, hi = self.inlets[inlet]
        volume = 0.0
        for c in self.cells:
            centre = np.mod(c.get_origin(), self.system.box_l)
            if np.all(centre >= lo) and np.all(centre <= hi):
                volume += c.volume()
        fluid = self._inlet_fluid[inlet]
        return volume / fluid if fluid > 0 else 0.0

    def _remove_leaving(self):
        leaving = []
        for c in self.cells:
            nodes = c.mesh.positions()
            for k, out in enumerate(self.outlets):
                if out.reached(nodes):
                    leaving.append((c, k))
                    break
        for c, k in leaving:
            c.remove()
            self.cells.remove(c)
            self.removed.append((c.cell_id, self.system.time))
            self.exits.append((c.cell_id, self.system.time, k))
        return [c for c, _ in leaving]

    def _with_the_flow(self, cell):
        """A new cell's nodes start with the fluid's velocity where they are
        (a cell at rest dropped into a fast flow is jerked by the coupling)."""
        fluid = self.system.lb_fluid
        if fluid is None:
            return
        parts = cell.mesh._live_parts()
        parts.v = np.array([fluid.get_interpolated_velocity(p) for p in parts.pos])

    def _place_one(self, type_index=None, inlet=None):
        if inlet is None:  # drawn by the inlets' fluid volumes
            weights = np.asarray(self._inlet_fluid, dtype=float)
            inlet = int(self.rng.choice(len(self.inlets), p=weights / weights.sum())) if len(self.inlets) > 1 else 0
        if type_index is None:
            weights = np.asarray(self.fractions if self.fractions is not None else [1.0] * len(self.types),
                                 dtype=float)
            type_index = int(self.rng.choice(len(self.types), p=weights / weights.sum()))
        counts = [0] * len(self.types)
        counts[type_index] = 1
        for _ in range(self.tries):
            try:
                new = seed_cells(self.system, self.types, counts=counts, boundaries=self.boundaries,
                                 region=self.inlets[inlet], particle_types=self.particle_types,
                                 particle_mass=self.particle_mass, seed=int(self.rng.integers(2**31)),
                                 max_attempts=200)
            except SeedingError:
                continue
            for c in new:
                self._with_the_flow(c)
            self.cells.extend(new)
            self.added.extend((c.cell_id, self.system.time) for c in new)
            return new
        return []

    def update(self):
        """Remove the cells at the outlets, add cells at the inlets; returns
        (added, removed) lists of OifCell. Call it between runs (collective
        under mpirun: every rank calls it alike)."""
        removed = self._remove_leaving()
        added = []
        if self.recycle:  # the same types again, in the order they left
            self._queue.extend(self.types.index(c.cell_type) for c in removed)
        elif self.rate is not None:
            self._due += self.rate * (self.system.time - self._last_time)
            while self._due >= 1.0:
                self._queue.append(None)  # a type drawn by `fractions`
                self._due -= 1.0
        self._last_time = self.system.time
        if self.haematocrit is not None:
            for k in range(len(self.inlets)):
                for _ in range(100):  # at most this many at once
                    if self.inlet_haematocrit(k) >= self.haematocrit:
                        break
                    new = self._place_one(inlet=k)
                    if not new:
                        break
                    added += new
        while self._queue:
            new = self._place_one(self._queue[0])
            if not new:
                break  # crowded: owed to the next update
            self._queue.pop(0)
            added += new
        return added, removed
