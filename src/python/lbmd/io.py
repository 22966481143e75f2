"""Trajectories in H5MD 1.1 (HDF5 for molecular data, https://www.nongnu.org/h5md/)
through Debian's h5py (package python3-h5py, serial HDF5).

``H5mdWriter(path, system, fields=..., cells=None, ...)``: ``write()`` appends
one frame (the particles' current state and, for the oif cells given, their
centre, volume, surface, ...), ``close()`` ends the file; also a context
manager. The layout (``<g>`` is the particle group, "atoms" by default, as
ESPResSo's writer)::

    h5md/                      +version [1, 1]
        author/                +name
        creator/               +name "PyOIF (lbmd)", +version
    particles/<g>/
        box/                   +dimension 3, +boundary ["periodic" | "none"] x 3
            edges/{step,time,value[n][3]}
        position/{step,time,value[n][N][3]}   folded into the box
        image/{step,time,value[n][N][3]}      position + image * edges = unfolded
        velocity/, force/      {step,time,value[n][N][3]}
        species/, id/, mol_id/, mass/         {step,time,value[n][N]}
    observables/cells/
        cell_id                mol_id of each cell (fixed)
        centre/{step,time,value[n][C][3]}, volume/, surface/ {..., value[n][C]}, velocity/,
        deformation_index/, max_edge_strain/, max_area_strain/, damage_time/, peak_area_strain/

Every time-dependent element has its own ``step`` (int64, the system's
``step_count``) and ``time`` (float64, ``system.time``) datasets, extensible
along the frame axis and chunked one frame per chunk. Rows are the particles
in increasing id order. ``mol_id`` is not a standard H5MD element (the
standard names no molecule element; ESPResSo's writer does not write one):
it sits beside the standard ones under the name the engine uses.

Particle number: by default a frame must hold as many particles as the
first (``ValueError`` otherwise, naming both counts). With
``variable_particles=True`` the particle axis grows as needed and the rows
of absent particles hold the fill values, ``id`` -1 (the H5MD convention
for a particle that is not there), ``species``/``mol_id`` -1 and NaN for
the floating-point fields.

Appending (``append=True``, a run resumed from a checkpoint): an existing
file is opened, checked (H5MD 1.1, the same particle group and fields, the
same cells, and for a fixed particle number the same count), and frames with
a step beyond the system's ``step_count`` (written after the checkpoint)
are dropped, so the resumed run writes them again. Without ``append`` an
existing file is replaced.

Under MPI every rank calls (the particle and cell queries are collective,
they return every particle on every rank); rank 0 alone opens and writes the
file, and an error there is raised on every rank (``lbmd.file_output``).
"""
import os

import numpy as np

from . import file_output
from .vtk_output import check_names

#: per-particle fields H5mdWriter can write, with what they hold
FIELDS = {
    "position": "position folded into the box (3 floats)",
    "velocity": "velocity (3 floats)",
    "force": "force of the last step (3 floats)",
    "image": "periodic image: position + image * edges is the unfolded position (3 ints)",
    "species": "particle type (int)",
    "id": "particle id (int; -1: no particle in this row)",
    "mol_id": "molecule id: the cell (int; not a standard H5MD element)",
    "mass": "mass (float)",
}
DEFAULT_FIELDS = ("position", "velocity", "force", "image", "species", "id", "mol_id")

#: per-cell observables (oif cells), with what they hold
CELL_FIELDS = {
    "centre": "mean node position, unfolded (OifCell.get_origin)",
    "volume": "enclosed volume (OifCell.volume)",
    "surface": "surface area (OifCell.surface)",
    "velocity": "mean node velocity (OifCell.get_velocity)",
    "deformation_index": "Taylor's (a - c) / (a + c) from the nodes' gyration tensor (OifCell.deformation_index)",
    "max_edge_strain": "largest abs(l / l0 - 1) over the edges (OifCell.max_edge_strain)",
    "max_area_strain": "largest abs(A / A0 - 1) over the triangles (OifCell.max_area_strain)",
    "damage_time": "time with max_area_strain above the damage threshold so far (cell.damage.time_above; "
                   "oif.update_damage fills it)",
    "peak_area_strain": "largest max_area_strain oif.update_damage has seen (cell.damage.peak_strain)",
}
DEFAULT_CELL_FIELDS = ("centre", "volume", "surface")

