"""Quick pictures of a running simulation, with matplotlib (Agg: no display
needed), each one call that returns a ``matplotlib.figure.Figure``:

- ``geometry(system, axis="z", position=None)``: a plane of the lattice's
  boundary flags (one colour per LBBoundary) with the outlines of the
  boundaries' shapes (their zero distance);
- ``fluid(system, ...)``: a plane of the fluid's speed (or one velocity
  component) with streamlines or arrows and a colour bar;
- ``cells(system, cells, ...)``: the cells' outlines where they cut the plane
  (or their projections onto it), with their ids, coloured by a per-cell
  quantity (``"deformation"``, ``"velocity"`` or an array);
- ``snapshot_3d(system, cells, path)``: a PNG of the cells and the walls in
  3D, rendered off-screen by VTK (Debian's python3-vtk9 renders through X: a
  display or Xvfb is needed, see ``doc/visualization.md``);
- ``LiveView(system, plot=..., every=...)``: runs the integrator in chunks
  and redraws one figure in place (in a notebook), interruptible.

``units=lbmd.units.UnitSystem(...)`` labels the axes in um, velocities in
mm/s and times in ms; without it, in the engine's units.

The position of the plane is a length along `axis` (default: the box's
middle); the lattice plane shown is that of the nodes whose centres are
nearest below or at it (node i has its centre at (i + 1/2) agrid).

Under MPI every rank must call (reading the nodes and the particles is
collective); every rank builds the same figure, and ``save=PATH`` writes the
file on rank 0 only. ``ax=`` draws into an existing matplotlib Axes instead
of a new figure (the Figure returned is then that Axes' figure).
"""
import math
import numbers
import os
import shutil
import subprocess
import sys
import tempfile
import time as _wallclock

import numpy as np

_AXES = {"x": 0, "y": 1, "z": 2}
_NAMES = "xyz"
# node colours of the boundaries (index b of system.lbboundaries: colour b mod 10)
_BOUNDARY_CMAP = "tab10"
# cells without color_by: a colour per cell type (seen on white and on viridis)
_TYPE_COLOURS = ("#d62728", "#ff7f0e", "#e377c2", "#17becf", "#8c564b")


# --- arguments ----------------------------------------------------------------
def _owner_system(owner, system):
    from .system import System
    if not isinstance(system, System):
        raise TypeError(f"{owner}: parameter 'system' must be an lbmd.System, got {type(system).__name__}")
    return system


def _fluid_of(owner, system):
    fluid = system._lb_fluid()
    if fluid is None:
        raise ValueError(f"{owner}: the system has no lattice-Boltzmann fluid (system.actors.add(lbf) first)")
    return fluid


def _axis(owner, axis):
    if isinstance(axis, str) and axis.lower() in _AXES:
        return _AXES[axis.lower()]
    if isinstance(axis, numbers.Integral) and not isinstance(axis, bool) and 0 <= axis <= 2:
        return int(axis)
    raise ValueError(f"{owner}: parameter 'axis' must be 'x', 'y', 'z' (or 0, 1, 2: the plane's normal), "
                     f"got {axis!r}")


def _units(owner, units):
    from .units import UnitSystem
    if units is not None and not isinstance(units, UnitSystem):
        raise TypeError(f"{owner}: parameter 'units' must be an lbmd.units.UnitSystem or None, "
                        f"got {type(units).__name__}")
    return units


def _plane(owner, system, fluid, axis, position):
    """(node index, plane coordinate of the node centres) of the plane."""
    box = float(system.box_l[axis])
    if position is None:
        position = 0.5 * box
    if isinstance(position, bool) or not isinstance(position, numbers.Real) or not math.isfinite(position):
        raise TypeError(f"{owner}: parameter 'position' must be a finite number (a length along "
                        f"{_NAMES[axis]}), got {position!r}")
    if not 0.0 <= position <= box:
        raise ValueError(f"{owner}: parameter 'position' must be in [0, {box:g}] (the box along "
                         f"{_NAMES[axis]}), got {position:g}")
    n = fluid.shape[axis]
    agrid = float(fluid.agrid)
    index = min(n - 1, max(0, int(math.floor(position / agrid - 0.5 + 1e-9))))
    if position < 0.5 * agrid:
        index = 0
    return index, (index + 0.5) * agrid


def _in_plane(axis):
    """The two in-plane axes, in the order drawn (horizontal, vertical)."""
    return [a for a in range(3) if a != axis]


def _length_scale(units):
    """(factor from engine lengths to the axes' unit, its label)."""
    if units is None:
        return 1.0, ""
    return units.scale("m") * 1e6, " (µm)"


def _length_text(value, units):
    """A plane's coordinate as text, in um with units."""
    scale, unit = _length_scale(units)
    return f"{value * scale:.4g}" + (" µm" if unit else "")


def _velocity_scale(units):
    if units is None:
        return 1.0, "(MD units)"
    return units.scale("m/s") * 1e3, "(mm/s)"


