"""VTK XML output of the lattice-Boltzmann fluid and of its walls for
ParaView, through Debian's VTK library (package python3-vtk9):

- ``FluidSeries(path, fluid, fields=("velocity", "density"), slice=None)``:
  one ``.vti`` (vtkImageData) per ``write(time)`` and a ``.pvd`` collection
  listing every step with its time;
- ``write_wall_surface(path, fluid)``: the wall surface as a ``.vtp``
  triangle mesh, extracted from the boundary flags of the nodes.

Under MPI every rank calls (reading the nodes is collective); rank 0 alone
writes. Every file is written under a temporary name and renamed over the
final one (``lbmd.file_output``), and the ``.pvd`` is rewritten after each
complete step, so ParaView can open it at any time of a run. See doc/lb.md.
"""
import math
import numbers
import os
from xml.sax.saxutils import quoteattr

import numpy as np

from . import file_output

#: point-data arrays FluidSeries can write, with what they hold
FIELDS = {
    "velocity": "fluid velocity u of the node (3 components, MD units)",
    "density": "fluid mass density rho of the node (MD units)",
    "boundary": "boundary flag of the node: 0 fluid, b + 1 for the b-th LBBoundary",
}

_AXES = {"x": 0, "y": 1, "z": 2}


def import_vtk(owner):
    try:
        import vtk
        from vtk.util import numpy_support
    except ImportError as e:  # pragma: no cover - python3-vtk9 is a dependency
        raise ImportError(f"{owner} needs the VTK Python bindings (Debian package python3-vtk9): {e}") from None
    return vtk, numpy_support


