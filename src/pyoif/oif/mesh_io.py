"""Reading and checking triangulated cell surfaces.

A cell type's relaxed shape is a closed, orientable 2-manifold: every edge is
shared by exactly two triangles, the triangles around every node form one fan,
no node is unused or duplicated, no triangle is degenerate, no edge passes
through a triangle (the surface does not cross itself). ``read_mesh``
checks all of that and reports the offending file and line, and (with
``check_orientation``) makes the orientation of all triangles consistent.

Orientation convention (the one of PyOIF's ``nodes.dat``/``triangles.dat``
files, kept so that files round-trip with ESPResSo): for a stored triangle
(A, B, C) the normal (B - A) x (C - A) points *into* the cell.
``outward(triangles)`` gives the same triangles ordered with outward normals.

Everything here works on numpy arrays; it needs no simulation system.
"""
import os

import numpy as np

#: nodes closer than this fraction of the mean edge length are duplicates
DUPLICATE_NODE_TOLERANCE = 1e-8
#: triangles with an area below this fraction of the mean edge length squared are degenerate
DEGENERATE_AREA_TOLERANCE = 1e-10


class MeshData:
    """Checked mesh: nodes (N x 3), triangles (M x 3, PyOIF orientation) and
    where each came from, for messages: file names and line numbers for
    PyOIF's text files; for files read through meshio (lines=False), the
    triangle's place among the file's triangles and the point's index."""

    def __init__(self, nodes, triangles, nodes_file="<array>", triangles_file="<array>",
                 node_lines=None, triangle_lines=None, lines=True):
        self.nodes = np.ascontiguousarray(nodes, dtype=float)
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        self.nodes_file = nodes_file
        self.triangles_file = triangles_file
        self.lines = lines
        self.node_lines = (np.arange(1, len(self.nodes) + 1) if node_lines is None
                           else np.asarray(node_lines))
        self.triangle_lines = (np.arange(1, len(self.triangles) + 1) if triangle_lines is None
                               else np.asarray(triangle_lines))
        self.flipped = np.zeros(len(self.triangles), dtype=bool)

    def __repr__(self):
        return (f"MeshData({len(self.nodes)} nodes from '{self.nodes_file}', {len(self.triangles)} "
                f"triangles from '{self.triangles_file}')")

    def node_at(self, i):
        """'file, line L' (or 'file, point k (counted from 0)') of node i."""
        return f"{self.nodes_file}, {self.node_ref(i)}" + ("" if self.lines else " (counted from 0)")

    def node_ref(self, i):
        """'line L' (or 'point k', the file's point index) of node i."""
        return f"line {int(self.node_lines[i])}" if self.lines else f"point {int(self.node_lines[i])}"

    def ids(self, nodes):
        """Node numbers as the file gives them: the mesh's own for PyOIF's
        files, the file's point indices for meshio inputs (whose coincident
        points are merged and unused ones dropped)."""
        if self.lines:
            return np.asarray(nodes).tolist()
        return np.asarray(self.node_lines)[np.asarray(nodes)].tolist()

    def triangle_at(self, t):
        """'file, line L' (or 'file, triangle t (counted from 0 ...)') of triangle t."""
        if self.lines:
            return _where(self.triangles_file, self.triangle_lines[t])
        return f"{self.triangles_file}, triangle {int(t)} (counted from 0 among the file's triangles)"

    def triangles_named(self, ts):
        """'the triangles on line(s) L1, L2' (or 'the file's triangle(s) t1,
        t2') of several triangles."""
        if self.lines:
            return "the triangles on line(s) " + ", ".join(str(int(self.triangle_lines[t])) for t in ts)
        return "the file's triangle(s) " + ", ".join(str(int(t)) for t in ts)


def _where(path, line):
    return f"{path}, line {int(line)}"