def _time_text(system, units):
    if units is None:
        return f"t = {system.time:.6g}"
    return f"t = {units.to_si(system.time, 's') * 1e3:.4g} ms"


def _grey():
    from matplotlib.colors import ListedColormap
    return ListedColormap(["0.7"])


def _figure_size(system, axis):
    """8 inches wide, as high as the plane's aspect needs (with room for
    the title and the labels)."""
    h, v = _in_plane(axis)
    aspect = float(system.box_l[v]) / float(system.box_l[h])
    return (8.0, min(8.0, max(2.6, 6.6 * aspect + 1.3)))


def _new_axes(ax, size=(8.0, 3.6)):
    if ax is not None:
        from matplotlib.axes import Axes
        if not isinstance(ax, Axes):
            raise TypeError(f"parameter 'ax' must be a matplotlib Axes or None, got {type(ax).__name__}")
        return ax.figure, ax
    from matplotlib.figure import Figure
    fig = Figure(figsize=size, layout="constrained")
    return fig, fig.add_subplot()


def _save(owner, fig, save):
    """Write the figure (rank 0 only); the folder must exist."""
    if save is None:
        return
    if not isinstance(save, (str, os.PathLike)) or not os.fspath(save):
        raise TypeError(f"{owner}: parameter 'save' must be a file name (str or path) or None, got {save!r}")
    from . import comm, rank
    error = None
    if rank == 0:
        folder = os.path.dirname(os.path.abspath(os.fspath(save)))
        try:
            if not os.path.isdir(folder):
                raise OSError(f"{owner}: cannot write {os.fspath(save)!r}: folder {folder!r} does not exist")
            fig.savefig(save, dpi=fig.dpi)
        except (OSError, ValueError) as e:  # (ValueError: a suffix matplotlib does not know)
            error = (type(e), str(e))
    if comm.Get_size() > 1:  # the same error on every rank
        error = comm.bcast(error, root=0)
    if error is not None:
        raise error[0](error[1])


def _extent(system, axis, fluid, scale):
    h, v = _in_plane(axis)
    agrid = float(fluid.agrid)
    nh, nv = fluid.shape[h], fluid.shape[v]
    return [0.0, nh * agrid * scale, 0.0, nv * agrid * scale]


def _label_axes(ax, axis, units, title):
    h, v = _in_plane(axis)
    _, unit = _length_scale(units)
    ax.set_xlabel(_NAMES[h] + unit)
    ax.set_ylabel(_NAMES[v] + unit)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize="medium")


def _flags(fluid, axis, index):
    key = [slice(None)] * 3
    key[axis] = index
    return np.asarray(fluid[tuple(key)].boundary)


# --- boundary-flag slice and the shapes' outlines -----------------------------------
def boundary_slice(system, axis="z", position=None):
    """The boundary flags of one lattice plane (0 fluid, b + 1 for the b-th
    LBBoundary) as a 2D array indexed [horizontal, vertical] (the plane's
    two other axes in x, y, z order), with the plane's coordinate. Collective
    under MPI."""
    owner = "visualization.boundary_slice"
    system = _owner_system(owner, system)
    fluid = _fluid_of(owner, system)
    axis = _axis(owner, axis)
    index, coordinate = _plane(owner, system, fluid, axis, position)
    return _flags(fluid, axis, index), coordinate


def _shape_distance(shape, points):
    """Signed distance of the shape at each point (n x 3)."""
    dist = shape._core.calc_dist
    return np.fromiter((dist(p)[0] for p in points), dtype=float, count=len(points))


def _outline_grid(system, fluid, axis, coordinate, resolution):
    h, v = _in_plane(axis)
    box = np.asarray(system.box_l, dtype=float)
    step = float(fluid.agrid) * resolution
    gh = np.arange(0.5 * step, box[h], step)
    gv = np.arange(0.5 * step, box[v], step)
    H, V = np.meshgrid(gh, gv, indexing="ij")
    points = np.empty((H.size, 3))
    points[:, axis] = coordinate
    points[:, h] = H.ravel()
    points[:, v] = V.ravel()
    return gh, gv, points


def _draw_outlines(ax, system, fluid, axis, coordinate, scale, resolution, color="k"):
    """The zero contour of each LBBoundary's shape distance in the plane."""
    gh, gv, points = _outline_grid(system, fluid, axis, coordinate, resolution)
    contours = []
    for k, b in enumerate(system.lbboundaries):
        d = _shape_distance(b.shape, points).reshape(len(gh), len(gv))
        if d.min() > 0.0 or d.max() < 0.0:
            continue  # the shape does not cross this plane
        cs = ax.contour(gh * scale, gv * scale, d.T, levels=[0.0], colors=color, linewidths=0.8)
        from matplotlib.collections import Collection
        for art in [cs] if isinstance(cs, Collection) else cs.collections:  # matplotlib >= 3.8 / older
            art.set_gid(f"outline {k}")
        contours.append(cs)
    return contours


