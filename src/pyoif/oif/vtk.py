"""Legacy ASCII VTK polydata writer (the format PyOIF wrote; ParaView and
python3-vtk read it), and the safe text-file writer all oif output goes
through. In an MPI run only rank 0 writes; every rank must call (the data
are the same on all ranks)."""
import numpy as np

# the rank-0 writer and the atomic file writes live in the engine package (one
# piece of code for lbmd's and oif's output)
from lbmd.file_output import is_writer, on_writer, output_path, write_text  # noqa: F401


def _check_name(name):
    if not isinstance(name, str) or not name or any(c.isspace() for c in name):
        raise ValueError(f"VTK output: data name must be a non-empty string without spaces, got {name!r}")


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
    if not is_writer():  # the other ranks only share the writer's outcome
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