def check_path(owner, path, suffix, example="out/fluid"):
    """path as a string ending in suffix (appended when missing); TypeError or
    ValueError naming owner's parameter 'path' otherwise."""
    if path is None:
        raise TypeError(f"{owner}: missing required parameter 'path' (a {suffix} file name)")
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise TypeError(f"{owner}: parameter 'path' must be a file name string, got {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str) or not path or path.endswith(("/", os.sep)) or "\0" in path:
        raise ValueError(f"{owner}: parameter 'path' must name a {suffix} file (e.g. '{example}{suffix}'), "
                         f"got {path!r}")
    return path if path.endswith(suffix) else path + suffix


def _check_fluid(owner, fluid):
    from .lb import LBFluid
    if not isinstance(fluid, LBFluid):
        raise TypeError(f"{owner}: parameter 'fluid' must be an lbmd.lb.LBFluid, got {type(fluid).__name__}")
    if fluid._core is None:
        raise RuntimeError(f"{owner}: the fluid is not active; add it to a system first (system.actors.add(lbf))")
    return fluid


def write_xml(owner, writer, data, path):
    """Write a VTK data set with an XML writer (appended binary blocks after
    the XML header, zlib, 64-bit headers so blocks over 4 GB stay readable)
    under a temporary name, renamed over path (writing rank only)."""

    def write_to(tmp):
        writer.SetFileName(tmp)
        writer.SetInputData(data)
        writer.SetDataModeToAppended()
        writer.SetCompressorTypeToZLib()
        writer.SetHeaderTypeToUInt64()
        if writer.Write() != 1:
            raise OSError(f"{type(writer).__name__} failed (error code {writer.GetErrorCode()})")

    file_output.replace_atomically(path, owner, write_to)


def collection_text(steps):
    """The ``.pvd`` XML of the steps [(time, file name relative to the .pvd)]."""
    rows = "".join(f'    <DataSet timestep={quoteattr(repr(t))} group="" part="0" file={quoteattr(f)}/>\n'
                   for t, f in steps)
    return ('<?xml version="1.0"?>\n'
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}  </Collection>\n</VTKFile>\n")


def check_names(owner, parameter, value, accepted, allow_empty=True):
    """value (a name, a sequence of names or None) as a tuple of names out of
    accepted, each once; errors name owner's parameter and the accepted names."""
    if isinstance(value, str) or value is None:
        value = () if value is None else (value,)
    try:
        names = list(value)
    except TypeError:
        raise TypeError(f"{owner}: parameter '{parameter}' must be a sequence of names out of "
                        f"{', '.join(accepted)}, got {value!r}") from None
    bad = [n for n in names if not isinstance(n, str) or n not in accepted]
    if bad:
        raise ValueError(f"{owner}: parameter '{parameter}' has unknown name(s) {bad!r}; accepted names: "
                         f"{', '.join(accepted)}")
    if not names and not allow_empty:
        raise ValueError(f"{owner}: parameter '{parameter}' is empty; name at least one of {', '.join(accepted)}")
    if len(set(names)) != len(names):
        raise ValueError(f"{owner}: parameter '{parameter}' names an entry twice: {names!r}")
    return tuple(names)


class TimeSeries:
    """A ``.pvd`` collection of VTK XML files, one per step, written beside
    it as ``<stem>_<k>.<suffix>`` (six digits, from 0). The ``.pvd`` is
    rewritten (write then rename) after each step, so it only ever lists
    complete steps and ParaView can open it during a run. Under MPI every
    rank calls ``write`` (the data are gathered collectively), rank 0 writes.
    Subclasses (FluidSeries here, oif.CellSeries) call start_series in their
    __init__, and in their write check_step_time, then write_step with the
    data built from vtk_modules."""

    def __repr__(self):
        return f"{type(self).__name__}('{self.pvd_path}', {len(self.steps)} step(s))"

    def start_series(self, owner, path, default_stem):
        """Set up the series: owner names it in messages, path is its .pvd
        (default_stem where the path gives no name)."""
        self._owner = owner
        self.pvd_path = check_path(owner, path, ".pvd", example=f"out/{default_stem}")
        self._folder = os.path.dirname(self.pvd_path)
        self._stem = os.path.basename(self.pvd_path)[:-len(".pvd")] or default_stem
        self.steps = []  # (time, file name relative to the .pvd's folder)
        self._vtk, self._ns = import_vtk(owner)

    # a series in a checkpoint (lbmd.checkpoint) goes on after a restart:
    # its steps are kept, the VTK module is imported again
    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in ("_vtk", "_ns")}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._vtk, self._ns = import_vtk(self._owner)

    @property
    def vtk_modules(self):
        """(vtk, vtk.util.numpy_support) as imported for this series."""
        return self._vtk, self._ns

    def check_step_time(self, time):
        """time as a float, finite and later than the last step's."""
        owner = f"{self._owner}.write"
        if (time is None or isinstance(time, (bool, np.bool_)) or not isinstance(time, numbers.Real)
                or not math.isfinite(float(time))):
            raise TypeError(f"{owner}: parameter 'time' must be a finite number, got {time!r}")
        time = float(time)
        if self.steps and not time > self.steps[-1][0]:
            raise ValueError(f"{owner}: parameter 'time' must grow from step to step: got {time!r} "
                             f"after {self.steps[-1][0]!r}")
        return time

    def write_step(self, time, suffix, writer, make_data):
        """The next step's file (make_data() on the writing rank, written by
        writer, a vtkXML*Writer), then the .pvd; returns the step's path."""
        name = f"{self._stem}_{len(self.steps):06d}{suffix}"
        path = os.path.join(self._folder, name)
        file_output.on_writer(lambda: write_xml(self._owner, writer(), make_data(), path))
        self.steps.append((time, name))
        try:
            file_output.write_text(self.pvd_path, collection_text(self.steps), self._owner)
        except BaseException:
            self.steps.pop()  # the .pvd on disk still lists the earlier steps only
            raise
        return path


def _point_array(ns, values, name):
    """VTK point array of node values (nx, ny, nz[, c]): x runs fastest."""
    values = np.asarray(values)
    if values.ndim == 3:
        flat = values.transpose(2, 1, 0).ravel()
    else:
        flat = values.transpose(2, 1, 0, 3).reshape(-1, values.shape[3])
    array = ns.numpy_to_vtk(np.ascontiguousarray(flat), deep=1)
    array.SetName(name)
    return array


