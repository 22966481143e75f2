"""Readers of 2D layouts (photomask drawings) for :class:`lbmd.shapes.Extrusion`:
DXF (ezdxf), SVG (svgelements) and black-and-white images (PIL). Each
returns (polygons, names): a list of (N, 2) vertex arrays and, for error
messages, what each polygon came from (entity, element or pixel region).

Errors name the file: OSError when it is missing or cannot be opened,
ValueError when it is not of the format, holds no closed contour, or holds a
piece that closes no contour.
"""
import collections
import math
import os

import numpy as np

from .validation import real_number


def _source(owner, path):
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{owner}: parameter 'path' must be a file name, got {type(path).__name__}")
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{owner}: no such file '{path}'")
    if not os.access(path, os.R_OK):
        raise PermissionError(f"{owner}: cannot read '{path}' (permission denied)")
    return path


def _placement(owner, scale, tolerance, origin):
    scale = real_number(f"{owner}: parameter 'scale'", scale, "pos")
    if tolerance is not None:
        tolerance = real_number(f"{owner}: parameter 'tolerance'", tolerance, "pos")
    try:
        origin = np.array(origin, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{owner}: parameter 'origin' must be 2 numbers (x, y), got {origin!r}") from None
    if origin.shape != (2,) or not np.all(np.isfinite(origin)):
        raise ValueError(f"{owner}: parameter 'origin' must be 2 finite numbers (x, y), got {origin!r}")
    return scale, tolerance, origin


def _drop_closing(points):
    """An (N, 2) array without the last vertex where it repeats the first (to
    rounding: a full ellipse's end is 1e-15 off its start)."""
    points = np.asarray(points, dtype=float)
    extent = np.ptp(points, axis=0).max() if len(points) else 0.0
    if len(points) > 1 and np.linalg.norm(points[0] - points[-1]) <= 1e-12 * extent:
        points = points[:-1]
    return points


def _chain(owner, path, pieces, snap, hint=""):
    """Closed loops made of open pieces [(points, name)] whose ends meet
    (within `snap`); ValueError naming the piece that closes no loop."""
    loops, names = [], []
    unused = list(pieces)
    while unused:
        points, name = unused.pop(0)
        chain, members = [np.asarray(points)], [name]
        while np.linalg.norm(chain[-1][-1] - chain[0][0]) > snap:
            end = chain[-1][-1]
            for k, (p, n) in enumerate(unused):
                p = np.asarray(p)
                if np.linalg.norm(p[0] - end) <= snap:
                    chain.append(p[1:])
                elif np.linalg.norm(p[-1] - end) <= snap:
                    chain.append(p[::-1][1:])
                else:
                    continue
                members.append(n)
                unused.pop(k)
                break
            else:
                raise ValueError(f"{owner}: '{path}': {name} is not part of a closed contour: the "
                                 f"chain through it ends at ({end[0]:.6g}, {end[1]:.6g}), which meets "
                                 f"no other piece{hint}")
        loop = np.concatenate(chain)
        loops.append(loop[:-1] if len(loop) > 1 else loop)  # the last point closes onto the first
        shown = ", ".join(members[:3]) + (f" and {len(members) - 3} more" if len(members) > 3 else "")
        names.append(f"the loop of {shown}")
    return loops, names


# --- DXF ----------------------------------------------------------------------
_DXF_TYPES = {"LWPOLYLINE", "POLYLINE", "CIRCLE", "ARC", "LINE", "ELLIPSE", "SPLINE"}


def read_dxf(path, layer=None, scale=1.0, tolerance=0.01, origin=(0.0, 0.0)):
    owner = "Extrusion.from_dxf"
    path = _source(owner, path)
    scale, tolerance, origin = _placement(owner, scale, tolerance, origin)
    if layer is not None and not isinstance(layer, str):
        raise TypeError(f"{owner}: parameter 'layer' must be a layer name or None, got {layer!r}")
    import ezdxf
    from ezdxf import path as dxf_path
    try:
        doc = ezdxf.readfile(path)
    except (IOError, ezdxf.DXFError) as e:  # ezdxf: IOError for a file that is not DXF
        raise ValueError(f"{owner}: '{path}' is not a readable DXF file: {e}") from None

    def entities(container):
        for e in container:
            if e.dxftype() == "INSERT":  # a block reference: its entities, placed
                yield from entities(e.virtual_entities())
            else:
                yield e

    loops, names, pieces = [], [], []
    skipped = collections.Counter()
    for e in entities(doc.modelspace()):
        kind = e.dxftype()
        if layer is not None and e.dxf.get("layer", "0") != layer:
            continue
        if kind not in _DXF_TYPES:
            skipped[kind] += 1
            continue
        name = f"{kind} (handle {e.dxf.get('handle', '?')}, layer '{e.dxf.get('layer', '0')}')"
        try:
            p = dxf_path.make_path(e)
        except (TypeError, ValueError, ezdxf.DXFError) as err:
            raise ValueError(f"{owner}: '{path}': {name} cannot be read: {err}") from None
        # ezdxf 0.18's paths approximate arcs by Bezier curves (2.7e-4 radius
        # off, whatever the tolerance) and mistake a closed spline's knots:
        # curves are flattened from the entities themselves
        if kind in ("CIRCLE", "ARC"):
            flat = [list(e.flattening(tolerance))]
        elif kind == "ELLIPSE":
            flat = [list(e.flattening(tolerance, segments=16))]
        elif kind == "SPLINE":
            flat = [list(e.construction_tool().flattening(tolerance, segments=16))]
        elif kind == "LWPOLYLINE" or (kind == "POLYLINE" and e.is_2d_polyline):
            flat = [_polyline_with_bulges(e, tolerance)]
        else:
            flat = [list(sub.flattening(tolerance, segments=16)) for sub in p.sub_paths()]
        for points in flat:
            pts = np.array([(v.x, v.y) for v in points], dtype=float)
            if len(pts) < 2:
                continue
            closed = getattr(e, "closed", False) or getattr(e, "is_closed", False) \
                or (kind != "LINE" and len(pts) > 2 and np.linalg.norm(pts[0] - pts[-1]) <= tolerance)
            if closed:
                loops.append(_drop_closing(pts))
                names.append(name)
            else:
                pieces.append((pts, name))
    chained, chain_names = _chain(owner, path, pieces, tolerance,
                                  " (pass layer=... to read only the layout's layer)")
    loops += chained
    names += chain_names
    if not loops:
        where = f" on layer '{layer}'" if layer is not None else ""
        found = ", ".join(f"{n} {k}" for k, n in skipped.items()) or "no drawing entities"
        raise ValueError(f"{owner}: '{path}' holds no closed contour{where} (found {found}; read are "
                         f"{', '.join(sorted(_DXF_TYPES))})")
    return [loop * scale + origin for loop in loops], names


def _polyline_with_bulges(e, tolerance):
    """The vertices of a 2D (LW)POLYLINE in WCS, each bulge (an arc of
    included angle 4 atan(bulge), counter-clockwise when positive) flattened
    with points on the arc, no chord farther than tolerance from it."""
    if e.dxftype() == "LWPOLYLINE":
        raw = [(x, y, b) for x, y, b in e.get_points("xyb")]
        closed, elevation = e.closed, e.dxf.get("elevation", 0.0)
    else:
        raw = [(v.dxf.location.x, v.dxf.location.y, v.dxf.get("bulge", 0.0)) for v in e.vertices]
        closed, elevation = e.is_closed, e.dxf.get("elevation", (0, 0, 0))[2]
    out = []
    count = len(raw) if closed else len(raw) - 1
    for k in range(count):
        x0, y0, bulge = raw[k]
        x1, y1, _ = raw[(k + 1) % len(raw)]
        out.append((x0, y0))
        chord = math.hypot(x1 - x0, y1 - y0)
        if bulge == 0 or chord == 0:
            continue
        theta = 4 * math.atan(bulge)
        r = chord / (2 * abs(math.sin(theta / 2)))
        offset = 0.5 * chord / math.tan(theta / 2)  # from the chord's midpoint, to its left
        cx = 0.5 * (x0 + x1) - offset * (y1 - y0) / chord
        cy = 0.5 * (y0 + y1) + offset * (x1 - x0) / chord
        step = 2 * math.acos(1 - tolerance / r) if tolerance < r else math.pi
        n = max(1, math.ceil(abs(theta) / step))
        a0 = math.atan2(y0 - cy, x0 - cx)
        out += [(cx + r * math.cos(a0 + theta * i / n), cy + r * math.sin(a0 + theta * i / n))
                for i in range(1, n)]
    if not closed:
        out.append(raw[-1][:2])
    from ezdxf.math import Vec3
    return list(e.ocs().points_to_wcs(Vec3(x, y, elevation) for x, y in out))


# --- SVG ----------------------------------------------------------------------
def _flatten_svg_segment(seg, tolerance):
    """Points after the segment's start, no farther than tolerance from it."""
    import svgelements as se
    end = np.array([seg.end.x, seg.end.y])
    if isinstance(seg, (se.Line, se.Close)):
        return [end]
    if isinstance(seg, (se.QuadraticBezier, se.CubicBezier)):
        ctrl = [np.array([q.x, q.y]) for q in
                ([seg.start, seg.control, seg.end] if isinstance(seg, se.QuadraticBezier)
                 else [seg.start, seg.control1, seg.control2, seg.end])]
        # n uniform steps leave at most max|B''| / (8 n^2) between curve and chords
        m = len(ctrl) - 1
        second = max(np.linalg.norm(ctrl[i] - 2 * ctrl[i + 1] + ctrl[i + 2]) for i in range(m - 1))
        n = max(1, math.ceil(math.sqrt(m * (m - 1) * second / (8 * tolerance))))
    elif isinstance(seg, se.Arc):
        # the same bound with |B''| <= the larger radius times sweep^2 (n steps)
        r = max(abs(seg.rx), abs(seg.ry))
        n = max(1, math.ceil(abs(seg.sweep) * math.sqrt(r / (8 * tolerance))))
    else:
        return [end]
    pts = [np.array([q.x, q.y]) for q in (seg.point(t) for t in np.linspace(0, 1, n + 1)[1:-1])]
    return pts + [end]


def read_svg(path, scale=1.0, tolerance=0.01, origin=(0.0, 0.0)):
    owner = "Extrusion.from_svg"
    path = _source(owner, path)
    scale, tolerance, origin = _placement(owner, scale, tolerance, origin)
    import svgelements as se
    import xml.etree.ElementTree as ET
    try:
        svg = se.SVG.parse(path)
    except OSError as e:
        raise OSError(f"{owner}: cannot read '{path}': {e}") from None
    except (ET.ParseError, ValueError) as e:
        raise ValueError(f"{owner}: '{path}' is not a readable SVG file: {e}") from None
    # svgelements maps the viewBox onto the viewport (px at 96 per inch): undo
    # that, so that coordinates are the drawing's user units; y is flipped
    # about the viewBox (or the viewport) so that its bottom edge is y = 0
    vb = svg.viewbox
    to_user = ~se.Matrix(svg.viewbox_transform) if vb is not None and svg.viewbox_transform else None
    height = (vb.y + vb.height) if vb is not None else (float(svg.height) if svg.height is not None else 0.0)
    if to_user is not None:  # the tolerance in px, where the curves are flattened
        to_px = se.Matrix(svg.viewbox_transform)
        tolerance_px = tolerance * min(math.hypot(to_px.a, to_px.b), math.hypot(to_px.c, to_px.d))
    else:
        tolerance_px = tolerance
    loops, names, pieces = [], [], []
    for k, el in enumerate(svg.elements()):
        if not isinstance(el, se.Shape):
            continue
        tag = el.values.get("tag") or type(el).__name__.lower()
        ident = el.values.get("id") if hasattr(el, "values") else None
        name = f"<{tag}>" + (f" id='{ident}'" if ident else f" (element {k})")
        p = el if isinstance(el, se.Path) else se.Path(el)
        for sub in p.as_subpaths():
            sub = se.Path(sub)
            pts, closed = [], False
            for seg in sub:
                if isinstance(seg, se.Move):
                    pts = [np.array([seg.end.x, seg.end.y])]
                    continue
                if not pts:
                    pts = [np.array([seg.start.x, seg.start.y])]
                pts += _flatten_svg_segment(seg, tolerance_px)
                closed = closed or isinstance(seg, se.Close)
            if len(pts) < 2:
                continue
            pts = np.array(pts)
            if to_user is not None:
                pts = np.array([tuple(to_user.point_in_matrix_space(tuple(q))) for q in pts], dtype=float)
            pts[:, 1] = height - pts[:, 1]  # SVG's y points down
            if closed or isinstance(el, (se.Rect, se.Circle, se.Ellipse, se.Polygon)) or (
                    len(pts) > 2 and np.linalg.norm(pts[0] - pts[-1]) <= tolerance):
                loops.append(_drop_closing(pts))
                names.append(name)
            else:
                pieces.append((pts, name))
    chained, chain_names = _chain(owner, path, pieces, tolerance)
    loops += chained
    names += chain_names
    if not loops:
        raise ValueError(f"{owner}: '{path}' holds no closed contour (read are closed paths and "
                         "subpaths, rect, circle, ellipse, polygon, and polylines or paths whose ends meet)")
    return [loop * scale + origin for loop in loops], names


# --- black-and-white masks -------------------------------------------------------
def read_mask(path, pixel_size, threshold=0.5, solid="black", origin=(0.0, 0.0)):
    owner = "Extrusion.from_mask"
    path = _source(owner, path)
    pixel_size = real_number(f"{owner}: parameter 'pixel_size'", pixel_size, "pos")
    threshold = real_number(f"{owner}: parameter 'threshold'", threshold,
                            (lambda t: 0 < t <= 1, "in (0, 1]"))
    if solid not in ("black", "white"):
        raise ValueError(f"{owner}: parameter 'solid' must be 'black' or 'white', got {solid!r}")
    _, _, origin = _placement(owner, 1.0, None, origin)
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as img:
            if img.mode in ("RGBA", "LA", "PA") or "transparency" in img.info:
                # transparent pixels count as white (the page), not as their colour
                rgba = img.convert("RGBA")
                img = Image.alpha_composite(Image.new("RGBA", rgba.size, (255, 255, 255, 255)), rgba)
            grey = np.asarray(img.convert("L"), dtype=float) / 255.0
    except UnidentifiedImageError:
        raise ValueError(f"{owner}: '{path}' is not a readable image") from None
    except OSError as e:
        raise OSError(f"{owner}: cannot read '{path}': {e}") from None
    black = grey < threshold
    mask = (black if solid == "black" else ~black)[::-1]  # row 0 at the bottom: y up
    if not mask.any():
        raise ValueError(f"{owner}: '{path}' holds no closed contour: no {solid} pixel "
                         f"(grey level below {threshold} * 255 is black)")
    polygons, names = [], []
    for loop in trace_pixel_regions(mask):
        polygons.append(loop * pixel_size + origin)
        x, y = loop[0]
        names.append(f"the outline through the pixel corner at column {int(x)}, row "
                     f"{mask.shape[0] - int(y)} from the top")
    return polygons, names


def trace_pixel_regions(mask):
    """Outlines of the True pixels of a 2D boolean array (row index = y, pixel
    (j, i) covering [i, i+1] x [j, j+1]) along the pixel edges, each with the
    region on its left (outer outlines counter-clockwise, holes clockwise),
    corners only. Diagonal neighbours belong to separate regions: at a vertex
    where they meet, an outline turns left."""
    m = np.pad(np.asarray(mask, dtype=bool), 1)
    solid = m[1:-1, 1:-1]
    j, i = np.nonzero(solid & ~m[:-2, 1:-1])          # nothing below: bottom edge, +x
    starts = [np.stack([i, j], 1)]
    dirs = [np.zeros(len(i), int)]
    j, i = np.nonzero(solid & ~m[1:-1, 2:])           # right edge, +y
    starts.append(np.stack([i + 1, j], 1))
    dirs.append(np.full(len(i), 1))
    j, i = np.nonzero(solid & ~m[2:, 1:-1])           # top edge, -x
    starts.append(np.stack([i + 1, j + 1], 1))
    dirs.append(np.full(len(i), 2))
    j, i = np.nonzero(solid & ~m[1:-1, :-2])          # left edge, -y
    starts.append(np.stack([i, j + 1], 1))
    dirs.append(np.full(len(i), 3))
    start = np.concatenate(starts)
    direction = np.concatenate(dirs)
    step = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]])
    end = start + step[direction]
    outgoing = collections.defaultdict(list)
    for k, (x, y) in enumerate(start.tolist()):
        outgoing[(x, y)].append(k)
    used = np.zeros(len(start), bool)
    end_list = end.tolist()
    loops = []
    for first in range(len(start)):
        if used[first]:
            continue
        corners = []
        k = first
        while True:
            used[k] = True
            options = outgoing[tuple(end_list[k])]
            if len(options) == 1:
                nxt = options[0]
            else:  # a pinch: turn left (the same pixel), else go straight
                turn = {(direction[o] - direction[k]) % 4: o for o in options}
                nxt = turn.get(1, turn.get(0, turn.get(3)))
            if direction[nxt] != direction[k]:
                corners.append(end_list[k])
            k = nxt
            if k == first:
                break
        loops.append(np.array(corners, dtype=float))
    return loops