def geometry(system, axis="z", position=None, *, outlines=True, resolution=0.5, units=None, ax=None,
             save=None):
    """A plane of the lattice's boundary flags: fluid nodes white, the nodes
    of LBBoundary b in colour b (tab10), the shapes' outlines (their zero
    distance, sampled every `resolution` lattice spacings) in black.
    Returns the Figure; `save` writes it (rank 0)."""
    owner = "visualization.geometry"
    system = _owner_system(owner, system)
    fluid = _fluid_of(owner, system)
    axis = _axis(owner, axis)
    units = _units(owner, units)
    if isinstance(resolution, bool) or not isinstance(resolution, numbers.Real) or not 0.05 <= resolution <= 4:
        raise ValueError(f"{owner}: parameter 'resolution' must be a number in [0.05, 4] (the outlines' sampling "
                         f"step in lattice spacings), got {resolution!r}")
    index, coordinate = _plane(owner, system, fluid, axis, position)
    flags = _flags(fluid, axis, index)
    fig, ax = _new_axes(ax, _figure_size(system, axis))
    scale, unit = _length_scale(units)
    solid = np.ma.masked_equal(flags.T, 0)
    ax.imshow(solid, origin="lower", extent=_extent(system, axis, fluid, scale), cmap=_BOUNDARY_CMAP,
              vmin=0.5, vmax=10.5, interpolation="nearest")
    if outlines:
        _draw_outlines(ax, system, fluid, axis, coordinate, scale, float(resolution))
    _label_axes(ax, axis, units, f"boundaries, plane {_NAMES[axis]} = {_length_text(coordinate, units)}"
                f" ({len(system.lbboundaries)} LBBoundaries)")
    _save(owner, fig, save)
    return fig


# --- fluid ---------------------------------------------------------------------------
def fluid_slice(system, axis="z", position=None, component="magnitude"):
    """(values, in-plane velocity, flags, plane coordinate) of one lattice
    plane: values the speed ``|u|`` (or component 'x', 'y', 'z') per node,
    indexed [horizontal, vertical]; the in-plane velocity (..., 2); the
    boundary flags. Engine units; collective under MPI."""
    owner = "visualization.fluid_slice"
    system = _owner_system(owner, system)
    fluid = _fluid_of(owner, system)
    axis = _axis(owner, axis)
    if component not in ("magnitude", "x", "y", "z"):
        raise ValueError(f"{owner}: parameter 'component' must be 'magnitude', 'x', 'y' or 'z', "
                         f"got {component!r}")
    index, coordinate = _plane(owner, system, fluid, axis, position)
    key = [slice(None)] * 3
    key[axis] = index
    u = np.asarray(fluid[tuple(key)].velocity)
    flags = _flags(fluid, axis, index)
    values = np.linalg.norm(u, axis=-1) if component == "magnitude" else u[..., _AXES[component]]
    return values, u[..., _in_plane(axis)], flags, coordinate


def fluid(system, axis="z", position=None, *, component="magnitude", arrows="stream", density=1.0,
          units=None, vmin=None, vmax=None, ax=None, save=None):
    """A plane of the fluid's speed (component 'magnitude', or 'x', 'y', 'z')
    with a colour bar; boundary nodes grey; `arrows` 'stream' (streamlines
    of the in-plane velocity, `density` as matplotlib's streamplot), 'quiver'
    (an arrow every few nodes) or None. Returns the Figure."""
    owner = "visualization.fluid"
    system = _owner_system(owner, system)
    units = _units(owner, units)
    if arrows not in ("stream", "quiver", None):
        raise ValueError(f"{owner}: parameter 'arrows' must be 'stream', 'quiver' or None, got {arrows!r}")
    if isinstance(density, bool) or not isinstance(density, numbers.Real) or not 0 < density <= 10:
        raise ValueError(f"{owner}: parameter 'density' must be a number in (0, 10], got {density!r}")
    values, uv, flags, coordinate = fluid_slice(system, axis, position, component)
    axis = _axis(owner, axis)
    fl = _fluid_of(owner, system)
    fig, ax = _new_axes(ax, _figure_size(system, axis))
    scale, unit = _length_scale(units)
    vscale, vunit = _velocity_scale(units)
    shown = np.ma.masked_where(flags.T != 0, values.T * vscale)
    import matplotlib
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="0.6")
    image = ax.imshow(shown, origin="lower", extent=_extent(system, axis, fl, scale), cmap=cmap,
                      vmin=vmin, vmax=vmax, interpolation="nearest")
    name = "|u|" if component == "magnitude" else f"u_{component}"
    fig.colorbar(image, ax=ax, label=f"{name} {vunit}", shrink=0.9)
    agrid = float(fl.agrid)
    h_nodes = (np.arange(values.shape[0]) + 0.5) * agrid * scale
    v_nodes = (np.arange(values.shape[1]) + 0.5) * agrid * scale
    fluid_nodes = flags == 0
    uh = np.where(fluid_nodes, uv[..., 0], 0.0).T
    uv_ = np.where(fluid_nodes, uv[..., 1], 0.0).T
    moving = bool(np.any(uh) or np.any(uv_))
    if arrows == "stream" and moving:
        ax.streamplot(h_nodes, v_nodes, uh, uv_, density=density, color="w", linewidth=0.6, arrowsize=0.6)
    elif arrows == "quiver" and moving:
        every = max(1, int(round(max(values.shape) / 40)))
        sel = (slice(None, None, every), slice(None, None, every))
        HH, VV = np.meshgrid(h_nodes, v_nodes)
        keep = fluid_nodes.T[sel]  # no arrows (dots) on the boundary nodes
        ax.quiver(HH[sel][keep], VV[sel][keep], uh[sel][keep], uv_[sel][keep], color="w", angles="xy")
    ax.set_xlim(0, values.shape[0] * agrid * scale)
    ax.set_ylim(0, values.shape[1] * agrid * scale)
    _label_axes(ax, axis, units, f"fluid {name}, plane {_NAMES[axis]} = {_length_text(coordinate, units)}, "
                f"{_time_text(system, units)}")
    _save(owner, fig, save)
    return fig