# field -> (particle property, numpy dtype, components (0: scalar), fill value)
_SPECS = {
    "position": ("pos_folded", np.float64, 3, np.nan),
    "velocity": ("v", np.float64, 3, np.nan),
    "force": ("f", np.float64, 3, np.nan),
    "image": ("image_box", np.int32, 3, 0),
    "species": ("type", np.int32, 0, -1),
    "id": ("id", np.int32, 0, -1),
    "mol_id": ("mol_id", np.int32, 0, -1),
    "mass": ("mass", np.float64, 0, np.nan),
}
_CELL_SPECS = {
    "centre": (lambda c: c.get_origin(), 3),
    "volume": (lambda c: c.volume(), 0),
    "surface": (lambda c: c.surface(), 0),
    "velocity": (lambda c: c.get_velocity(), 3),
    "deformation_index": (lambda c: c.deformation_index(), 0),
    "max_edge_strain": (lambda c: c.max_edge_strain(), 0),
    "max_area_strain": (lambda c: c.max_area_strain(), 0),
    "damage_time": (lambda c: c.damage.time_above, 0),
    "peak_area_strain": (lambda c: c.damage.peak_strain, 0),
}


def _import_h5py(owner):
    try:
        import h5py
    except ImportError as e:  # pragma: no cover - python3-h5py is a dependency
        raise ImportError(f"{owner} needs h5py (Debian package python3-h5py): {e}") from None
    return h5py


