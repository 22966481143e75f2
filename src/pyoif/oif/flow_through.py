"""Cells in and out of a device with an inlet and an outlet
(``oif.CellFlow``), between the runs of a script's loop.

    flow = oif.CellFlow(system, [rbc], inlet=([1, 2, 1], [12, 38, 19]), outlet=L - 3,
                        haematocrit=0.1, boundaries=walls, seed=7, particle_mass=m)
    for i in range(n_outputs):
        system.integrator.run(steps)
        added, removed = flow.update()

- **Out.** A cell is removed (its particles, bonds and exclusions go; the
  Python object stays, with its last data) once one of its nodes reaches the
  outlet plane (`outlet`, a coordinate along `axis`; put it a couple of
  lattice spacings before the box's end, so that no node ever wraps round
  the periodic box into the inlet). `flow.removed` logs (cell id, time).
- **In.** After the removals, new cells are placed in the `inlet` box
  (random position and orientation, never overlapping other cells or the
  `boundaries`: oif.seed_cells; their nodes start with the fluid's
  velocity there; keep the box two lattice spacings from an open face,
  whose node plane the inlet rewrites) while the inlet's haematocrit (cell volume
  whose centre is in the inlet box over its fluid volume) is below
  `haematocrit`; or, with `rate` (cells per unit time), as many as are due
  since the last update; or, with `recycle=True`, as many as left (a closed
  loop with a constant number of cells). A cell that cannot be placed now
  (the inlet is crowded) is tried again at the next update.
- Deterministic: the placements come from one random generator seeded with
  `seed`; the same script gives the same cells.
"""
import numpy as np

from .oif_classes import OifCellType
from .seeding import SeedingError, seed_cells


class CellFlow:
    def __init__(self, system, cell_types, inlet, outlet, axis=0, haematocrit=None, rate=None, recycle=False,
                 fractions=None, boundaries=(), particle_types=None, particle_mass=1.0, seed=None, cells=None,
                 tries=3):
        import lbmd
        if not isinstance(system, lbmd.System):
            raise TypeError(f"CellFlow: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
        types = [cell_types] if isinstance(cell_types, OifCellType) else list(cell_types)
        if not types or not all(isinstance(t, OifCellType) for t in types):
            raise TypeError("CellFlow: parameter 'cell_types' must be an OifCellType or a list of them")
        try:
            lo, hi = (np.asarray(v, dtype=float).reshape(3) for v in inlet)
        except (TypeError, ValueError):
            raise ValueError(f"CellFlow: parameter 'inlet' must be a box (lo, hi) of two 3-vectors, got {inlet!r}") \
                from None
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
            raise ValueError(f"CellFlow: parameter 'inlet' must have hi > lo on every axis, got {inlet!r}")
        if axis not in (0, 1, 2):
            raise ValueError(f"CellFlow: parameter 'axis' must be 0, 1 or 2, got {axis!r}")
        outlet = float(outlet)
        if not (np.isfinite(outlet) and hi[axis] < outlet <= system.box_l[axis]):
            raise ValueError(f"CellFlow: parameter 'outlet' must lie beyond the inlet box ({hi[axis]:g}) and "
                             f"inside the box ({system.box_l[axis]:g}) along axis {axis}, got {outlet!r}")
        modes = [m for m, v in (("haematocrit", haematocrit), ("rate", rate), ("recycle", recycle or None))
                 if v is not None]
        if len(modes) != 1:
            raise ValueError("CellFlow: give exactly one of haematocrit, rate, recycle=True (got "
                             f"{', '.join(modes) or 'none'})")
        for name, value, upper in (("haematocrit", haematocrit, 0.6), ("rate", rate, np.inf)):
            if value is not None and not (np.isfinite(value) and 0 < value <= upper):
                raise ValueError(f"CellFlow: parameter '{name}' must be in (0, {upper:g}], got {value!r}")
        self.system, self.types, self.axis = system, types, axis
        self.inlet, self.outlet = (lo, hi), outlet
        self.haematocrit, self.rate, self.recycle = haematocrit, rate, bool(recycle)
        self.fractions = fractions
        self.boundaries = list(boundaries) if not hasattr(boundaries, "calc_dist") else [boundaries]
        self.particle_types = particle_types if particle_types is not None else [0] * len(types)
        self.particle_mass = particle_mass
        self.rng = np.random.default_rng(seed)
        self.tries = int(tries)
        self.cells = list(cells or [])
        self.removed = []   # (cell_id, time)
        self.added = []     # (cell_id, time)
        self._due = 0.0     # rate: the fraction of a cell owed to the inlet
        self._queue = []    # cells owed to the inlet (a type index, or None: drawn)
        self._last_time = system.time
        self._inlet_fluid = self._fluid_volume()

    def __repr__(self):
        mode = (f"haematocrit={self.haematocrit}" if self.haematocrit is not None else
                f"rate={self.rate}" if self.rate is not None else "recycle=True")
        return (f"CellFlow({mode}, axis={self.axis}, inlet={[v.tolist() for v in self.inlet]}, "
                f"outlet={self.outlet}, {len(self.cells)} cells, added {len(self.added)}, "
                f"removed {len(self.removed)})")

    def _fluid_volume(self):
        """Fluid volume of the inlet box: the box less the boundaries, on
        a grid of half-spacing points."""
        lo, hi = self.inlet
        n = np.maximum(2, np.ceil((hi - lo) / 0.5).astype(int))
        axes = [lo[d] + (np.arange(n[d]) + 0.5) * (hi[d] - lo[d]) / n[d] for d in range(3)]
        pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        inside = np.zeros(len(pts), dtype=bool)
        for shape in self.boundaries:
            inside |= np.array([shape.is_inside(p) for p in pts])
        return float(np.prod(hi - lo) * (1.0 - inside.mean()))

    def inlet_haematocrit(self):
        """Cell volume whose centre lies in the inlet box, over its fluid volume."""
        lo, hi = self.inlet
        volume = 0.0
        for c in self.cells:
            centre = np.mod(c.get_origin(), self.system.box_l)
            if np.all(centre >= lo) and np.all(centre <= hi):
                volume += c.volume()
        return volume / self._inlet_fluid if self._inlet_fluid > 0 else 0.0

    def _remove_leaving(self):
        leaving = [c for c in self.cells if c.mesh.positions()[:, self.axis].max() >= self.outlet]
        for c in leaving:
            c.remove()
            self.cells.remove(c)
            self.removed.append((c.cell_id, self.system.time))
        return leaving

    def _with_the_flow(self, cell):
        """A new cell's nodes start with the fluid's velocity where they are
        (a cell at rest dropped into a fast flow is jerked by the coupling)."""
        fluid = self.system.lb_fluid
        if fluid is None:
            return
        parts = cell.mesh._live_parts()
        parts.v = np.array([fluid.get_interpolated_velocity(p) for p in parts.pos])

    def _place_one(self, type_index=None):
        if type_index is None:
            weights = np.asarray(self.fractions if self.fractions is not None else [1.0] * len(self.types),
                                 dtype=float)
            type_index = int(self.rng.choice(len(self.types), p=weights / weights.sum()))
        counts = [0] * len(self.types)
        counts[type_index] = 1
        for _ in range(self.tries):
            try:
                new = seed_cells(self.system, self.types, counts=counts, boundaries=self.boundaries,
                                 region=self.inlet, particle_types=self.particle_types,
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
        """Remove the cells at the outlet, add cells at the inlet; returns
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
            for _ in range(100):  # at most this many at once
                if self.inlet_haematocrit() >= self.haematocrit:
                    break
                new = self._place_one()
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