class FluidSeries(TimeSeries):
    """Time series of the fluid's nodes for ParaView (VTK XML ImageData).

    ``FluidSeries(path, fluid, fields=("velocity", "density"), slice=None)``

    path: the collection file, e.g. ``"out/fluid.pvd"`` (``".pvd"`` is
    appended when missing); step k goes to ``out/fluid_<k>.vti`` (six
    digits, from 0) beside it. A new series starts at step 0 and overwrites
    an existing collection of that name at its first write.

    fluid: the active ``lbmd.lb.LBFluid``.

    fields: point-data arrays to write, any of ``"velocity"`` (3
    components), ``"density"`` and ``"boundary"`` (0 fluid, b + 1 for the
    b-th LBBoundary; boundary nodes report the boundary's velocity and the
    density ``dens``, as ``lbf[i, j, k]`` does).

    slice: None (all nodes) or ``(axis, index)`` with axis ``"x"``, ``"y"``,
    ``"z"`` or 0, 1, 2 and the node index along it: only that plane of nodes
    is written (an image one node thick), for big lattices.

    The image has the spacing agrid and its points at the node centres,
    ``(i + 1/2) agrid``. ``write(time)`` writes the next step at the
    simulation time ``time`` (finite, larger than the previous step's) and
    returns its ``.vti`` file name; every rank must call it under MPI.
    """

    def __init__(self, path=None, fluid=None, fields=("velocity", "density"), slice=None):
        owner = "FluidSeries"
        self.start_series(owner, path, "fluid")
        if fluid is None:
            raise TypeError(f"{owner}: missing required parameter 'fluid' (an active lbmd.lb.LBFluid)")
        self.fluid = _check_fluid(owner, fluid)
        self.fields = check_names(owner, "fields", fields, FIELDS, allow_empty=False)
        shape = fluid.shape
        self.slice = None
        if slice is not None:
            if isinstance(slice, str) or not hasattr(slice, "__len__") or len(slice) != 2:
                raise TypeError(f"{owner}: parameter 'slice' must be None or (axis, index), e.g. ('z', 3), "
                                f"got {slice!r}")
            axis, index = slice
            if isinstance(axis, str) and axis.lower() in _AXES:
                axis = _AXES[axis.lower()]
            elif not (isinstance(axis, numbers.Integral) and not isinstance(axis, bool) and 0 <= axis <= 2):
                raise ValueError(f"{owner}: parameter 'slice': axis must be 'x', 'y', 'z' or 0, 1, 2, "
                                 f"got {axis!r}")
            if not isinstance(index, numbers.Integral) or isinstance(index, bool):
                raise TypeError(f"{owner}: parameter 'slice': the node index must be an integer, got {index!r}")
            if not 0 <= index < shape[axis]:
                raise ValueError(f"{owner}: parameter 'slice': node index {index} is outside "
                                 f"[0, {shape[axis]}) on axis {'xyz'[axis]}")
            self.slice = (int(axis), int(index))

    def _image(self, arrays):
        vtk = self._vtk
        agrid = float(self.fluid.agrid)
        dims = next(iter(arrays.values())).shape[:3]
        lo = [0, 0, 0] if self.slice is None else [self.slice[1] if a == self.slice[0] else 0 for a in range(3)]
        image = vtk.vtkImageData()
        image.SetDimensions(*dims)
        image.SetSpacing(agrid, agrid, agrid)
        image.SetOrigin(*[(i + 0.5) * agrid for i in lo])
        for name in self.fields:
            image.GetPointData().AddArray(_point_array(self._ns, arrays[name], name))
        return image

    def write(self, time=None):
        """Write the fluid at `time` as the next step and rewrite the
        ``.pvd``; collective under MPI. Returns the step's ``.vti`` name."""
        time = self.check_step_time(time)
        _check_fluid("FluidSeries.write", self.fluid)
        core = self.fluid._collective_core()
        lo, hi = [0, 0, 0], [int(n) for n in self.fluid.shape]
        if self.slice is not None:
            lo[self.slice[0]], hi[self.slice[0]] = self.slice[1], self.slice[1] + 1
        arrays = {}
        for name in self.fields:
            # collective: each rank sends its own nodes to the writing rank
            # (rank 0), the only one that holds the whole field
            block = np.asarray(core.gather_block(name, lo, hi, 0))
            if block.size:
                block = block if name == "velocity" else block[..., 0]
                arrays[name] = block.astype(np.int32 if name == "boundary" else np.float64)
        return self.write_step(time, ".vti", self._vtk.vtkXMLImageDataWriter, lambda: self._image(arrays))