class H5mdWriter:
    """An H5MD 1.1 trajectory of ``system`` (see the module's text).

    ``H5mdWriter(path, system, fields=DEFAULT_FIELDS, cells=None,
    cell_fields=DEFAULT_CELL_FIELDS, group="atoms", author="", append=False,
    variable_particles=False, compression=None)``

    path: the .h5 file; fields: names out of ``FIELDS``; cells: a list of
    oif.OifCell whose ``cell_fields`` (names out of ``CELL_FIELDS``) go to
    ``observables/cells``; author: the ``h5md/author`` name (default: the
    login name); compression: None or "gzip". Collective under MPI."""

    def __init__(self, path, system, fields=DEFAULT_FIELDS, cells=None, cell_fields=DEFAULT_CELL_FIELDS,
                 group="atoms", author="", append=False, variable_particles=False, compression=None):
        owner = "H5mdWriter"
        from .system import System
        if not isinstance(system, System):
            raise TypeError(f"{owner}: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
        from .vtk_output import check_path
        self.path = check_path(owner, path, ".h5", example="out/trajectory")
        self.system = system
        self.fields = check_names(owner, "fields", fields, tuple(FIELDS), allow_empty=False)
        cells = [] if cells is None else list(cells) if not isinstance(cells, (str, bytes)) else None
        if cells is None or any(not all(hasattr(c, a) for a in ("cell_id", "volume", "surface", "get_origin"))
                                for c in cells):
            raise TypeError(f"{owner}: parameter 'cells' must be a list of oif.OifCell, got {cells!r}")
        self.cells = cells
        self.cell_fields = check_names(owner, "cell_fields", cell_fields, tuple(CELL_FIELDS)) if cells else ()
        if not isinstance(group, str) or not group or "/" in group or group == ".":
            raise ValueError(f"{owner}: parameter 'group' must be a non-empty name without '/', got {group!r}")
        self.group = group
        if not isinstance(author, str):
            raise TypeError(f"{owner}: parameter 'author' must be a string, got {type(author).__name__}")
        self.author = author or _login_name()
        for name, value in (("append", append), ("variable_particles", variable_particles)):
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{owner}: parameter '{name}' must be True or False, got {value!r}")
        self.variable_particles = bool(variable_particles)
        if self.variable_particles and "id" not in self.fields:
            raise ValueError(f"{owner}: variable_particles=True needs the field 'id' (it tells which rows "
                             f"hold a particle), got fields {list(self.fields)}")
        if compression not in (None, "gzip"):
            raise ValueError(f"{owner}: parameter 'compression' must be None or 'gzip', got {compression!r}")
        self.compression = compression
        self._file = None  # h5py.File on the writing rank
        self._n_particles = None  # the fixed particle count (after the first frame)
        self._closed = False
        self.frames = 0
        _import_h5py(owner)
        mode = "append" if append and _exists_on_writer(self.path) else "create"
        # rank 0 opens; what it found (the particle count of the last frame kept)
        # goes to every rank, so that all refuse a mismatching frame alike
        found = {}

        def open_file():
            found.update(self._open_append() if mode == "append" else self._create())

        file_output.on_writer(open_file)
        from . import comm, size
        if size > 1:
            found = comm.bcast(found, root=0)
        self.frames = found.get("frames", 0)
        self._n_particles = found.get("n_particles")
        if mode == "append" and not self.variable_particles and self._n_particles is not None:
            n = len(system.part)
            if n != self._n_particles:
                self._close_quietly()
                raise ValueError(f"{owner}: cannot append to '{self.path}': its frames hold "
                                 f"{self._n_particles} particles, the system has {n} (a different run? "
                                 f"use a new file, or variable_particles=True for a changing number)")

    # -- file structure (writing rank) ------------------------------------------
    def _create(self):
        h5py = _import_h5py("H5mdWriter")
        real = file_output.output_path(self.path, "H5mdWriter")
        try:
            f = h5py.File(real, "w")
        except OSError as e:
            raise OSError(f"H5mdWriter: cannot create '{self.path}': {e}") from None
        self._file = f
        from . import __version__
        h5md = f.create_group("h5md")
        h5md.attrs["version"] = np.array([1, 1], dtype=np.int32)
        h5md.create_group("author").attrs["name"] = self.author
        creator = h5md.create_group("creator")
        creator.attrs["name"] = "PyOIF (lbmd)"
        creator.attrs["version"] = __version__
        g = f.create_group(f"particles/{self.group}")
        box = g.create_group("box")
        box.attrs["dimension"] = np.int32(3)
        box.attrs["boundary"] = np.array(["periodic" if p else "none" for p in self.system.periodicity],
                                         dtype=h5py.string_dtype("ascii"))
        self._element(box, "edges", np.float64, (3,), np.nan, 3)
        for name in self.fields:
            _, dtype, comps, fill = _SPECS[name]
            self._element(g, name, dtype, (0, 3) if comps else (0,), fill, None)
        if self.cells:
            obs = f.create_group("observables/cells")
            obs.create_dataset("cell_id", data=np.array([c.cell_id for c in self.cells], dtype=np.int32))
            for name in self.cell_fields:
                comps = _CELL_SPECS[name][1]
                n = len(self.cells)
                self._element(obs, name, np.float64, (n, 3) if comps else (n,), np.nan, n)
        f.flush()
        return {"frames": 0, "n_particles": None}

    def _element(self, parent, name, dtype, frame_shape, fill, chunk_rows):
        """A time-dependent element {step, time, value}: extensible along the
        frame axis (and along the particle axis, for per-particle values)."""
        grp = parent.create_group(name)
        grp.create_dataset("step", shape=(0,), maxshape=(None,), dtype=np.int64, chunks=(1024,))
        grp.create_dataset("time", shape=(0,), maxshape=(None,), dtype=np.float64, chunks=(1024,))
        per_particle = chunk_rows is None
        maxshape = (None,) + ((None,) + frame_shape[1:] if per_particle else frame_shape)
        # one frame per chunk; at least 64 rows, so that a particle axis that grows
        # from few particles (variable_particles) does not end in tiny chunks
        chunks = (1,) + ((min(4096, max(64, len(self.system.part))),) + frame_shape[1:] if per_particle
                         else frame_shape)
        grp.create_dataset("value", shape=(0,) + frame_shape, maxshape=maxshape, dtype=dtype, chunks=chunks,
                           fillvalue=fill, compression=self.compression)

    def _open_append(self):
        h5py = _import_h5py("H5mdWriter")
        real = file_output.output_path(self.path, "H5mdWriter")
        where = f"H5mdWriter: cannot append to '{self.path}'"
        try:
            f = h5py.File(real, "r+")
        except OSError as e:
            raise OSError(f"{where}: {e}") from None
        self._file = f
        try:
            version = f["h5md"].attrs["version"] if "h5md" in f else None
            if version is None or [int(v) for v in version] != [1, 1]:
                raise ValueError(f"{where}: not an H5MD 1.1 file (no h5md/version [1, 1])")
            gname = f"particles/{self.group}"
            if gname not in f:
                raise ValueError(f"{where}: it has no particle group '{self.group}'")
            g = f[gname]
            present = tuple(k for k in FIELDS if k in g)
            if sorted(present) != sorted(self.fields):
                raise ValueError(f"{where}: it holds the fields {list(present)}, this writer was asked "
                                 f"for {list(self.fields)}")
            if self.cells:
                obs = f.get("observables/cells")
                ids = [] if obs is None or "cell_id" not in obs else obs["cell_id"][()].tolist()
                if ids != [c.cell_id for c in self.cells]:
                    raise ValueError(f"{where}: its cells have the ids {ids}, this writer's "
                                     f"{[c.cell_id for c in self.cells]}")
                have = tuple(k for k in CELL_FIELDS if k in obs)
                if sorted(have) != sorted(self.cell_fields):
                    raise ValueError(f"{where}: it holds the cell observables {list(have)}, this writer "
                                     f"was asked for {list(self.cell_fields)}")
            # frames written after the checkpoint this run resumed from go
            step_now = self.system.step_count
            elements = [g["box/edges"]] + [g[k] for k in self.fields]
            if self.cells:
                elements += [f["observables/cells"][k] for k in self.cell_fields]
            for el in elements:
                steps = el["step"][()]
                keep = int(np.searchsorted(steps, step_now, side="right"))
                if keep < len(steps):
                    for k in ("step", "time", "value"):
                        el[k].resize(keep, axis=0)
            frames = len(g["box/edges/step"])
            n_particles = None
            if frames:
                ref = g["id/value"][frames - 1] if "id" in self.fields else None
                if ref is not None:
                    n_particles = int(np.count_nonzero(ref >= 0))
                else:
                    el = g[self.fields[0]]["value"]
                    n_particles = int(el.shape[1])
            f.flush()
            return {"frames": frames, "n_particles": n_particles}
        except BaseException:
            f.close()
            self._file = None
            raise

    # -- writing --------------------------------------------------------------------
    def write(self):
        """Append one frame: the particles' fields and the cells' observables
        at the system's current step and time. Collective under MPI."""
        if self._closed:
            raise ValueError(f"H5mdWriter: '{self.path}' is closed; make a new H5mdWriter(..., append=True)")
        system = self.system
        step, time = system.step_count, float(system.time)
        part = system.part.all()
        n = len(part)
        if self._n_particles is not None and n != self._n_particles and not self.variable_particles:
            raise ValueError(f"H5mdWriter.write: the system has {n} particles, the frames of '{self.path}' "
                             f"{self._n_particles}; pass variable_particles=True for a changing number "
                             f"(absent rows then hold id -1)")
        values = {}
        for name in self.fields:
            prop, dtype, comps, _ = _SPECS[name]
            arr = np.asarray(getattr(part, prop))
            values[name] = arr.astype(dtype).reshape((n, 3) if comps else (n,))
        cell_values = {}
        for name in self.cell_fields:
            get, comps = _CELL_SPECS[name]
            cell_values[name] = np.array([get(c) for c in self.cells], dtype=np.float64).reshape(
                (len(self.cells), 3) if comps else (len(self.cells),))
        edges = np.asarray(system.box_l, dtype=np.float64)

        def append():
            f = self._file
            g = f[f"particles/{self.group}"]
            _append(g["box/edges"], step, time, edges)
            for name, arr in values.items():
                _append(g[name], step, time, arr)
            if cell_values:
                obs = f["observables/cells"]
                for name, arr in cell_values.items():
                    _append(obs[name], step, time, arr)
            f.flush()  # a run that is killed keeps the frames written so far

        file_output.on_writer(append)
        if self._n_particles is None:
            self._n_particles = n
        self.frames += 1

    def close(self):
        """Close the file (every rank calls; a second close does nothing)."""
        if self._closed:
            return
        self._closed = True
        file_output.on_writer(self._close_quietly)

    def _close_quietly(self):
        if self._file is not None:
            f, self._file = self._file, None
            f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        # an unclosed writer on the writing rank: let HDF5 finish the file
        if getattr(self, "_file", None) is not None:
            try:
                self._file.close()
            except Exception:  # pragma: no cover - interpreter shutdown
                pass

    def __repr__(self):
        state = "closed" if self._closed else f"{self.frames} frame(s)"
        cells = f", cells={len(self.cells)}" if self.cells else ""
        return f"H5mdWriter('{self.path}', fields={list(self.fields)}{cells}, {state})"


def _append(element, step, time, value):
    """One frame onto a time-dependent element; the particle axis grows to
    the frame's rows (the rows beyond them keep the dataset's fill value)."""
    k = element["step"].shape[0]
    for name, v in (("step", step), ("time", time)):
        element[name].resize(k + 1, axis=0)
        element[name][k] = v
    ds = element["value"]
    shape = list(ds.shape)
    shape[0] = k + 1
    if value.ndim >= 1 and ds.ndim >= 2 and ds.maxshape[1] is None and value.shape[0] > shape[1]:
        shape[1] = value.shape[0]
    ds.resize(tuple(shape))
    if ds.maxshape[1:] and ds.ndim >= 2 and ds.maxshape[1] is None:
        ds[k, :value.shape[0]] = value
        if value.shape[0] < shape[1]:  # fewer particles than rows: the rest are absent
            ds[k, value.shape[0]:] = ds.fillvalue
    else:
        ds[k] = value


def _exists_on_writer(path):
    """Whether path exists, as the writing rank sees it (told to every rank)."""
    from . import comm, rank, size
    exists = os.path.exists(path) if rank == 0 else None
    return comm.bcast(exists, root=0) if size > 1 else exists


def _login_name():
    try:
        import getpass
        return getpass.getuser()
    except Exception:  # no login name (containers): a neutral one
        return "unknown"
