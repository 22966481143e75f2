"""Surface meshes for shapes.SurfaceMesh: read_surface(path) gives the
vertices and triangles of a surface file (STL, ASCII or binary, read here;
every other format through Debian's python3-meshio), mesh_arrays checks
given arrays. Errors name the parameter or the file (and line)."""
import contextlib
import io
import os

import numpy as np

from .validation import integers


def mesh_arrays(vertices, triangles):
    """vertices as an (N, 3) float array and triangles as an (M, 3) int32
    array of ids in 0..N-1, refused with the parameter named otherwise."""
    try:
        raw = np.asarray(vertices)
        if raw.dtype.kind not in "iuf":
            raise TypeError
        v = raw.astype(float)
    except (TypeError, ValueError):
        raise TypeError("SurfaceMesh: parameter 'vertices' must be an N x 3 array of numbers, "
                        f"got {type(vertices).__name__}") from None
    if v.ndim != 2 or v.shape[1] != 3 or not len(v):
        raise ValueError("SurfaceMesh: parameter 'vertices' must be an N x 3 array (N > 0), "
                         f"got shape {v.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(v), axis=1))
    if bad.size:
        raise ValueError(f"SurfaceMesh: parameter 'vertices': vertex {bad[0]} is not finite: "
                         f"{v[bad[0]].tolist()}")
    shape = np.shape(triangles)
    if len(shape) != 2 or shape[1] != 3 or not shape[0]:
        raise ValueError("SurfaceMesh: parameter 'triangles' must be an M x 3 array of vertex "
                         f"ids (M > 0), got shape {shape}")
    t = integers("SurfaceMesh", "triangles", triangles, 0, len(v) - 1).reshape(-1, 3)
    return np.ascontiguousarray(v), t


def read_surface(path):
    """(vertices, triangles) of a surface file: STL (ASCII or binary) read
    here, every other format through meshio (triangles, and quads split in
    two). OSError for a missing file, ValueError naming the file otherwise."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"SurfaceMesh: parameter 'file': no such file {path!r}")
    if os.path.getsize(path) == 0:
        raise ValueError(f"SurfaceMesh: file {path!r} is empty")
    if path.lower().endswith(".stl"):
        return _read_stl(path)
    try:
        import meshio
    except ImportError:  # pragma: no cover - Debian's python3-meshio
        raise ImportError(f"SurfaceMesh: reading {path!r} needs meshio (Debian: python3-meshio); "
                          "STL files are read without it") from None
    said = io.StringIO()
    try:
        # meshio prints its complaints and, for some, calls sys.exit
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            mesh = meshio.read(path)
    except (Exception, SystemExit) as err:
        why = f"{type(err).__name__}: {err}" if isinstance(err, Exception) else "meshio"
        why += "; " + " ".join(said.getvalue().split()) if said.getvalue().strip() else ""
        raise ValueError(f"SurfaceMesh: cannot read {path!r} ({why})") from None
    parts = []
    for block in mesh.cells:
        if block.type == "triangle":
            parts.append(np.asarray(block.data))
        elif block.type == "quad":
            q = np.asarray(block.data)
            parts += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    if not parts:
        kinds = sorted({block.type for block in mesh.cells})
        raise ValueError(f"SurfaceMesh: file {path!r} has no triangles (cells: {kinds})")
    return np.asarray(mesh.points, dtype=float)[:, :3], np.concatenate(parts)


def _read_stl(path):
    with open(path, "rb") as f:
        data = f.read()
    n = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if n >= 0 and len(data) == 84 + 50 * n:
        record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
        corners = np.frombuffer(data, record, count=n, offset=84)["corners"].astype(float)
    else:
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError:
            raise ValueError(f"SurfaceMesh: {path!r} is neither a binary STL (size {len(data)} "
                             f"bytes, expected 84 + 50 * {n}) nor an ASCII one") from None
        if not text.lstrip().startswith("solid"):
            raise ValueError(f"SurfaceMesh: {path!r} is neither a binary STL (size {len(data)} "
                             "bytes) nor an ASCII one (which starts with 'solid')")
        points = []
        for number, line in enumerate(text.splitlines(), 1):
            words = line.split()
            if words and words[0] == "vertex":
                try:
                    if len(words) != 4:
                        raise ValueError
                    points.append([float(w) for w in words[1:]])
                except ValueError:
                    raise ValueError(f"SurfaceMesh: {path!r} line {number}: expected 'vertex x y "
                                     f"z', got {line.strip()!r}") from None
        if len(points) % 3:
            raise ValueError(f"SurfaceMesh: {path!r}: {len(points)} vertices, not 3 per facet")
        corners = np.asarray(points, dtype=float).reshape(-1, 3, 3)
    if not len(corners):
        raise ValueError(f"SurfaceMesh: file {path!r} has no triangles")
    # STL repeats each corner per facet: equal coordinates are one vertex
    vertices, ids = np.unique(corners.reshape(-1, 3), axis=0, return_inverse=True)
    return vertices, ids.reshape(-1, 3)
