"""Legacy ASCII VTK polydata writer (the format PyOIF wrote; ParaView and
python3-vtk read it), and the safe text-file writer all oif output goes
through. In an MPI run only rank 0 writes; every rank must call (the data
are the same on all ranks)."""
import os
import stat

import numpy as np


def _is_writer():
    try:
        from mpi4py import MPI
        return MPI.COMM_WORLD.Get_rank() == 0
    except ImportError:  # pragma: no cover
        return True


def on_writer(action):
    """Run action() on the writing rank only; an exception it raises is
    raised on every rank, so that all ranks of an SPMD script see the same
    outcome (a rank that raised alone would leave the others waiting)."""
    try:
        from mpi4py import MPI
        comm = MPI.COMM_WORLD
    except ImportError:  # pragma: no cover
        comm = None
    if comm is None or comm.Get_size() == 1:
        action()
        return
    error = None
    if comm.Get_rank() == 0:
        try:
            action()
        except Exception as e:  # handed to every rank below
            error = e
    error = comm.bcast(error, root=0)
    if error is not None:
        raise error


def _check_name(name):
    if not isinstance(name, str) or not name or any(c.isspace() for c in name):
        raise ValueError(f"VTK output: data name must be a non-empty string without spaces, got {name!r}")


def output_path(path, owner="output"):
    """Check an output file name and prepare its folder: returns the path to
    write (symlinks resolved, so that the link keeps pointing at the data).
    Raises TypeError/ValueError naming the path for a non-string, an empty
    name, a name that is a directory or another non-regular file (device,
    fifo), or a folder part that is a regular file; creates missing folders."""
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise TypeError(f"{owner}: file name must be a string, got {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str):  # a PathLike returning bytes
        raise TypeError(f"{owner}: file name must be a string, got {path!r}")
    if not path:
        raise ValueError(f"{owner}: file name is empty")
    if path.endswith(os.sep) or os.path.isdir(path):
        raise ValueError(f"{owner}: '{path}' is a directory, not a file name")
    real = os.path.realpath(path)  # write to the target of a symlink, not over the link
    if os.path.lexists(real):
        mode = os.stat(real).st_mode if os.path.exists(real) else 0
        if not stat.S_ISREG(mode):
            raise ValueError(f"{owner}: '{path}' exists and is not a regular file (a directory, device, "
                             f"fifo or broken link); give the name of a regular file")
    # the first existing ancestor must be a folder: 'afile/x.vtk' cannot be created
    folder = os.path.dirname(real)
    probe = folder
    while probe and not os.path.exists(probe):
        probe = os.path.dirname(probe)
    if probe and not os.path.isdir(probe):
        raise ValueError(f"{owner}: cannot write '{path}': '{probe}' is a file, not a folder")
    if folder and not os.path.isdir(folder):
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError as e:
            raise OSError(f"{owner}: cannot create the folder of '{path}': {e.strerror or e}") from None
    return real


def write_text(path, text, owner="output"):
    """Write text to path through a temporary file in the same folder, renamed
    over the target at the end (readers never see a half-written file); the
    temporary file is removed on any failure. The name is checked and the
    folder created by the writing rank only, which hands its outcome to the
    others (on_writer): a check that came out differently on another rank
    (a node-local folder) cannot make one rank raise alone."""

    def write():
        real = output_path(path, owner)
        tmp = real + ".tmp"
        try:
            with open(tmp, "w") as f:
                f.write(text)
            os.replace(tmp, real)
        except OSError as e:
            raise OSError(f"{owner}: cannot write '{path}': {e.strerror or e}") from None
        finally:
            if os.path.lexists(tmp) and os.path.isfile(tmp):
                try:
                    os.remove(tmp)
                except OSError:  # pragma: no cover - the original error is the one to report
                    pass

    on_writer(write)


def format_rows(values, integer=False):
    """Whitespace table (one row per line) as np.savetxt wrote it for PyOIF's
    files: '%d' for indices, '%.15g' for coordinates."""
    values = np.asarray(values)
    values = values.reshape(len(values), -1)
    fmt = "%d" if integer else "%.15g"
    return "".join(" ".join(fmt % x for x in row) + "\n" for row in values.tolist())


def _point_arrays(point_data, n):
    if point_data is None:
        return []
    if not isinstance(point_data, dict):
        raise TypeError(f"VTK output: point_data must be a dict {{name: values}}, got {type(point_data).__name__}")
    arrays = []
    for name, values in point_data.items():
        _check_name(name)
        try:
            values = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"VTK output: point data '{name}' must be numbers") from None
        if values.shape not in ((n,), (n, 3)):
            raise ValueError(f"VTK output: point data '{name}' must have {n} values or {n} x 3 "
                             f"vectors, got shape {values.shape}")
        arrays.append((name, values))
    return arrays


def write_polydata(path, points, polygons=None, lines=None, point_data=None, title="PyOIF"):
    """Write points (N x 3), optional polygons (list of index lists or M x k
    array), lines (list of index lists) and point_data {name: N values or
    N x 3 vectors} to `path` (parent folder created if missing)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(points)
    arrays = _point_arrays(point_data, n)
    # every input checked on every rank: the writer raising alone before the
    # shared write would leave the other ranks waiting for its outcome
    cell_lists = []
    for keyword, cells in (("POLYGONS", polygons), ("LINES", lines)):
        if cells is not None and len(cells) > 0:
            try:
                cell_lists.append((keyword, [np.asarray(c, dtype=np.int64).ravel() for c in cells]))
            except (TypeError, ValueError):
                raise TypeError(f"VTK output: {keyword.lower()} must be lists of point indices") from None
    if not _is_writer():  # the other ranks only share the writer's outcome
        write_text(path, "", "VTK output")
        return
    out = [f"# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET POLYDATA\n", f"POINTS {n} double\n"]
    if n:
        out.append("\n".join(" ".join(repr(float(x)) for x in p) for p in points) + "\n")
    for keyword, cells in cell_lists:
        size = sum(len(c) + 1 for c in cells)
        out.append(f"{keyword} {len(cells)} {size}\n")
        out.append("\n".join(f"{len(c)} " + " ".join(map(str, c)) for c in cells) + "\n")
    if arrays:
        out.append(f"POINT_DATA {n}\n")
        for name, values in arrays:
            if values.ndim == 1:
                out.append(f"SCALARS {name} double 1\nLOOKUP_TABLE default\n")
                out.append("\n".join(repr(float(v)) for v in values) + "\n")
            else:
                out.append(f"VECTORS {name} double\n")
                out.append("\n".join(" ".join(repr(float(x)) for x in v) for v in values) + "\n")
    write_text(path, "".join(out), "VTK output")


def write_triangles(path, points, triangles, point_data=None):
    """A triangulated surface (triangles M x 3) with optional point data."""
    write_polydata(path, points, polygons=np.asarray(triangles), point_data=point_data)
