"""lbmd.vtk_output: VTK XML time series of the fluid (.vti steps + .pvd) and
the wall surface (.vtp), read back with VTK's own XML readers."""
import os
import tempfile
import unittest
import xml.etree.ElementTree as ET

import numpy as np

import lbmd

AGRID = 0.5
SHAPE = (12, 8, 6)  # nodes; walls at the first and last z node
CYL_CENTER = np.array([6.0, 4.0, 3.0]) * AGRID
CYL_RADIUS = 1.3 * AGRID


def read_vti(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    dims = image.GetDimensions()
    pd = image.GetPointData()
    arrays = {}
    for i in range(pd.GetNumberOfArrays()):
        a = vtk_to_numpy(pd.GetArray(i))
        # VTK order: x fastest -> back to (nx, ny, nz[, c])
        a = a.reshape(dims[::-1] + a.shape[1:])
        arrays[pd.GetArrayName(i)] = a.transpose(2, 1, 0, 3) if a.ndim == 4 else a.transpose(2, 1, 0)
    return dims, image.GetSpacing(), image.GetOrigin(), arrays


class TestFluidVtk(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        box = np.array(SHAPE, dtype=float) * AGRID
        cls.system = lbmd.System(box_l=box, periodicity=[True, True, False])
        cls.system.time_step = 0.01
        cls.lbf = lbmd.lb.LBFluid(agrid=AGRID, dens=1.0, visc=1.0, tau=0.01,
                                  ext_force_density=[0.5, 0, 0])
        cls.system.actors.add(cls.lbf)
        cls.shapes = [lbmd.shapes.Wall(normal=[0, 0, 1], dist=AGRID),
                      lbmd.shapes.Wall(normal=[0, 0, -1], dist=-(box[2] - AGRID)),
                      lbmd.shapes.Cylinder(center=CYL_CENTER, axis=[0, 1, 0], radius=CYL_RADIUS,
                                           length=10 * box[1])]
        for s in cls.shapes:
            cls.system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=s))
        cls.system.integrator.run(5)

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def test_series_reads_back(self):
        pvd = os.path.join(self.tmp.name, "out", "fluid.pvd")
        series = lbmd.vtk_output.FluidSeries(pvd, self.lbf, fields=("velocity", "density", "boundary"))
        names, fluid_states = [], []
        for k in range(3):
            self.system.integrator.run(2)
            nodes = self.lbf[:, :, :]
            fluid_states.append((nodes.velocity, nodes.density, nodes.boundary))
            names.append(series.write(self.system.time))
        self.assertTrue(np.any(np.abs(fluid_states[-1][0][..., 0]) > 1e-6))  # the flow is on
        for name, (u, rho, flags) in zip(names, fluid_states):
            dims, spacing, origin, arrays = read_vti(name)
            self.assertEqual(dims, SHAPE)
            self.assertEqual(spacing, (AGRID,) * 3)
            self.assertEqual(origin, (0.5 * AGRID,) * 3)
            np.testing.assert_array_equal(arrays["velocity"], u)
            np.testing.assert_array_equal(arrays["density"], rho)
            np.testing.assert_array_equal(arrays["boundary"], flags)
        self.assertEqual(sorted(set(np.unique(fluid_states[0][2]))), [0, 1, 2, 3])
        root = ET.parse(pvd).getroot()
        rows = root.findall("./Collection/DataSet")
        self.assertEqual([float(r.get("timestep")) for r in rows], [t for t, _ in series.steps])
        self.assertEqual([r.get("file") for r in rows], [os.path.basename(n) for n in names])
        self.assertAlmostEqual(float(rows[-1].get("timestep")), self.system.time, delta=1e-12)
        self.assertEqual(sorted(os.listdir(os.path.dirname(pvd))),
                         sorted(["fluid.pvd"] + [os.path.basename(n) for n in names]))  # no .tmp left

    def test_slice(self):
        for axis, index, key in (("z", 2, (slice(None), slice(None), slice(2, 3))),
                                 (0, 7, (slice(7, 8), slice(None), slice(None)))):
            pvd = os.path.join(self.tmp.name, f"slice_{axis}.pvd")
            series = lbmd.vtk_output.FluidSeries(pvd, self.lbf, slice=(axis, index))
            name = series.write(1.0)
            dims, spacing, origin, arrays = read_vti(name)
            a = {"z": 2}.get(axis, axis)
            expected_dims = list(SHAPE)
            expected_dims[a] = 1
            self.assertEqual(dims, tuple(expected_dims))
            expected_origin = [0.5 * AGRID] * 3
            expected_origin[a] = (index + 0.5) * AGRID
            np.testing.assert_allclose(origin, expected_origin, rtol=0, atol=1e-15)
            self.assertEqual(sorted(arrays), ["density", "velocity"])
            np.testing.assert_array_equal(arrays["velocity"], self.lbf[key].velocity)
            np.testing.assert_array_equal(arrays["density"], self.lbf[key].density)

    def test_wall_surface(self):
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
        path = lbmd.vtk_output.write_wall_surface(os.path.join(self.tmp.name, "walls"), self.lbf)
        self.assertTrue(path.endswith("walls.vtp"))
        reader = vtk.vtkXMLPolyDataReader()
        reader.SetFileName(path)
        reader.Update()
        poly = reader.GetOutput()
        self.assertGreater(poly.GetNumberOfCells(), 100)
        self.assertEqual(poly.GetNumberOfCells(), poly.GetPolys().GetNumberOfCells())  # triangles only
        sizes = np.diff(vtk_to_numpy(poly.GetPolys().GetOffsetsArray()))
        self.assertTrue(np.all(sizes == 3))
        pts = vtk_to_numpy(poly.GetPoints().GetData())
        box = np.array(SHAPE) * AGRID
        # inside the box (cut at the periodic faces, nothing beyond the lattice)
        self.assertTrue(np.all(pts >= -1e-12) and np.all(pts <= box + 1e-12))
        # every point lies halfway on a fluid-solid link: within agrid / 2 of
        # the surface of a shape (signed distance is 1-Lipschitz)
        dist = np.array([min(abs(s.calc_dist(p)[0]) for s in self.shapes) for p in pts])
        self.assertLessEqual(dist.max(), 0.5 * AGRID + 1e-9)
        # the planar walls exactly halfway between the wall and fluid nodes
        on_cylinder = np.array([abs(self.shapes[2].calc_dist(p)[0]) <= 0.5 * AGRID + 1e-9 for p in pts])
        z_walls = np.unique(pts[~on_cylinder, 2])
        np.testing.assert_array_equal(z_walls, [AGRID, (SHAPE[2] - 1) * AGRID])
        self.assertTrue(np.any(on_cylinder))
        # the rounded obstacle: not only lattice-aligned faces (its surface
        # has points off the node planes x = (i + 1/2) agrid and z = ...)
        cyl = pts[on_cylinder]
        off_grid = np.abs((cyl[:, [0, 2]] / AGRID - 0.5) % 1.0)
        self.assertTrue(np.any((off_grid > 1e-9) & (off_grid < 1 - 1e-9)))
        # closed but for the cut at the periodic faces x = 0, Lx and y = 0, Ly
        edges = vtk.vtkFeatureEdges()
        edges.SetInputData(poly)
        edges.BoundaryEdgesOn()
        edges.NonManifoldEdgesOn()
        edges.FeatureEdgesOff()
        edges.ManifoldEdgesOff()
        edges.Update()
        open_pts = vtk_to_numpy(edges.GetOutput().GetPoints().GetData())
        self.assertGreater(len(open_pts), 0)
        on_face = ((np.abs(open_pts[:, 0]) < 1e-9) | (np.abs(open_pts[:, 0] - box[0]) < 1e-9)
                   | (np.abs(open_pts[:, 1]) < 1e-9) | (np.abs(open_pts[:, 1] - box[1]) < 1e-9))
        self.assertTrue(np.all(on_face), open_pts[~on_face])

    def test_bad_input(self):
        FS = lbmd.vtk_output.FluidSeries
        p = os.path.join(self.tmp.name, "f.pvd")
        with self.assertRaisesRegex(TypeError, "'path'"):
            FS(None, self.lbf)
        with self.assertRaisesRegex(TypeError, "'fluid' must be an lbmd.lb.LBFluid"):
            FS(p, "fluid")
        with self.assertRaisesRegex(ValueError, "'fields' has unknown name.*'vel'"):
            FS(p, self.lbf, fields=("vel",))
        with self.assertRaisesRegex(ValueError, "'fields' is empty"):
            FS(p, self.lbf, fields=())
        with self.assertRaisesRegex(ValueError, "axis must be 'x', 'y', 'z'"):
            FS(p, self.lbf, slice=("w", 0))
        with self.assertRaisesRegex(ValueError, r"node index 6 is outside \[0, 6\) on axis z"):
            FS(p, self.lbf, slice=("z", 6))
        with self.assertRaisesRegex(TypeError, "'slice' must be None or"):
            FS(p, self.lbf, slice=3)
        s = FS(p, self.lbf)
        s.write(1.0)
        with self.assertRaisesRegex(ValueError, "'time' must grow"):
            s.write(1.0)
        with self.assertRaisesRegex(TypeError, "'time' must be a finite number"):
            s.write(float("nan"))
        self.assertEqual(len(ET.parse(p).getroot().findall("./Collection/DataSet")), 1)
        with self.assertRaisesRegex(TypeError, "'fluid'"):
            lbmd.vtk_output.write_wall_surface(os.path.join(self.tmp.name, "w.vtp"), None)
        inactive = lbmd.lb.LBFluid(agrid=AGRID, dens=1.0, visc=1.0, tau=0.01)
        with self.assertRaisesRegex(RuntimeError, "not active"):
            FS(p, inactive)

    def test_no_walls(self):
        system = lbmd.System(box_l=[2.0, 2.0, 2.0])
        system.time_step = 0.01
        lbf = lbmd.lb.LBFluid(agrid=AGRID, dens=1.0, visc=1.0, tau=0.01)
        system.actors.add(lbf)
        with self.assertRaisesRegex(ValueError, "no boundary nodes"):
            lbmd.vtk_output.write_wall_surface(os.path.join(self.tmp.name, "w.vtp"), lbf)


if __name__ == "__main__":
    unittest.main()