# --- cells ------------------------------------------------------------------------------
def _check_cells(owner, cells):
    """A list of cells (lbmd.cell_registry: oif.OifCell and other cell
    models' cells), without lbmd knowing the model: what is drawn is read
    through the cell's mesh.positions(), diameter() and reference_diameter()."""
    try:
        cells = list(cells)
    except TypeError:
        raise TypeError(f"{owner}: parameter 'cells' must be a list of cells (oif.OifCell), got "
                        f"{type(cells).__name__}") from None
    for k, c in enumerate(cells):
        if not (hasattr(c, "mesh") and hasattr(c, "cell_id") and hasattr(c, "reference_diameter")):
            raise TypeError(f"{owner}: parameter 'cells' item {k} must be a cell (an oif.OifCell), got "
                            f"{type(c).__name__}")
    return cells


def cell_values(cells, color_by, units=None):
    """The per-cell quantity `color_by` names, with its label:
    'deformation' (largest node distance over the undeformed cell type's,
    D / D0), 'velocity' (speed of the mean node velocity), or an array of one
    number per cell (returned as is). Collective under MPI."""
    owner = "visualization.cell_values"
    cells = _check_cells(owner, cells)
    if isinstance(color_by, str):
        if color_by == "deformation":
            return np.array([c.diameter() / c.reference_diameter() for c in cells]), "D / D0"
        if color_by == "velocity":
            vscale, vunit = _velocity_scale(units)
            return np.array([np.linalg.norm(c.get_velocity()) * vscale for c in cells]), f"|v| {vunit}"
        raise ValueError(f"{owner}: parameter 'color_by' must be 'deformation', 'velocity', an array of one "
                         f"number per cell or None, got {color_by!r}")
    try:
        values = np.asarray(color_by, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{owner}: parameter 'color_by' must be 'deformation', 'velocity', an array of one number "
                        f"per cell or None, got {type(color_by).__name__}") from None
    if values.shape != (len(cells),):
        raise ValueError(f"{owner}: parameter 'color_by' must hold one number per cell ({len(cells)}), "
                         f"got shape {values.shape}")
    return values, "value"


def _folded(system, pos):
    """Node positions moved by whole box lengths so that the cell's centre
    lies in the box (periodic axes)."""
    box = np.asarray(system.box_l, dtype=float)
    shift = np.floor(pos.mean(axis=0) / box) * box
    shift[~np.asarray(system.periodicity, dtype=bool)] = 0.0
    return pos - shift


def _cut(pos, triangles, axis, coordinate, h, v):
    """Segments (k, 2, 2) where the triangles cross the plane."""
    d = pos[:, axis] - coordinate
    side = d[triangles] >= 0.0                      # (m, 3)
    crossing = side.any(axis=1) & ~side.all(axis=1)
    tri = triangles[crossing]
    if len(tri) == 0:
        return np.empty((0, 2, 2))
    segments = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        ia, ib = tri[:, a], tri[:, b]
        da, db = d[ia], d[ib]
        cuts = (da >= 0.0) != (db >= 0.0)
        t = np.where(cuts, da / np.where(cuts, da - db, 1.0), 0.0)
        p = pos[ia] + t[:, None] * (pos[ib] - pos[ia])
        segments.append((cuts, p[:, [h, v]]))
    # each crossing triangle has exactly two crossing edges: pair them in order
    points = np.full((len(tri), 2, 2), np.nan)
    filled = np.zeros(len(tri), dtype=int)
    for cuts, p in segments:
        rows = np.nonzero(cuts)[0]
        points[rows, filled[rows]] = p[rows]
        filled[rows] += 1
    return points[filled == 2]


