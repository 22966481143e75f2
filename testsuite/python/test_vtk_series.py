"""oif.CellSeries: VTK XML time series of cells (.vtp steps + .pvd
collection) read back with VTK's own XML reader and xml.etree."""
import os
import tempfile
import unittest
import warnings
import xml.etree.ElementTree as ET

import numpy as np

import lbmd
from lbmd.settings_check import SettingsWarning
import oif

R_RBC = 3.91


def read_vtp(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    poly = reader.GetOutput()
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    polys = poly.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray())
    conn = vtk_to_numpy(polys.GetConnectivityArray())
    pd, cd = poly.GetPointData(), poly.GetCellData()
    point_data = {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}
    cell_data = {cd.GetArrayName(i): vtk_to_numpy(cd.GetArray(i)) for i in range(cd.GetNumberOfArrays())}
    return pts, offsets, conn, point_data, cell_data


class TestCellSeries(unittest.TestCase):

    def setUp(self):
        self.system = lbmd.System(box_l=[30.0, 20.0, 20.0])
        self.system.time_step = 0.02
        self.tmp = tempfile.TemporaryDirectory()
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=self.system, resize=(3.0, 3.0, 3.0),
                             ks=0.05, kb=0.01, kal=0.01, kag=0.5, kv=0.9)
        # the second cell sticks out of the box: its folded image is shifted by -box_l[0]
        self.cells = [oif.OifCell(cell_type=ct, particle_type=0, origin=[8.0, 10.0, 10.0]),
                      oif.OifCell(cell_type=ct, particle_type=0, origin=[31.0, 10.0, 10.0], rotate=(0.3, 0.2, 0.1))]
        rng = np.random.default_rng(3)
        for c in self.cells:
            c.particles.v = rng.normal(size=(c.get_n_nodes(), 3)) * 1e-3
            c.particles.pos = c.mesh.positions() * (1.0 + 0.01 * rng.random((c.get_n_nodes(), 1)))

    def tearDown(self):
        self.tmp.cleanup()

    def test_three_steps(self):
        pvd = os.path.join(self.tmp.name, "out", "cells.pvd")
        for folded in (True, False):
            series = oif.CellSeries(pvd, folded=folded)
            times = [0.0, 2.5, 5.0]
            n_nodes = sum(c.get_n_nodes() for c in self.cells)
            n_tris = sum(c.get_n_triangles() for c in self.cells)
            for step, t in enumerate(times):
                if step:
                    with warnings.catch_warnings():  # no fluid, no contacts: only forces are wanted here
                        warnings.simplefilter("ignore", SettingsWarning)
                        self.system.integrator.run(5)
                name = series.write(self.cells, t)
                self.assertEqual(os.path.basename(name), f"cells_{step:06d}.vtp")
                pts, offsets, conn, pdata, cdata = read_vtp(name)
                self.assertEqual(len(pts), n_nodes)
                self.assertEqual(len(offsets) - 1, n_tris)
                np.testing.assert_array_equal(np.diff(offsets), 3)
                self.assertEqual(set(pdata), {"velocity", "force", "normal"})
                begin, tri_begin = 0, 0
                for c in self.cells:
                    n, m = c.get_n_nodes(), c.get_n_triangles()
                    pos = c.mesh.positions()
                    if folded:
                        box = np.asarray(self.system.box_l)
                        pos = pos - np.floor(pos.mean(axis=0) / box) * box
                        centre = pts[begin:begin + n].mean(axis=0)
                        self.assertTrue(np.all((centre >= 0) & (centre < box)))
                    np.testing.assert_array_equal(pts[begin:begin + n], pos)
                    np.testing.assert_array_equal(pdata["velocity"][begin:begin + n], c.particles.v)
                    np.testing.assert_array_equal(pdata["force"][begin:begin + n], c.particles.f)
                    # the triangles of this cell use its points only, in the outward order
                    tris = conn[3 * tri_begin:3 * (tri_begin + m)].reshape(-1, 3) - begin
                    np.testing.assert_array_equal(tris, c._vtk_triangles())
                    np.testing.assert_array_equal(cdata["cell_id"][tri_begin:tri_begin + m], c.cell_id)
                    # outward unit normals: the mesh's own area-weighted node normals (PyOIF's
                    # inward triangle order, negated), pointing away from the centre on a near-sphere
                    normal = pdata["normal"][begin:begin + n]
                    np.testing.assert_allclose(normal, c.mesh._vertex_normals(c.mesh.positions()), atol=1e-12)
                    np.testing.assert_allclose(np.linalg.norm(normal, axis=1), 1.0, rtol=1e-12)
                    radial = pos - pos.mean(axis=0)
                    radial /= np.linalg.norm(radial, axis=1)[:, None]
                    self.assertGreater(np.min(np.sum(normal * radial, axis=1)), 0.95)
                    begin += n
                    tri_begin += m
                if step:  # after a run the stretched cells have elastic forces (a zero array would pass above)
                    self.assertGreater(np.abs(pdata["force"]).max(), 1e-6)
                # the collection lists every step so far, with times and relative names
                root = ET.parse(pvd).getroot()
                self.assertEqual(root.get("type"), "Collection")
                sets = root.find("Collection").findall("DataSet")
                self.assertEqual([float(d.get("timestep")) for d in sets], times[:step + 1])
                self.assertEqual([d.get("file") for d in sets], [f"cells_{k:06d}.vtp" for k in range(step + 1)])
            self.assertFalse([f for f in os.listdir(os.path.dirname(pvd)) if f.endswith(".tmp")])
        # the last series was unfolded: the second cell's nodes reach past the box face x = 30
        unfolded_pts = read_vtp(os.path.join(self.tmp.name, "out", "cells_000000.vtp"))[0]
        self.assertGreater(unfolded_pts[:, 0].max(), 32.0)

    def test_selected_arrays_and_prefix(self):
        series = oif.CellSeries(os.path.join(self.tmp.name, "run"), point_data=("force",), folded=False)
        self.assertEqual(series.pvd_path, os.path.join(self.tmp.name, "run.pvd"))
        name = series.write(self.cells[0], 1.0)
        pts, _, _, pdata, cdata = read_vtp(name)
        self.assertEqual(set(pdata), {"force"})
        self.assertEqual(set(cdata), {"cell_id"})
        np.testing.assert_array_equal(pts, self.cells[0].mesh.positions())
        self.assertEqual(set(read_vtp(oif.CellSeries(os.path.join(self.tmp.name, "p.pvd"), point_data=())
                                      .write(self.cells, 0.0))[3]), set())

    def test_bad_input(self):
        d = self.tmp.name
        with self.assertRaisesRegex(ValueError, r"'point_data'.*'pressure'.*velocity, force, normal"):
            oif.CellSeries(os.path.join(d, "a.pvd"), point_data=("velocity", "pressure"))
        with self.assertRaisesRegex(ValueError, "'point_data'.*twice"):
            oif.CellSeries(os.path.join(d, "a.pvd"), point_data=("force", "force"))
        with self.assertRaisesRegex(TypeError, "'point_data'"):
            oif.CellSeries(os.path.join(d, "a.pvd"), point_data=3)
        with self.assertRaisesRegex(TypeError, "'path'"):
            oif.CellSeries(None)
        with self.assertRaisesRegex(ValueError, "'path'"):
            oif.CellSeries(d + os.sep)
        with self.assertRaisesRegex(TypeError, "'folded'"):
            oif.CellSeries(os.path.join(d, "a.pvd"), folded="yes")
        series = oif.CellSeries(os.path.join(d, "a.pvd"))
        with self.assertRaisesRegex(TypeError, "'cells'"):
            series.write([self.cells[0], "cell"], 0.0)
        with self.assertRaisesRegex(ValueError, "'cells'"):
            series.write([], 0.0)
        for t in (None, float("nan"), "1", True):
            with self.assertRaisesRegex(TypeError, "'time'"):
                series.write(self.cells, t)
        self.assertFalse(os.path.exists(os.path.join(d, "a.pvd")))  # nothing written on bad input
        series.write(self.cells, 1.0)
        with self.assertRaisesRegex(ValueError, "'time' must grow"):
            series.write(self.cells, 1.0)
        # a folder where the next .vtp goes: the error names it, the .pvd keeps the one good step
        os.mkdir(os.path.join(d, "a_000001.vtp"))
        with self.assertRaisesRegex(ValueError, "a_000001.vtp"):
            series.write(self.cells, 2.0)
        self.assertEqual(len(ET.parse(os.path.join(d, "a.pvd")).getroot().find("Collection")), 1)
        self.assertEqual(len(series.steps), 1)


if __name__ == "__main__":
    unittest.main()
