"""VTK XML time series of cells for ParaView: one ``.vtp`` PolyData file per
output step (all given cells together) and a ``.pvd`` collection that lists
every step with its time.

Written through Debian's VTK library (``vtkXMLPolyDataWriter``, package
python3-vtk9): appended binary data, zlib-compressed and base64-encoded (the
writer's default; the file stays valid XML), 64-bit block headers. The legacy
``.vtk`` writers of ``oif.vtk`` are kept for PyOIF scripts.

Under MPI every rank calls ``write`` (the particle queries are collective and
return the same on all ranks); rank 0 alone writes the files, so they do not
depend on the rank count. Each file is written under a temporary name in its
folder and renamed over the final name: a crash never leaves a half-written
``.vtp`` or ``.pvd``, and ParaView can open the ``.pvd`` at any time of a run.
"""

import numpy as np

from lbmd import vtk_output


#: point-data arrays CellSeries can write, with what they hold
POINT_DATA = {
    "velocity": "particle velocities v (N x 3)",
    "force": "total particle forces f of the last step (N x 3)",
    "normal": "outward unit node normals of the current shape (N x 3, area-weighted over the adjacent triangles)",
}


def _outward_node_normals(pos, triangles):
    """Area-weighted outward unit normal at every node; `triangles` are
    ordered outward, (B - A) x (C - A) pointing out of the cell (its length
    is twice the triangle's area, hence the area weighting)."""
    a, b, c = pos[triangles[:, 0]], pos[triangles[:, 1]], pos[triangles[:, 2]]
    tri_normal = np.cross(b - a, c - a)
    acc = np.zeros_like(pos)
    for k in range(3):
        np.add.at(acc, triangles[:, k], tri_normal)
    length = np.linalg.norm(acc, axis=1)
    length[length == 0.0] = 1.0  # a node in no triangle keeps a zero normal
    return acc / length[:, None]


class CellSeries(vtk_output.TimeSeries):
    """Time series of OIF cells for ParaView (VTK XML PolyData + collection).

    ``CellSeries(path, point_data=("velocity", "force", "normal"), folded=True)``

    path: the collection file, e.g. ``"out/cells.pvd"`` (``".pvd"`` is
    appended when missing); step k is written to ``out/cells_<k>.vtp`` (six
    digits, from 0) beside it and listed in the ``.pvd`` under its file name
    relative to the ``.pvd``'s folder. A new series starts from step 0: an
    existing collection of that name is overwritten at the first write.

    point_data: names of the per-node arrays to write, any of
    ``"velocity"`` (particles' v), ``"force"`` (particles' f) and
    ``"normal"`` (outward unit node normals computed from the current
    shape, for every cell, whether or not its type was built with
    ``normal=True``). Every step also has the cell data ``cell_id`` (the
    cell's mol_id, one value per triangle) to colour or threshold cells.

    folded: True shifts each whole cell by box periods so that its centre
    lies in the box (as ``OifCell.output_vtk_pos_folded``; the cell is not
    cut at the box faces); False writes the unfolded positions.

    ``write(cells, time)``: one OifCell or a sequence of them, at the
    simulation time ``time`` (a finite number, larger than the previous
    step's); returns the ``.vtp`` file name of the step.
    """

    def __init__(self, path=None, point_data=("velocity", "force", "normal"), folded=True):
        owner = "CellSeries"
        self.start_series(owner, path, "cells")
        self.point_data = vtk_output.check_names(owner, "point_data", point_data, POINT_DATA)
        if not isinstance(folded, (bool, np.bool_)):
            raise TypeError(f"{owner}: parameter 'folded' must be True or False, got {folded!r}")
        self.folded = bool(folded)

    # -- data ---------------------------------------------------------------------
    def _cells(self, cells):
        from .oif_classes import OifCell
        if isinstance(cells, OifCell):
            cells = [cells]
        try:
            cells = list(cells)
        except TypeError:
            raise TypeError(f"CellSeries.write: parameter 'cells' must be an OifCell or a sequence of OifCells, "
                            f"got {type(cells).__name__}") from None
        if not cells:
            raise ValueError("CellSeries.write: parameter 'cells' is empty; give at least one OifCell")
        for c in cells:
            if not isinstance(c, OifCell):
                raise TypeError(f"CellSeries.write: parameter 'cells' must hold OifCells, got {type(c).__name__}")
        return cells

    def _gather(self, cells):
        """Points, outward triangles (global point ids), per-triangle cell ids
        and the point-data arrays of all cells (collective under MPI)."""
        points, triangles, tri_cell_ids = [], [], []
        arrays = {name: [] for name in self.point_data}
        offset = 0
        for cell in cells:
            parts = cell._parts  # checked to be all this cell's particles
            pos = np.asarray(cell.mesh.positions(), dtype=float)
            tris = np.asarray(cell._vtk_triangles(), dtype=np.int64).reshape(-1, 3)
            if "normal" in arrays:  # the shape, not its periodic image, defines the normals
                arrays["normal"].append(_outward_node_normals(pos, tris))
            if self.folded:
                box = np.asarray(cell.system.box_l, dtype=float)
                pos = pos - np.floor(pos.mean(axis=0) / box) * box
            if "velocity" in arrays:
                arrays["velocity"].append(np.asarray(parts.v, dtype=float).reshape(-1, 3))
            if "force" in arrays:
                arrays["force"].append(np.asarray(parts.f, dtype=float).reshape(-1, 3))
            points.append(pos)
            triangles.append(tris + offset)
            tri_cell_ids.append(np.full(len(tris), cell.cell_id, dtype=np.int32))
            offset += len(pos)
        return (np.vstack(points), np.vstack(triangles), np.concatenate(tri_cell_ids),
                {name: np.vstack(a) for name, a in arrays.items()})

    def _polydata(self, points, triangles, tri_cell_ids, arrays):
        vtk, ns = self.vtk_modules
        poly = vtk.vtkPolyData()
        vtk_points = vtk.vtkPoints()
        vtk_points.SetData(ns.numpy_to_vtk(np.ascontiguousarray(points, dtype=np.float64), deep=1))
        poly.SetPoints(vtk_points)
        offsets = np.arange(0, 3 * len(triangles) + 1, 3, dtype=np.int64)
        polys = vtk.vtkCellArray()
        polys.SetData(ns.numpy_to_vtk(offsets, deep=1, array_type=vtk.VTK_ID_TYPE),
                      ns.numpy_to_vtk(np.ascontiguousarray(triangles.ravel()), deep=1,
                                      array_type=vtk.VTK_ID_TYPE))
        poly.SetPolys(polys)
        ids = ns.numpy_to_vtk(tri_cell_ids, deep=1, array_type=vtk.VTK_INT)
        ids.SetName("cell_id")
        poly.GetCellData().AddArray(ids)
        for name in self.point_data:
            arr = ns.numpy_to_vtk(np.ascontiguousarray(arrays[name], dtype=np.float64), deep=1)
            arr.SetName(name)
            poly.GetPointData().AddArray(arr)
        return poly

    # -- files --------------------------------------------------------------------
    def write(self, cells=None, time=None):
        """Write the cells at `time` as the next step and rewrite the
        ``.pvd``; every rank must call it under MPI. Returns the step's
        ``.vtp`` file name."""
        if cells is None:
            raise TypeError("CellSeries.write: missing required parameter 'cells'")
        cells = self._cells(cells)
        time = self.check_step_time(time)
        data = self._gather(cells)  # collective: every rank takes part
        return self.write_step(time, ".vtp", self.vtk_modules[0].vtkXMLPolyDataWriter, lambda: self._polydata(*data))