def _images(system, coords, h, v):
    """Shifts (dh, dv) of the periodic images that overlap the box."""
    box = np.asarray(system.box_l, dtype=float)
    periodic = np.asarray(system.periodicity, dtype=bool)
    shifts = [(0.0, 0.0)]
    lo, hi = coords.min(axis=0), coords.max(axis=0)
    dh = [0.0] + ([box[h]] if periodic[h] and lo[0] < 0 else []) + ([-box[h]] if periodic[h] and hi[0] > box[h] else [])
    dv = [0.0] + ([box[v]] if periodic[v] and lo[1] < 0 else []) + ([-box[v]] if periodic[v] and hi[1] > box[v] else [])
    shifts = [(a, b) for a in dh for b in dv]
    return shifts


def cells(system, cells, axis="z", position=None, *, mode="slice", color_by=None, ids=True, walls=True,
          cmap="plasma", vmin=None, vmax=None, units=None, ax=None, save=None):
    """The cells in a plane: mode 'slice' draws each cell's outline where its
    membrane cuts the plane (one line collection per cell that cuts it),
    'projected' its whole membrane projected onto the plane (filled);
    `ids` writes each cell's cell_id at its centre; `color_by` 'deformation',
    'velocity', an array (one number per cell; colour bar) or None (a colour
    per cell type); `walls` shows the plane's boundary nodes in grey (slice
    mode: that plane; projected: the plane at `position`). Cells are folded
    into the box by their centre; a cell across a periodic face is drawn on
    both sides. Returns the Figure."""
    owner = "visualization.cells"
    system = _owner_system(owner, system)
    cell_list = _check_cells(owner, cells)
    axis = _axis(owner, axis)
    units = _units(owner, units)
    if mode not in ("slice", "projected"):
        raise ValueError(f"{owner}: parameter 'mode' must be 'slice' or 'projected', got {mode!r}")
    fl = _fluid_of(owner, system) if walls else system._lb_fluid()
    if fl is not None:
        index, coordinate = _plane(owner, system, fl, axis, position)
    else:
        box = float(system.box_l[axis])
        coordinate = 0.5 * box if position is None else float(position)
    values, label = (None, None) if color_by is None else cell_values(cell_list, color_by, units)
    fig, ax = _new_axes(ax, _figure_size(system, axis))
    scale, unit = _length_scale(units)
    h, v = _in_plane(axis)
    box = np.asarray(system.box_l, dtype=float)
    if walls and fl is not None:
        flags = _flags(fl, axis, index)
        ax.imshow(np.ma.masked_equal((flags.T > 0).astype(float), 0.0), origin="lower",
                  extent=_extent(system, axis, fl, scale), cmap=_grey(), vmin=0.0, vmax=1.0,
                  interpolation="nearest")
    import matplotlib
    from matplotlib.collections import LineCollection, PolyCollection
    if values is not None:
        norm = matplotlib.colors.Normalize(vmin=np.nanmin(values) if vmin is None else vmin,
                                           vmax=np.nanmax(values) if vmax is None else vmax)
        colormap = matplotlib.colormaps[cmap]
    type_colours = {}
    for k, c in enumerate(cell_list):
        pos = _folded(system, np.asarray(c.mesh.positions(), dtype=float))
        tri = np.asarray(c.mesh.triangle_ids)
        if values is not None:
            colour = colormap(norm(values[k]))
        else:
            colour = type_colours.setdefault(id(c.cell_type), _TYPE_COLOURS[len(type_colours) % len(_TYPE_COLOURS)])
        if mode == "slice":
            seg = _cut(pos, tri, axis, coordinate, h, v)
            if len(seg) == 0:
                continue
            flat = seg.reshape(-1, 2)
            parts = [seg + np.array(s) for s in _images(system, flat, h, v)]
            art = LineCollection(np.concatenate(parts) * scale, colors=[colour], linewidths=1.5,
                                 label=f"cell {c.cell_id}")
            ax.add_collection(art)
            centre = flat.mean(axis=0)
        else:
            p2 = pos[:, [h, v]]
            polys = p2[tri]
            parts = [polys + np.array(s) for s in _images(system, p2, h, v)]
            art = PolyCollection(np.concatenate(parts) * scale, facecolors=[colour], edgecolors="none",
                                 alpha=0.85, label=f"cell {c.cell_id}")
            ax.add_collection(art)
            centre = p2.mean(axis=0)
        art.set_gid(f"cell {c.cell_id}")
        if ids:
            ax.text(*(centre * scale), str(c.cell_id), fontsize=7, ha="center", va="center", color="k",
                    gid=f"id {c.cell_id}")
    if values is not None:
        mappable = matplotlib.cm.ScalarMappable(norm=norm, cmap=colormap)
        fig.colorbar(mappable, ax=ax, label=label, shrink=0.9)
    ax.set_xlim(0, box[h] * scale)
    ax.set_ylim(0, box[v] * scale)
    where = (f"cut by the plane {_NAMES[axis]} = {_length_text(coordinate, units)}" if mode == "slice"
             else f"projected along {_NAMES[axis]}")
    _label_axes(ax, axis, units, f"{len(cell_list)} cells {where}, {_time_text(system, units)}")
    _save(owner, fig, save)
    return fig