def _read_table(path, ncols, kind, what):
    """(values, line_numbers) of a whitespace table with ncols columns;
    blank lines and '#' comments are skipped."""
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise TypeError(f"mesh input: {what} file name must be a string, got {type(path).__name__}")
    path = os.fspath(path)
    if os.path.isdir(path):
        raise ValueError(f"mesh input: {what} file '{path}' is a directory, not a file")
    if not os.path.isfile(path):
        raise ValueError(f"mesh input: {what} file '{path}' does not exist")
    rows, lines = [], []
    lineno = 0
    try:
        with open(path, "r", encoding="utf-8") as f:
            for lineno, raw in enumerate(f, start=1):
                text = raw.split("#", 1)[0].strip()
                if not text:
                    continue
                fields = text.split()
                if len(fields) != ncols:
                    raise ValueError(f"{_where(path, lineno)}: expected {ncols} {what} values, "
                                     f"got {len(fields)}: {raw.strip()!r}")
                try:
                    row = [kind(x) for x in fields]
                except ValueError:
                    raise ValueError(f"{_where(path, lineno)}: {what} values must be "
                                     f"{'integers' if kind is int else 'numbers'}: {raw.strip()!r}") from None
                if kind is int and any(abs(x) > 2**31 - 1 for x in row):
                    # node indices are int32 in the engine; a larger one is certainly wrong
                    raise ValueError(f"{_where(path, lineno)}: {what} value out of range: {raw.strip()!r}")
                rows.append(row)
                lines.append(lineno)
    except UnicodeDecodeError:
        # Python decodes in blocks, so find the offending line from the bytes
        raise ValueError(f"{_where(path, _first_undecodable_line(path))}: not UTF-8 text; {what} "
                         f"files are plain text tables") from None
    except OSError as e:
        raise ValueError(f"mesh input: cannot read {what} file '{path}': {e.strerror or e}") from None
    if not rows:
        raise ValueError(f"mesh input: {what} file '{path}' contains no data")
    return np.array(rows, dtype=np.int64 if kind is int else float), np.array(lines)


def _first_undecodable_line(path):
    with open(path, "rb") as f:
        for lineno, raw in enumerate(f, start=1):
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError:
                return lineno
    return 1  # pragma: no cover - only called after a decoding error