def wall_surface(fluid, boundary=None):
    """The wall surface (vtkPolyData of triangles) of the fluid's boundary
    nodes; see write_wall_surface. `boundary`: the flags
    ``fluid[:, :, :].boundary`` if already read (reading them is
    collective under MPI)."""
    owner = "write_wall_surface"
    _check_fluid(owner, fluid)
    vtk, ns = import_vtk(owner)
    if boundary is None:
        boundary = fluid[:, :, :].boundary
    solid = (np.asarray(boundary) > 0).astype(np.float64)
    periodic = [bool(p) for p in fluid._system.periodicity]
    # one layer of padding per side: a periodic axis continues with the
    # nodes of the far side (the surface crossing the box face is found and
    # then cut at the face); a non-periodic axis ends in solid, since the
    # lattice ends at the box face (fluid reaching it gets a surface there)
    for axis in range(3):
        pad = [(0, 0)] * 3
        pad[axis] = (1, 1)
        if periodic[axis]:
            solid = np.pad(solid, pad, mode="wrap")
        else:
            solid = np.pad(solid, pad, mode="constant", constant_values=1.0)
    agrid = float(fluid.agrid)
    image = vtk.vtkImageData()
    image.SetDimensions(*solid.shape)
    image.SetSpacing(agrid, agrid, agrid)
    image.SetOrigin(-0.5 * agrid, -0.5 * agrid, -0.5 * agrid)  # padding node centres
    image.GetPointData().SetScalars(_point_array(ns, solid, "solid"))
    # iso-surface 0.5 of the solid indicator: on each lattice link between a
    # fluid and a solid node it lies halfway, where halfway bounce-back puts
    # the wall (Ladd 1994)
    contour = vtk.vtkFlyingEdges3D()
    contour.SetInputData(image)
    contour.SetValue(0, 0.5)
    contour.ComputeNormalsOff()
    contour.ComputeGradientsOff()
    contour.ComputeScalarsOff()
    contour.Update()
    surface = contour.GetOutput()
    if any(periodic):
        # cut at the periodic box faces, one plane at a time (a plane's
        # implicit function is linear: the cut is exact along the edges)
        box = np.asarray(fluid._system.box_l, dtype=float)
        port, keep = None, []  # keep: the filters stay alive until Update
        for axis in range(3):
            if not periodic[axis]:
                continue
            for position, inward in ((0.0, 1.0), (box[axis], -1.0)):
                plane = vtk.vtkPlane()
                origin, normal = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
                origin[axis], normal[axis] = position, inward
                plane.SetOrigin(*origin)
                plane.SetNormal(*normal)
                clip = vtk.vtkClipPolyData()
                if port is None:
                    clip.SetInputData(surface)
                else:
                    clip.SetInputConnection(port)
                clip.SetClipFunction(plane)  # keeps the side the normal points to
                keep += [plane, clip]
                port = clip.GetOutputPort()
        triangles = vtk.vtkTriangleFilter()
        triangles.SetInputConnection(port)
        clean = vtk.vtkCleanPolyData()
        clean.SetInputConnection(triangles.GetOutputPort())
        clean.Update()
        surface = clean.GetOutput()
    return surface


def write_wall_surface(path=None, fluid=None):
    """Write the wall surface of the fluid's boundaries (all LBBoundaries
    together) as a ``.vtp`` triangle mesh, atomically; returns the file name.

    The surface is the iso-surface 1/2 of the solid indicator (1 at boundary
    nodes, 0 at fluid nodes) at the node centres: it lies halfway between
    neighbouring fluid and solid nodes, where halfway bounce-back puts the
    wall, so it shows the staircase the fluid sees, rounded by the
    interpolation (within agrid/2 of the shapes' surfaces). On a periodic
    axis the surface is continued across the box faces and cut at them (it
    is open there only). A non-periodic axis counts as solid beyond the
    lattice: fluid nodes at the box face get a surface on the face.
    Collective under MPI; rank 0 writes. Walls do not move: write once.
    """
    owner = "write_wall_surface"
    path = check_path(owner, path, ".vtp")
    if fluid is None:
        raise TypeError(f"{owner}: missing required parameter 'fluid' (an active lbmd.lb.LBFluid)")
    _check_fluid(owner, fluid)
    solid = np.asarray(fluid[:, :, :].boundary)  # collective: every rank reads the nodes
    if not np.any(solid > 0):
        raise ValueError(f"{owner}: the fluid has no boundary nodes (add an LBBoundary to "
                         f"system.lbboundaries first); there is no wall surface to write")
    vtk, _ = import_vtk(owner)
    file_output.on_writer(lambda: write_xml(owner, vtk.vtkXMLPolyDataWriter(), wall_surface(fluid, solid), path))
    return path