def shape_outlines(fig):
    """The shapes' outline artists of a figure made by geometry():
    {boundary index: [artists]} (gid 'outline <index>')."""
    out = {}
    for ax in fig.axes:
        for art in ax.get_children():
            gid = art.get_gid() if hasattr(art, "get_gid") else None
            if gid and gid.startswith("outline "):
                out.setdefault(int(gid.split()[1]), []).append(art)
    return out


def cell_outlines(fig):
    """The cells' artists of a figure made by cells(): {cell_id: artist}
    (their gid is 'cell <cell_id>')."""
    out = {}
    for ax in fig.axes:
        for art in ax.collections:
            gid = art.get_gid()
            if gid and gid.startswith("cell "):
                out[int(gid.split()[1])] = art
    return out


# --- 3D snapshot through VTK, off-screen -------------------------------------------------
_RENDER_CHECK = {}
_XVFB = {}


def _vtk_display_problem():
    """None if VTK can render off-screen here, else why not (checked once,
    in a child process: a failed X connection aborts the process)."""
    display = os.environ.get("DISPLAY", "")
    if display in _RENDER_CHECK:
        return _RENDER_CHECK[display]
    code = ("import vtk\nw = vtk.vtkRenderWindow()\nw.SetOffScreenRendering(1)\nr = vtk.vtkRenderer()\n"
            "w.AddRenderer(r)\nw.SetSize(8, 8)\nw.Render()\nprint(type(w).__name__)\n")
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
        problem = None if out.returncode == 0 else (out.stderr.strip().splitlines() or ["(no message)"])[-1]
    except (OSError, subprocess.TimeoutExpired) as e:
        problem = str(e)
    _RENDER_CHECK[display] = problem
    return problem


