"""Particles: ``system.part`` (add, by_id, by_ids, all, clear), handles to one
particle and slices of many, with numpy-valued properties (ESPResSo 4.2 API).
ESPResSo 4.1's indexing, ``system.part[i]``, ``system.part[:]``,
``system.part[2:10]`` and ``system.part[[1, 5]]``, works too (lbmd.old_names)."""

import os

import numpy as np

_VECTOR_PROPS = ("pos", "v", "f", "ext_force")
_READONLY_VECTOR_PROPS = ("pos_folded", "image_box", "normal")
_SCALAR_PROPS = ("mass", "type", "mol_id")
_ADD_KEYS = ("id", "pos", "v", "mass", "type", "mol_id", "ext_force", "fix")


from .old_names import warn_old_name
from .validation import INT32_MAX, integers as _integers, is_whole_number


def _ids_array(ids, owner="particles", name="id"):
    return _integers(owner, name, ids, 0, INT32_MAX - 1)


def _one_id(owner, name, pid, hi=INT32_MAX - 1):
    """One particle id: an integer of any numeric kind (np.int64, a 0-d
    array, a whole float such as 1.0), refused when not whole or out of range."""
    if np.ndim(pid) != 0 or isinstance(pid, (str, bytes)):
        raise TypeError(f"{owner}: parameter '{name}' must be one particle id, got {pid!r}")
    return int(_integers(owner, name, pid, 0, hi)[0])


def _fix_to_mask(fix, n, what="ParticleList.add: parameter 'fix'"):
    fix = np.asarray(fix, dtype=bool)
    if fix.shape == (3,):
        fix = np.broadcast_to(fix, (n, 3))
    if fix.shape != (n, 3):
        raise ValueError(f"{what} must be 3 booleans per particle, got shape {fix.shape}")
    return (fix[:, 0] * 1 + fix[:, 1] * 2 + fix[:, 2] * 4).astype(np.int32)