def from_arrays(nodes, triangles):
    """MeshData of user arrays, checked for shape, finiteness and integer
    indices (rows named in messages; the mesh checks come after)."""
    try:
        nodes = np.asarray(nodes, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("Mesh.from_arrays: 'nodes' must be an N x 3 array of numbers") from None
    if nodes.ndim != 2 or nodes.shape[1] != 3 or len(nodes) == 0:
        raise ValueError(f"Mesh.from_arrays: 'nodes' must be an N x 3 array (x, y, z per row), "
                         f"got shape {nodes.shape}")
    bad = np.nonzero(~np.all(np.isfinite(nodes), axis=1))[0]
    if bad.size:
        raise ValueError(f"Mesh.from_arrays: node {bad[0]} (row {bad[0]} of 'nodes') has non-finite "
                         f"coordinates {nodes[bad[0]].tolist()}")
    try:
        tris = np.asarray(triangles)
    except ValueError:  # ragged nested lists
        raise ValueError("Mesh.from_arrays: 'triangles' must be an M x 3 array of node indices "
                         "(every row three indices)") from None
    if tris.dtype == object or tris.ndim != 2 or tris.shape[1] != 3:
        raise ValueError(f"Mesh.from_arrays: 'triangles' must be an M x 3 array of node indices, got "
                         f"{'a ragged list' if tris.dtype == object else f'shape {tris.shape}'}")
    if tris.dtype == bool or not (np.issubdtype(tris.dtype, np.integer) or np.issubdtype(tris.dtype, np.floating)):
        raise TypeError(f"Mesh.from_arrays: 'triangles' must hold integer node indices, got dtype {tris.dtype}")
    if np.issubdtype(tris.dtype, np.floating):
        # np.loadtxt gives floats; accept them only when they are whole numbers
        bad = np.nonzero(~np.all(np.isfinite(tris) & (tris == np.round(tris)), axis=1))[0]
        if bad.size:
            raise ValueError(f"Mesh.from_arrays: triangle {bad[0]} (row {bad[0]} of 'triangles') has "
                             f"non-integer node indices {tris[bad[0]].tolist()}")
    if tris.size and np.abs(tris).max() > 2**62:
        raise ValueError("Mesh.from_arrays: 'triangles' has node indices out of range")
    return MeshData(nodes, tris.astype(np.int64))


def read_nodes(path):
    nodes, lines = _read_table(path, 3, float, "node coordinate")
    bad = np.nonzero(~np.all(np.isfinite(nodes), axis=1))[0]
    if bad.size:
        raise ValueError(f"{_where(path, lines[bad[0]])}: node coordinates must be finite")
    return nodes, lines


def read_triangles(path):
    return _read_table(path, 3, int, "triangle node index")


def read_mesh(nodes_file, triangles_file, resize=(1.0, 1.0, 1.0), check_orientation=True):
    """Read a mesh in PyOIF's format (or any format meshio reads, given as
    nodes_file with triangles_file=None), check it and return MeshData."""
    if triangles_file is None:
        data = _read_with_meshio(nodes_file)
    else:
        nodes, node_lines = read_nodes(nodes_file)
        triangles, tri_lines = read_triangles(triangles_file)
        data = MeshData(nodes, triangles, os.fspath(nodes_file), os.fspath(triangles_file),
                        node_lines, tri_lines)
    data.nodes = data.nodes * np.asarray(resize, dtype=float)
    check_mesh(data, check_orientation=check_orientation)
    return data


def _read_with_meshio(path):
    """Gmsh .msh, .stl, .off, .vtk, ... through meshio (Debian python3-meshio).
    Only triangle cells are used; STL's duplicated vertices are merged."""
    try:
        import meshio
    except ImportError:  # pragma: no cover - meshio is a dependency
        raise ValueError(f"mesh input: reading '{path}' needs meshio (Debian package python3-meshio)") from None
    path = os.fspath(path)
    if os.path.isdir(path):
        raise ValueError(f"mesh input: mesh file '{path}' is a directory, not a file")
    if not os.path.isfile(path):
        raise ValueError(f"mesh input: mesh file '{path}' does not exist")
    try:
        m = meshio.read(path)
    except SystemExit:  # some meshio readers print their complaint and sys.exit()
        raise ValueError(f"mesh input: cannot read '{path}': meshio could not parse it (its message is "
                         f"printed above)") from None
    except Exception as e:  # meshio raises many kinds
        raise ValueError(f"mesh input: cannot read '{path}': {e or type(e).__name__}") from None
    tris = [c.data for c in m.cells if c.type == "triangle"]
    if not tris:
        raise ValueError(f"mesh input: '{path}' contains no triangles")
    points = np.asarray(m.points, dtype=float)
    before = 0  # triangles in the blocks before this one
    for block in tris:  # numpy would take -1 as the last node, and fail on too large ones
        out = (block < 0) | (block >= len(points))
        if np.any(out):
            row = int(np.nonzero(out.any(axis=1))[0][0]) + before
            raise ValueError(f"mesh input: '{path}': triangle {row} (counted from 0 among the file's triangles) "
                             f"{block[row - before].tolist()} refers to a node outside 0..{len(points) - 1}")
        before += len(block)
    if points.shape[1] == 2:
        points = np.hstack([points, np.zeros((len(points), 1))])
    bad = np.nonzero(~np.all(np.isfinite(points), axis=1))[0]
    if bad.size:  # before merging: NaN keys would merge into nonsense
        raise ValueError(f"mesh input: '{path}': point {bad[0]} has non-finite coordinates "
                         f"{points[bad[0]].tolist()}; node coordinates must be finite")
    triangles = np.vstack(tris).astype(np.int64)
    # merge coincident points (STL stores every triangle's corners separately)
    scale = np.ptp(points, axis=0).max() or 1.0
    keys = np.round(points / scale * 1e9).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    used = np.unique(triangles)
    file_index = np.arange(len(points))  # per node: its point index in the file
    if len(first) != len(points) or len(used) != len(points):
        order = np.sort(first)
        remap = np.empty(len(first), dtype=np.int64)
        remap[np.argsort(first)] = np.arange(len(first))
        triangles = remap[inverse[triangles]]
        points = points[order]
        file_index = order
        used_mask = np.zeros(len(points), dtype=bool)
        used_mask[triangles.ravel()] = True
        if not used_mask.all():  # drop points no triangle uses (e.g. Gmsh geometry points)
            new_index = np.cumsum(used_mask) - 1
            triangles = new_index[triangles]
            points = points[used_mask]
            file_index = file_index[used_mask]
    return MeshData(points, triangles, path, path, node_lines=file_index, lines=False)


def edge_table(triangles):
    """Undirected edges of the triangles: (edges E x 2 with a < b,
    edge_of_halfedge 3M, halfedge i of triangle t is index 3 t + i,
    going from corner i to corner i+1)."""
    t = np.asarray(triangles)
    src = t.ravel()
    dst = t[:, [1, 2, 0]].ravel()
    lo, hi = np.minimum(src, dst), np.maximum(src, dst)
    n = int(t.max()) + 1 if t.size else 0
    keys = lo * n + hi
    uniq, inverse = np.unique(keys, return_inverse=True)
    edges = np.stack([uniq // n, uniq % n], axis=1)
    return edges, inverse.ravel()


def check_mesh(data, check_orientation=True):
    """Raise ValueError (file, line) if the mesh is not a closed orientable
    2-manifold; make triangle orientation consistent (PyOIF convention) when
    check_orientation, else only verify it."""
    nodes, tris = data.nodes, data.triangles
    nf, tf = data.nodes_file, data.triangles_file
    n = len(nodes)
    if len(tris) < 4:
        raise ValueError(f"mesh input: {tf} has {len(tris)} triangles; a closed surface needs at least 4")
    # indices in range
    bad = np.nonzero(np.any((tris < 0) | (tris >= n), axis=1))[0]
    if bad.size:
        raise ValueError(f"{data.triangle_at(bad[0])}: node index out of range 0..{n - 1} "
                         f"({nf} has {n} nodes): {tris[bad[0]].tolist()}")
    # repeated node in a triangle
    bad = np.nonzero((tris[:, 0] == tris[:, 1]) | (tris[:, 1] == tris[:, 2]) | (tris[:, 0] == tris[:, 2]))[0]
    if bad.size:
        raise ValueError(f"{data.triangle_at(bad[0])}: degenerate triangle (a node repeated): "
                         f"{data.ids(tris[bad[0]])}")
    # unused nodes
    used = np.zeros(n, dtype=bool)
    used[tris.ravel()] = True
    bad = np.nonzero(~used)[0]
    if bad.size:
        raise ValueError(f"{data.node_at(bad[0])}: node {data.ids(bad[0])} is not used by any triangle")
    edges, he_edge = edge_table(tris)
    lengths = np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1)
    h = lengths.mean()
    # duplicate nodes (coincident positions)
    order = np.lexsort(nodes.T[::-1])
    srt = nodes[order]
    close = np.nonzero(np.linalg.norm(np.diff(srt, axis=0), axis=1) <= DUPLICATE_NODE_TOLERANCE * h)[0]
    if close.size:
        i, j = sorted((order[close[0]], order[close[0] + 1]))
        raise ValueError(f"{data.node_at(j)}: node {data.ids(j)} duplicates node {data.ids(i)} "
                         f"({data.node_ref(i)}) at {nodes[i].tolist()}")
    # degenerate (zero-area) triangles
    a, b, c = nodes[tris[:, 0]], nodes[tris[:, 1]], nodes[tris[:, 2]]
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    bad = np.nonzero(areas <= DEGENERATE_AREA_TOLERANCE * h * h)[0]
    if bad.size:
        raise ValueError(f"{data.triangle_at(bad[0])}: degenerate triangle (zero area, collinear "
                         f"nodes): {data.ids(tris[bad[0]])}")
    # every edge in exactly two triangles
    counts = np.bincount(he_edge, minlength=len(edges))
    for kind, mask in (("an edge shared by more than two triangles", counts > 2),
                       ("an open edge (in only one triangle)", counts == 1)):
        bad_edges = np.nonzero(mask)[0]
        if bad_edges.size:
            e = bad_edges[0]
            hes = np.nonzero(he_edge == e)[0]
            raise ValueError(f"{data.triangle_at(hes[0] // 3)}: {kind}: edge {data.ids(edges[e])} "
                             f"({data.triangles_named(hes // 3)}); the mesh must be a closed surface")
    # duplicate triangles (same node set) are caught above as edges in >2 triangles,
    # except for a 2-triangle "pillow", excluded by len(tris) >= 4 and connectivity below.
    _check_vertex_fans(data, edges, he_edge)
    _orient(data, he_edge, check_orientation)
    _check_self_intersection(data, edges)


def _check_self_intersection(data, edges):
    """Raise ValueError if an edge passes through a triangle that does not
    share one of its nodes (the surface crosses itself). Only the pairs
    whose midpoint and centroid are close enough to touch are tested
    (a k-d tree), then a vectorised Moeller-Trumbore test."""
    from scipy.spatial import cKDTree
    nodes, tris = data.nodes, data.triangles
    a, b = nodes[edges[:, 0]], nodes[edges[:, 1]]
    corners = nodes[tris]
    centroid = corners.mean(axis=1)
    reach = 0.5 * np.linalg.norm(b - a, axis=1).max() + \
        np.linalg.norm(corners - centroid[:, None], axis=2).max()
    near = cKDTree(centroid).query_ball_point(0.5 * (a + b), reach)
    counts = np.fromiter((len(x) for x in near), dtype=np.int64, count=len(near))
    if not counts.sum():
        return
    e = np.repeat(np.arange(len(edges)), counts)
    t = np.fromiter((k for x in near for k in x), dtype=np.int64, count=int(counts.sum()))
    shares = np.any(tris[t] == edges[e, 0][:, None], axis=1) | np.any(tris[t] == edges[e, 1][:, None], axis=1)
    e, t = e[~shares], t[~shares]
    p0, d = a[e], b[e] - a[e]
    v0, e1, e2 = corners[t, 0], corners[t, 1] - corners[t, 0], corners[t, 2] - corners[t, 0]
    pv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pv)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
    ok = np.abs(det) > 1e-12 * scale  # not parallel to the triangle's plane
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    sv = p0 - v0
    u = np.einsum("ij,ij->i", sv, pv) * inv
    q = np.cross(sv, e1)
    v = np.einsum("ij,ij->i", d, q) * inv
    w = np.einsum("ij,ij->i", e2, q) * inv  # where along the edge (0..1)
    tol = 1e-9
    hit = np.nonzero(ok & (u > tol) & (v > tol) & (u + v < 1 - tol) & (w > tol) & (w < 1 - tol))[0]
    if hit.size:
        k = hit[0]
        i, j = edges[e[k]]
        raise ValueError(f"{data.triangle_at(t[k])}: the surface intersects itself: the edge between "
                         f"nodes {data.ids(i)} and {data.ids(j)} ({data.nodes_file}, {data.node_ref(i)} "
                         f"and {data.node_ref(j)}) passes through triangle {data.ids(tris[t[k]])}; the "
                         f"mesh must not cross itself")


def _check_vertex_fans(data, edges, he_edge):
    """The triangles around each node must form a single fan (no two surface
    sheets touching at a node)."""
    tris = data.triangles
    n = len(data.nodes)
    # per node: number of incident triangles must equal number of incident edges
    # (for a closed manifold a node's link is a cycle with as many edges as vertices);
    # if a node's link has several cycles the link is still balanced, so count
    # connected link cycles through a union-find on incident triangles sharing an edge.
    tri_count = np.bincount(tris.ravel(), minlength=n)
    # walk: for every node, start at one incident triangle and rotate around
    # the node through the shared edges; the fan must reach all incident triangles.
    he_of_edge = [[] for _ in range(len(edges))]
    for k, e in enumerate(he_edge):
        he_of_edge[e].append(k)
    incident = [[] for _ in range(n)]
    for t, row in enumerate(tris):
        for v in row:
            incident[v].append(t)
    for v in range(n):
        start = incident[v][0]
        seen = {start}
        t = start
        prev_edge = -1
        while True:
            row = tris[t]
            corner = int(np.nonzero(row == v)[0][0])
            # the two half-edges of t touching v: (corner-1 -> corner) and (corner -> corner+1)
            e_in = he_edge[3 * t + (corner - 1) % 3]
            e_out = he_edge[3 * t + corner]
            e_next = e_out if e_out != prev_edge else e_in
            other = [k for k in he_of_edge[e_next] if k // 3 != t]
            t_next = other[0] // 3
            prev_edge = e_next
            if t_next in seen:
                break
            seen.add(t_next)
            t = t_next
        if len(seen) != tri_count[v]:
            missing = next(x for x in incident[v] if x not in seen)
            raise ValueError(f"{data.triangle_at(missing)}: node {data.ids(v)} joins separate sheets of "
                             f"surface (its triangles do not form one fan); the mesh must be a "
                             f"2-manifold")


def _orient(data, he_edge, fix):
    """Make orientation consistent across every edge (breadth-first over
    triangles), check there is one connected surface, and choose the global
    sign so that normals (B - A) x (C - A) point inward (PyOIF convention)."""
    tris = data.triangles
    m = len(tris)
    # neighbour across each half-edge
    partner = np.empty(3 * m, dtype=np.int64)
    order = np.argsort(he_edge, kind="stable")
    pairs = order.reshape(-1, 2)
    partner[pairs[:, 0]] = pairs[:, 1]
    partner[pairs[:, 1]] = pairs[:, 0]
    src = tris.ravel()
    # same direction across an edge => inconsistent orientation
    flip = np.zeros(m, dtype=bool)
    visited = np.zeros(m, dtype=bool)
    visited[0] = True
    queue = [0]
    head = 0
    while head < len(queue):
        t = queue[head]
        head += 1
        for i in range(3):
            k = 3 * t + i
            q = partner[k]
            u = q // 3
            same_dir = src[k] == src[q]  # both half-edges start at the same node
            # effective relation once t's own flip is applied
            needs_flip = bool(same_dir) != bool(flip[t])
            if not visited[u]:
                visited[u] = True
                flip[u] = needs_flip
                queue.append(u)
            elif flip[u] != needs_flip:
                raise ValueError(f"{data.triangle_at(u)}: the surface is not orientable "
                                 f"(Moebius-like); {data.triangles_named([t, u])} "
                                 f"cannot be oriented consistently")
    if not visited.all():
        u = int(np.nonzero(~visited)[0][0])
        raise ValueError(f"{data.triangle_at(u)}: the mesh has more than one connected surface "
                         f"(this triangle is not connected to {data.triangles_named([0])})")
    if flip.any() and not fix:
        u = int(np.nonzero(flip)[0][0])
        if flip.sum() > m / 2:
            u = int(np.nonzero(~flip)[0][0])
        raise ValueError(f"{data.triangle_at(u)}: triangle {data.ids(tris[u])} is oriented "
                         f"opposite to its neighbours; pass check_orientation=True to fix it")
    new = tris.copy()
    new[flip] = new[flip][:, [0, 2, 1]]
    if signed_volume(data.nodes, new) > 0:  # outward normals: flip all to PyOIF's inward convention
        new = new[:, [0, 2, 1]]
        flip = ~flip
    data.triangles = new
    data.flipped = flip


def outward(triangles):
    """Triangles reordered so that (B - A) x (C - A) points out of the cell."""
    return np.asarray(triangles)[:, [0, 2, 1]]


def signed_volume(nodes, triangles):
    """Volume enclosed by triangles whose normals (B - A) x (C - A) point
    outward (negative for PyOIF's inward order): divergence theorem,
    V = 1/6 sum A . (B x C), with positions relative to one node so that
    a mesh far from the origin keeps its precision."""
    if len(triangles) == 0:
        return 0.0
    ref = nodes[triangles[0, 0]]
    a, b, c = (nodes[triangles[:, k]] - ref for k in range(3))
    return float(np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0) + 0.0  # + 0.0: no -0.0


def write_nodes(path, nodes, owner="mesh output"):
    """PyOIF's nodes.dat format (x y z per line); missing folders are created."""
    from .vtk import write_text, format_rows
    write_text(path, format_rows(np.asarray(nodes, dtype=float)), owner)


def write_triangles(path, triangles, owner="mesh output"):
    """PyOIF's triangles.dat format (three node indices per line)."""
    from .vtk import write_text, format_rows
    write_text(path, format_rows(np.asarray(triangles, dtype=np.int64), integer=True), owner)