def _start_xvfb():
    """A private Xvfb display for this process (stopped at exit), or None."""
    if "display" in _XVFB:
        return _XVFB["display"]
    exe = shutil.which("Xvfb")
    _XVFB["display"] = None
    if exe is None:
        return None
    import atexit
    read, write = os.pipe()
    proc = subprocess.Popen([exe, "-displayfd", str(write), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            pass_fds=(write,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    number = b""
    with os.fdopen(read, "rb") as r:
        deadline = _wallclock.monotonic() + 20
        while not number.endswith(b"\n") and _wallclock.monotonic() < deadline:
            chunk = r.read(1)
            if not chunk:
                break
            number += chunk
    if not number.strip():
        proc.kill()
        return None
    def stop():
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
    atexit.register(stop)
    _XVFB["display"] = ":" + number.decode().strip()
    _XVFB["process"] = proc
    return _XVFB["display"]


def check_3d():
    """Make 3D snapshots possible here, or raise RuntimeError saying why:
    Debian's VTK 9.1 (python3-vtk9) draws through an X server only (no
    OSMesa, no EGL). Without DISPLAY a private Xvfb is started (Debian's
    package xvfb)."""
    import importlib.util
    if importlib.util.find_spec("vtk") is None:
        raise RuntimeError("visualization.snapshot_3d needs VTK: install Debian's python3-vtk9")
    if not os.environ.get("DISPLAY"):
        display = _start_xvfb()
        if display is None:
            raise RuntimeError(
                "visualization.snapshot_3d: no display to render on. Debian's VTK 9.1 (python3-vtk9) renders "
                "through X only (it is built without OSMesa and EGL off-screen support), DISPLAY is not set and "
                "Xvfb is not installed: install Debian's xvfb (apt install xvfb; PyOIF then starts a virtual "
                "display itself), or run under xvfb-run, or set DISPLAY to an X server")
        os.environ["DISPLAY"] = display
    problem = _vtk_display_problem()
    if problem is not None:
        raise RuntimeError(f"visualization.snapshot_3d: VTK cannot render off-screen on DISPLAY="
                           f"{os.environ.get('DISPLAY')!r}: {problem}. Debian's VTK 9.1 renders through X only: set "
                           "DISPLAY to a working X server or unset it with Debian's xvfb installed")


def _cells_polydata(vtk, system, cell_list, positions, values):
    points = vtk.vtkPoints()
    polys = vtk.vtkCellArray()
    scalars = vtk.vtkDoubleArray()
    scalars.SetName("value")
    offset = 0
    for k, c in enumerate(cell_list):
        pos = _folded(system, positions[k])
        for p in pos:
            points.InsertNextPoint(*p)
            scalars.InsertNextValue(values[k])
        for t in np.asarray(c.mesh.triangle_ids):
            polys.InsertNextCell(3)
            for i in t:
                polys.InsertCellPoint(int(i) + offset)
        offset += len(pos)
    data = vtk.vtkPolyData()
    data.SetPoints(points)
    data.SetPolys(polys)
    data.GetPointData().SetScalars(scalars)
    return data


def snapshot_3d(system, cells=(), path="snapshot.png", *, color_by=None, walls=True, size=(1000, 600),
                azimuth=-30.0, elevation=35.0, units=None):
    """A PNG of the cells (coloured by `color_by`: as in cells(); default one
    colour) and the walls (the boundary nodes' surface, translucent) in 3D,
    rendered off-screen by VTK; returns the path (written by rank 0; every
    rank must call: the queries are collective). Raises RuntimeError with
    what to install where VTK cannot render (see check_3d)."""
    owner = "visualization.snapshot_3d"
    system = _owner_system(owner, system)
    cell_list = _check_cells(owner, cells)
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path).lower().endswith(".png"):
        raise ValueError(f"{owner}: parameter 'path' must be a file name ending in .png, got {path!r}")
    path = os.fspath(path)
    try:
        width, height = (int(s) for s in size)
        if not (16 <= width <= 8192 and 16 <= height <= 8192):
            raise ValueError
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: parameter 'size' must be (width, height) in pixels, 16..8192, got {size!r}") \
            from None
    values = (np.zeros(len(cell_list)), None) if color_by is None else cell_values(cell_list, color_by, units)
    fl = system._lb_fluid() if walls else None
    # the collective queries, on every rank, before rank 0 draws alone
    flags = fl[:, :, :].boundary if fl is not None else None
    positions = [np.asarray(c.mesh.positions(), dtype=float) for c in cell_list]
    # rank 0 alone checks and draws; its error, if any, is raised on every rank
    from . import comm, rank
    error = None
    if rank == 0:
        try:
            folder = os.path.dirname(os.path.abspath(path))
            if not os.path.isdir(folder):
                raise OSError(f"{owner}: cannot write {path!r}: folder {folder!r} does not exist")
            check_3d()
            _render(system, cell_list, positions, flags, fl, values, color_by, path, width, height, azimuth,
                    elevation)
        except (OSError, RuntimeError) as e:
            error = (type(e), str(e))
    if comm.Get_size() > 1:
        error = comm.bcast(error, root=0)
    if error is not None:
        raise error[0](error[1])
    return path


def _render(system, cell_list, positions, flags, fl, values, color_by, path, width, height, azimuth, elevation):
    import vtk
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    if cell_list:
        data = _cells_polydata(vtk, system, cell_list, positions, values[0])
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputData(data)
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        if color_by is None:
            mapper.ScalarVisibilityOff()
            actor.GetProperty().SetColor(0.8, 0.1, 0.15)
        else:
            lo, hi = float(np.nanmin(values[0])), float(np.nanmax(values[0]))
            mapper.SetScalarRange(lo, hi if hi > lo else lo + 1e-12)
            bar = vtk.vtkScalarBarActor()
            bar.SetLookupTable(mapper.GetLookupTable())
            bar.SetTitle(values[1])
            bar.GetTitleTextProperty().SetColor(0, 0, 0)
            bar.GetLabelTextProperty().SetColor(0, 0, 0)
            bar.SetWidth(0.08)
            bar.SetLabelFormat("%.4g")
            renderer.AddActor2D(bar)
        renderer.AddActor(actor)
    if flags is not None and np.any(flags):
        from .vtk_output import wall_surface
        surface = wall_surface(fl, boundary=flags)
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputData(surface)
        mapper.ScalarVisibilityOff()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetColor(0.55, 0.6, 0.7)
        actor.GetProperty().SetOpacity(0.35)
        renderer.AddActor(actor)
    outline = vtk.vtkOutlineSource()
    box = np.asarray(system.box_l, dtype=float)
    outline.SetBounds(0, box[0], 0, box[1], 0, box[2])
    om = vtk.vtkPolyDataMapper()
    om.SetInputConnection(outline.GetOutputPort())
    oa = vtk.vtkActor()
    oa.SetMapper(om)
    oa.GetProperty().SetColor(0.2, 0.2, 0.2)
    renderer.AddActor(oa)
    camera = renderer.GetActiveCamera()
    camera.SetFocalPoint(*(0.5 * box))
    camera.SetPosition(*(0.5 * box + np.array([0.0, -1.0, 0.0])))
    camera.SetViewUp(0, 0, 1)
    camera.Azimuth(azimuth)
    camera.Elevation(elevation)
    renderer.ResetCamera()
    camera.Zoom(1.3)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(width, height)
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    with tempfile.NamedTemporaryFile(suffix=".png", dir=os.path.dirname(os.path.abspath(path)),
                                     delete=False) as tmp:
        pass
    writer.SetFileName(tmp.name)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    window.Finalize()
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp.name, 0o666 & ~mask)  # a temporary file is private; the picture is not
    os.replace(tmp.name, path)


# --- live view --------------------------------------------------------------------------
def _in_notebook():
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and hasattr(shell, "kernel")


class LiveView:
    """Run the integrator in chunks of `every` steps and redraw one figure
    after each: ``LiveView(system, plot=visualization.fluid, every=200,
    units=None, plot_args={}, save=None, callback=None, display=None)``,
    then ``view.run(n_steps)``.

    `plot` is one of this module's pictures (or any function
    ``plot(system, ax=ax, **plot_args)`` that draws into `ax`), e.g.
    ``plot=lambda s, ax: visualization.cells(s, my_cells, ax=ax)``. In a
    notebook the figure is shown once and updated in place (IPython display
    handle); elsewhere a line per chunk is printed (display='print', the
    default outside a notebook) or nothing (display='none'); `save` writes
    each frame to that PNG (rank 0). The title shows the simulated time and
    the steps per second (wall clock, the drawing included).

    The notebook's stop button (or Ctrl-C) stops the run: the engine stops
    at the next 16-step boundary, in a consistent state (on one MPI rank;
    under mpirun Ctrl-C ends the job), or between chunks if the interrupt
    comes while drawing; ``run`` then redraws, says how many steps ran and
    returns that number (``view.interrupted`` is True). `callback(view)`
    is called after each chunk (a KeyboardInterrupt from it stops the same
    way)."""

    def __init__(self, system, plot=None, every=100, *, units=None, plot_args=None, save=None, callback=None,
                 display=None, size=None):
        owner = "visualization.LiveView"
        self.system = _owner_system(owner, system)
        if isinstance(every, bool) or not isinstance(every, numbers.Integral) or every < 1:
            raise ValueError(f"{owner}: parameter 'every' must be an integer >= 1 (steps per redraw), got {every!r}")
        if plot is None:
            plot = fluid
        if not callable(plot):
            raise TypeError(f"{owner}: parameter 'plot' must be a function plot(system, ax=..., **plot_args), "
                            f"got {type(plot).__name__}")
        if callback is not None and not callable(callback):
            raise TypeError(f"{owner}: parameter 'callback' must be callable or None, got {type(callback).__name__}")
        if display not in (None, "notebook", "print", "none"):
            raise ValueError(f"{owner}: parameter 'display' must be 'notebook', 'print', 'none' or None (automatic), "
                             f"got {display!r}")
        self.plot = plot
        self.every = int(every)
        self.units = _units(owner, units)
        self.plot_args = dict(plot_args or {})
        if plot in (fluid, geometry, cells) or getattr(plot, "__module__", None) == __name__:
            self.plot_args.setdefault("units", self.units)
        self.save = save
        self.callback = callback
        self.display = display or ("notebook" if _in_notebook() else "print")
        from matplotlib.figure import Figure
        if size is None:
            size = _figure_size(self.system, _axis(owner, self.plot_args.get("axis", "z")))
        self.figure = Figure(figsize=size, layout="constrained")
        self._handle = None
        self.steps_done = 0
        self.interrupted = False
        self.rate = float("nan")

    def draw(self, note=""):
        """Redraw the figure now (collective under MPI) and show it."""
        self.figure.clf()
        ax = self.figure.add_subplot()
        self.plot(self.system, ax=ax, **self.plot_args)
        rate = "" if not math.isfinite(self.rate) else f", {self.rate:.0f} steps/s"
        self.figure.suptitle(f"{_time_text(self.system, self.units)}, step {self.system.step_count}{rate}{note}",
                             fontsize="medium")
        _save("LiveView", self.figure, self.save)
        self._show()

    def _show(self):
        from . import rank
        if rank != 0:
            return
        if self.display == "notebook":
            import io
            from IPython.display import Image, display
            buffer = io.BytesIO()
            self.figure.savefig(buffer, format="png", dpi=self.figure.dpi)
            image = Image(data=buffer.getvalue(), format="png")
            if self._handle is None:
                self._handle = display(image, display_id=True)
            else:
                self._handle.update(image)

    def _say(self, text):
        from . import rank
        if rank == 0 and self.display == "print":
            print(text, flush=True)

    def run(self, n_steps):
        """Integrate n_steps in chunks of `every`, redrawing after each;
        returns the number of steps run (fewer if interrupted)."""
        if isinstance(n_steps, bool) or not isinstance(n_steps, numbers.Integral) or n_steps < 0:
            raise ValueError(f"LiveView.run: parameter 'n_steps' must be an integer >= 0, got {n_steps!r}")
        system = self.system
        start_step = system.step_count
        self.interrupted = False
        started = _wallclock.monotonic()
        try:
            if self._handle is None:
                self.draw()
            while system.step_count - start_step < n_steps:
                chunk = min(self.every, n_steps - (system.step_count - start_step))
                system.integrator.run(chunk)
                elapsed = _wallclock.monotonic() - started
                self.rate = (system.step_count - start_step) / elapsed if elapsed > 0 else float("nan")
                self.draw()
                self._say(f"{_time_text(system, self.units)}, step {system.step_count}, {self.rate:.0f} steps/s")
                if self.callback is not None:
                    self.callback(self)
        except KeyboardInterrupt:
            self.interrupted = True
        done = system.step_count - start_step
        self.steps_done += done
        if self.interrupted:
            message = f"interrupted after {done} of {n_steps} steps (the system is at step {system.step_count})"
            try:
                self.draw(note=" (interrupted)")
            except KeyboardInterrupt:
                pass
            from . import rank
            if rank == 0:
                print(f"LiveView: {message}", flush=True)
        return done