class _ParticleView:
    """Shared property access for handles (one id) and slices (many ids)."""

    _single = False

    def __init__(self, system, ids):
        object.__setattr__(self, "_system", system)
        object.__setattr__(self, "_ids", _ids_array(ids))

    @property
    def _core(self):
        return self._system._core

    def _out(self, arr):
        return arr[0] if self._single else arr

    def _vec_in(self, name, value):
        arr = np.asarray(value, dtype=float)
        if arr.shape == (3,):
            arr = np.broadcast_to(arr, (len(self._ids), 3))
        if arr.shape != (len(self._ids), 3):
            raise ValueError(f"particle property '{name}' must be 3 numbers per particle, "
                             f"got shape {np.shape(value)} for {len(self._ids)} particle(s)")
        return np.ascontiguousarray(arr)

    def __getattr__(self, name):
        if name in _VECTOR_PROPS or name in _READONLY_VECTOR_PROPS:
            return self._out(self._core.get_vectors(name, self._ids))
        if name in _SCALAR_PROPS:
            return self._out(self._core.get_scalars(name, self._ids))
        if name == "fix":
            mask = self._core.get_scalars("fix", self._ids)
            arr = np.stack([(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0], axis=1)
            return self._out(arr)
        if name == "id":
            return self._out(self._ids.copy())
        raise AttributeError(f"{type(self).__name__} has no property '{name}'")

    def __setattr__(self, name, value):
        if name in _VECTOR_PROPS:
            self._core.set_vectors(name, self._ids, self._vec_in(name, value))
        elif name in _SCALAR_PROPS:
            if name == "mass":
                try:
                    arr = np.asarray(value, dtype=float)
                except (TypeError, ValueError):
                    raise TypeError(f"particle property 'mass' must be a number, got {value!r}") from None
            else:  # type >= 0, mol_id any int32
                arr = _integers("particle property", name, value, 0 if name == "type" else -2**31)
            if arr.ndim == 0 or arr.shape == (1,) and len(self._ids) != 1:
                arr = np.full(len(self._ids), arr.reshape(-1)[0], dtype=arr.dtype)
            if arr.shape != (len(self._ids),):
                raise ValueError(f"particle property '{name}' must be one value per particle, "
                                 f"got shape {np.shape(value)} for {len(self._ids)} particle(s)")
            self._core.set_scalars(name, self._ids, np.ascontiguousarray(arr, dtype=float))
        elif name == "fix":
            mask = _fix_to_mask(value, len(self._ids), "particle property 'fix'")
            self._core.set_scalars("fix", self._ids, mask.astype(float))
        elif name in _READONLY_VECTOR_PROPS or name == "id":
            raise AttributeError(f"particle property '{name}' is read-only")
        else:
            raise AttributeError(f"particles have no property '{name}' "
                                 f"(settable: {', '.join(_VECTOR_PROPS + _SCALAR_PROPS + ('fix',))})")

    def __dir__(self):
        # the particle properties, served by __getattr__, for tab completion
        return sorted(set(super().__dir__()) | set(_VECTOR_PROPS + _READONLY_VECTOR_PROPS + _SCALAR_PROPS)
                      | {"fix", "id"})

    def remove(self):
        for pid in self._ids:
            self._core.remove_particle(int(pid))


class ParticleHandle(_ParticleView):
    """One particle, by id."""

    _single = True

    def __init__(self, system, pid):
        super().__init__(system, [pid])
        if not system._core.exists(int(pid)):
            raise IndexError(f"particle id {pid} does not exist")

    @property
    def id(self):
        return int(self._ids[0])

    def add_bond(self, bond):
        """bond = (bonded_interaction, partner, ...): partners as ids or handles."""
        if not isinstance(bond, tuple) or len(bond) < 2:
            raise TypeError("add_bond: expected a tuple (bond, partner_id, ...)")
        ia, partners = bond[0], bond[1:]
        ids = [self.id] + [p.id if isinstance(p, ParticleHandle) else _one_id("add_bond", "partner", p)
                           for p in partners]
        ids = _ids_array(ids, "add_bond", "partner")
        self._system.bonded_inter._add_bonds(ia, ids.reshape(1, -1))

    def delete_bond(self, bond):
        if not isinstance(bond, tuple) or len(bond) < 2:
            raise TypeError("delete_bond: expected a tuple (bond, partner_id, ...)")
        ia, partners = bond[0], bond[1:]
        ids = [self.id] + [p.id if isinstance(p, ParticleHandle) else p for p in partners]
        ids = _ids_array(ids, "delete_bond", "partner").tolist()
        if not self._core.remove_bond(self._system.bonded_inter._id_of(ia), ids):
            raise ValueError(f"delete_bond: particle {self.id} has no such bond")

    @property
    def bonds(self):
        """Bonds owned by this particle: tuples (bond, partner ids...)."""
        out = []
        for bond_id, ia in enumerate(self._system.bonded_inter):
            for row in self._core.get_bonds(bond_id):
                if row[0] == self.id:
                    out.append((ia,) + tuple(int(x) for x in row[1:]))
        return tuple(out)

    def _partner(self, what, pid):
        if isinstance(pid, ParticleHandle):
            pid = pid.id
        pid = _one_id(what, "partner", pid)
        if not self._core.exists(pid):
            raise ValueError(f"{what}: partner particle {pid} does not exist")
        if pid == self.id:
            raise ValueError(f"{what}: a particle cannot be excluded from itself (id {pid})")
        return pid

    def add_exclusion(self, pid):
        """No non-bonded interaction between this particle and pid."""
        self._core.add_exclusion(self.id, self._partner("add_exclusion", pid))

    def delete_exclusion(self, pid):
        self._core.remove_exclusion(self.id, self._partner("delete_exclusion", pid))

    def to_dict(self):
        return {k: getattr(self, k) for k in ("id", "pos", "v", "f", "mass", "type", "mol_id",
                                              "ext_force", "fix")}

    def __repr__(self):
        from . import size
        if size > 1:  # pos and type are collective queries: repr() may be called on one rank
            return f"ParticleHandle(id={self.id})"
        return f"ParticleHandle(id={self.id}, pos={self.pos.tolist()}, type={self.type})"

    def __eq__(self, other):
        return isinstance(other, ParticleHandle) and other.id == self.id and other._system is self._system

    def __hash__(self):
        return hash(self.id)


class ParticleSlice(_ParticleView):
    """Several particles, by ids; properties are numpy arrays (N×3 or N)."""

    def __len__(self):
        return len(self._ids)

    def __iter__(self):
        for pid in self._ids:
            yield ParticleHandle(self._system, int(pid))

    def __getitem__(self, i):
        sel = self._ids[i]
        if np.ndim(sel) == 0:
            return ParticleHandle(self._system, int(sel))
        return ParticleSlice(self._system, sel)

    def __repr__(self):
        ids = self._ids.tolist()
        shown = ", ".join(map(str, ids[:6])) + (", ..." if len(ids) > 6 else "")
        return f"ParticleSlice({len(self)} particles, ids [{shown}])"


def outside_closed_axes(pos, box, periodic):
    """Positions outside the box along an axis that is not periodic (there
    is no image to fold them into): None, or (row, axis, count) of the first
    one and how many rows are outside."""
    periodic = np.asarray(periodic, dtype=bool)
    if periodic.all() or len(pos) == 0:
        return None
    outside = ~periodic & ((pos < 0.0) | (pos > np.asarray(box, dtype=float)))
    if not outside.any():
        return None
    k, axis = (int(i) for i in np.argwhere(outside)[0])
    return k, axis, int(outside.any(axis=1).sum())


def _check_inside_closed_axes(owner, system, pos):
    """Refuse positions outside the box along an axis that is not periodic:
    the engine would lose them."""
    if not np.all(np.isfinite(pos)):
        return  # (non-finite positions are refused by the engine, with their own message)
    periodic, box = np.asarray(system.periodicity, dtype=bool), np.asarray(system.box_l, dtype=float)
    found = outside_closed_axes(pos, box, periodic)
    if found is not None:
        k, axis, count = found
        name = "xyz"[axis]
        raise ValueError(f"{owner}: parameter 'pos': particle {k} at {name} = {pos[k, axis]:g} is outside the box "
                         f"(0..{box[axis]:g}) along {name}, which is not periodic (periodicity "
                         f"{[bool(v) for v in periodic]}); {count} of {len(pos)} "
                         f"particles are outside: place them inside, or make {name} periodic")


class ParticleList:
    """``system.part``: create, find and remove particles."""

    def __init__(self, system):
        self._system = system

    @property
    def _core(self):
        return self._system._core

    def add(self, *args, **kwargs):
        """Add one particle (pos of 3 numbers) -> ParticleHandle, or many
        (pos of shape N×3, other properties per particle or shared) -> ParticleSlice.

        Keywords: id, pos (required), v, mass, type, mol_id, ext_force, fix."""
        if args:
            if len(args) == 1 and isinstance(args[0], dict) and not kwargs:
                kwargs = dict(args[0])
            else:
                raise TypeError("ParticleList.add: use keyword arguments, e.g. add(pos=[1, 2, 3])")
        unknown = [k for k in kwargs if k not in _ADD_KEYS]
        if unknown:
            raise TypeError(f"ParticleList.add: unknown parameter(s) {', '.join(map(repr, unknown))}; "
                            f"accepted: {', '.join(_ADD_KEYS)}")
        if "pos" not in kwargs:
            raise TypeError("ParticleList.add: missing required parameter 'pos'")
        try:
            pos = np.asarray(kwargs["pos"], dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"ParticleList.add: parameter 'pos' must be numbers, got {kwargs['pos']!r}") from None
        single = pos.ndim == 1
        pos = np.atleast_2d(pos)
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise ValueError(f"ParticleList.add: parameter 'pos' must have 3 components per particle, "
                             f"got shape {np.shape(kwargs['pos'])}")
        n = pos.shape[0]
        _check_inside_closed_axes("ParticleList.add", self._system, pos)

        def per_particle_vec(name, default):
            value = kwargs.get(name, default)
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise TypeError(f"ParticleList.add: parameter '{name}' must be numbers, got {value!r}") from None
            if arr.shape == (3,):
                arr = np.broadcast_to(arr, (n, 3))
            if arr.shape != (n, 3):
                raise ValueError(f"ParticleList.add: parameter '{name}' must be 3 numbers"
                                 f"{' per particle' if not single else ''}, got shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"ParticleList.add: parameter '{name}' must be finite")
            return np.ascontiguousarray(arr)

        def per_particle_scalar(name, default, integer, lo=0, hi=INT32_MAX):
            value = kwargs.get(name, default)
            if integer:
                arr = _integers("ParticleList.add", name, value, lo, hi)
                if np.ndim(value) == 0:
                    arr = arr.reshape(())
            else:
                try:
                    arr = np.asarray(value)
                except (TypeError, ValueError):
                    arr = np.asarray(None, dtype=object)
            if arr.dtype == bool or (not integer and not np.issubdtype(arr.dtype, np.number)):
                raise TypeError(f"ParticleList.add: parameter '{name}' must be a number, got {value!r}")
            if arr.ndim == 0:
                arr = np.full(n, arr)
            if arr.shape != (n,):
                raise ValueError(f"ParticleList.add: parameter '{name}' must have one value per "
                                 f"particle, got shape {arr.shape}")
            return np.ascontiguousarray(arr, dtype=np.int32 if integer else float)

        v = per_particle_vec("v", [0.0, 0.0, 0.0])
        ext_force = per_particle_vec("ext_force", [0.0, 0.0, 0.0])
        mass = per_particle_scalar("mass", 1.0, False)
        if not np.all(mass > 0):
            raise ValueError(f"ParticleList.add: parameter 'mass' must be > 0, got {kwargs['mass']!r}")
        ptype = per_particle_scalar("type", 0, True)
        mol_id = per_particle_scalar("mol_id", 0, True, -2**31)
        if "id" in kwargs:
            ids = per_particle_scalar("id", 0, True, 0, INT32_MAX - 1)
            if len(np.unique(ids)) != n:
                raise ValueError("ParticleList.add: parameter 'id' has duplicate ids")
        else:
            first = self._core.max_id() + 1
            if first + n - 1 > INT32_MAX - 1:
                raise ValueError(f"ParticleList.add: no ids left above {first - 1} for {n} particles")
            ids = np.arange(first, first + n, dtype=np.int32)
        fix = _fix_to_mask(kwargs.get("fix", [False, False, False]), n)
        for pid in ids:
            if self._core.exists(int(pid)):
                raise ValueError(f"ParticleList.add: parameter 'id': particle {pid} already exists")
        new_ids = self._core.add_particles(ids, np.ascontiguousarray(pos), v, mass, ptype, mol_id,
                                           ext_force, fix)
        if single:
            return ParticleHandle(self._system, int(new_ids[0]))
        return ParticleSlice(self._system, new_ids)

    def by_id(self, pid):
        return ParticleHandle(self._system, _one_id("by_id", "pid", pid))

    def by_ids(self, ids):
        ids = _ids_array(ids, "by_ids", "ids")
        for pid in ids:
            if not self._core.exists(int(pid)):
                raise IndexError(f"particle id {pid} does not exist")
        return ParticleSlice(self._system, ids)

    def all(self):
        return ParticleSlice(self._system, self._core.all_ids())

    def __getitem__(self, key):
        """ESPResSo 4.1 indexing (warns once): ``part[i]`` is by_id(i);
        ``part[start:stop:step]`` the existing particles among the ids
        range(0, highest id + 1)[start:stop:step] (``part[:]`` is all());
        ``part[[i, j, ...]]`` is by_ids([i, j, ...])."""
        if isinstance(key, slice):
            warn_old_name("system.part[start:stop]", "system.part.all() or system.part.by_ids()")
            for name in ("start", "stop", "step"):
                value = getattr(key, name)
                if value is not None and not is_whole_number(value):
                    raise TypeError(f"system.part[...]: slice {name} must be an integer, got {value!r}")
            key = slice(*(None if v is None else int(v) for v in (key.start, key.stop, key.step)))
            ids = np.arange(self._core.max_id() + 1)[key]
            all_ids = np.asarray(self._core.all_ids())
            return ParticleSlice(self._system, ids[np.isin(ids, all_ids)])
        if np.ndim(key) == 0 and not isinstance(key, (str, bytes)):
            warn_old_name("system.part[id]", "system.part.by_id(id)")
            return self.by_id(key)
        warn_old_name("system.part[ids]", "system.part.by_ids(ids)")
        return self.by_ids(key)

    def select(self, **conditions):
        """Particles whose properties equal the given values, e.g. select(type=1)."""
        sl = self.all()
        mask = np.ones(len(sl), dtype=bool)
        for k, val in conditions.items():
            mask &= np.asarray(getattr(sl, k)) == val
        return ParticleSlice(self._system, sl._ids[mask])

    def exists(self, pid):
        """Whether particle pid exists (False for any negative or too large id)."""
        if is_whole_number(pid) and not 0 <= pid <= INT32_MAX:
            return False
        pid = _one_id("exists", "pid", pid, INT32_MAX)
        return pid < INT32_MAX and bool(self._core.exists(pid))

    def clear(self):
        self._core.clear_particles()

    @property
    def highest_particle_id(self):
        return int(self._core.max_id())

    def __len__(self):
        return int(self._core.n_particles())

    def __iter__(self):
        """Handles of all particles, by increasing id (ESPResSo: ``for p in system.part``)."""
        return iter(self.all())

    def writevtk(self, fname, types="all"):
        """ESPResSo's ``system.part.writevtk``: a legacy ASCII VTK file of the
        folded positions of the particles of the given types ('all', one
        type or a list of types), as vertices, with their velocities as point
        data 'velocity'. Written once under MPI (every rank calls)."""
        from .file_output import is_writer, write_text
        owner = "system.part.writevtk"
        if not isinstance(fname, (str, os.PathLike)) or isinstance(fname, bytes):
            raise TypeError(f"{owner}: parameter 'fname' must be a file name, got {fname!r}")
        sl = self.all()
        if isinstance(types, str):
            if types != "all":
                raise ValueError(f"{owner}: parameter 'types' must be 'all', a type or a list of types, "
                                 f"got {types!r}")
            sel = sl
        else:
            wanted = _integers(owner, "types", np.atleast_1d(types) if np.ndim(types) == 0 else types, 0, INT32_MAX)
            sel = ParticleSlice(self._system, sl._ids[np.isin(sl.type, wanted)])
        pos, vel = sel.pos_folded.reshape(-1, 3), sel.v.reshape(-1, 3)
        n = len(pos)
        text = ""
        if is_writer():
            rows = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in pos.tolist())
            verts = "".join(f"1 {i}\n" for i in range(n))
            vels = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in vel.tolist())
            text = (f"# vtk DataFile Version 3.0\nparticles\nASCII\nDATASET POLYDATA\nPOINTS {n} double\n{rows}"
                    f"VERTICES {n} {2 * n}\n{verts}POINT_DATA {n}\nVECTORS velocity double\n{vels}")
        write_text(fname, text, owner)

    def add_bonds(self, bond, ids, per_bond=None):
        """Bulk bonds: ids is an M×k array of particle ids, one row per bond
        (owner first); per_bond an M×s array of per-bond reference values for
        bonds that have them (default: the bond's own, see BondedInteraction)."""
        self._system.bonded_inter._add_bonds(bond, ids, per_bond)

    def add_exclusions(self, pairs):
        """Bulk exclusions: pairs is an M×2 array of particle ids; no
        non-bonded interaction acts between the two particles of a row
        (a cell's nodes near each other on its own membrane)."""
        self._core.add_exclusions(np.ascontiguousarray(pairs, dtype=np.int32))

    def __repr__(self):
        return f"ParticleList({len(self)} particles)"
