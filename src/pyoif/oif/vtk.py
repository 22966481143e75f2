"""Legacy ASCII VTK polydata writer (the format PyOIF wrote; ParaView and
python3-vtk read it). In an MPI run only rank 0 writes; every rank must call
(the data are the same on all ranks)."""
import os

import numpy as np


def _is_writer():
    try:
        from mpi4py import MPI
        return MPI.COMM_WORLD.Get_rank() == 0
    except ImportError:  # pragma: no cover
        return True


def _check_name(name):
    if not isinstance(name, str) or not name or any(c.isspace() for c in name):
        raise ValueError(f"VTK output: data name must be a non-empty string without spaces, got {name!r}")


def write_polydata(path, points, polygons=None, lines=None, point_data=None, title="PyOIF"):
    """Write points (N x 3), optional polygons (list of index lists or M x k
    array), lines (list of index lists) and point_data {name: N values or
    N x 3 vectors} to `path` (parent folder created if missing)."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"VTK output: file name must be a string, got {type(path).__name__}")
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(points)
    arrays = []
    for name, values in (point_data or {}).items():
        _check_name(name)
        values = np.asarray(values, dtype=float)
        if values.shape not in ((n,), (n, 3)):
            raise ValueError(f"VTK output: point data '{name}' must have {n} values or {n} x 3 "
                             f"vectors, got shape {values.shape}")
        arrays.append((name, values))
    if not _is_writer():
        return
    folder = os.path.dirname(os.fspath(path))
    if folder:
        os.makedirs(folder, exist_ok=True)
    out = [f"# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET POLYDATA\n", f"POINTS {n} double\n"]
    out.append("\n".join(" ".join(repr(float(x)) for x in p) for p in points) + "\n")
    for keyword, cells in (("POLYGONS", polygons), ("LINES", lines)):
        if cells is None or len(cells) == 0:
            continue
        cells = [np.asarray(c, dtype=np.int64).ravel() for c in cells]
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
    tmp = os.fspath(path) + ".tmp"
    with open(tmp, "w") as f:
        f.write("".join(out))
    os.replace(tmp, path)


def write_triangles(path, points, triangles, point_data=None):
    """A triangulated surface (triangles M x 3) with optional point data."""
    write_polydata(path, points, polygons=np.asarray(triangles), point_data=point_data)
