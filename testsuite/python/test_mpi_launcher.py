"""Under `mpirun -np N pyoif script.py` every rank runs the script (SPMD).
Whatever the fluid's split over the ranks, every query returns the same value
on every rank: all ranks must agree bit for bit with each other and with a
serial run."""
import unittest

import numpy as np
from mpi4py import MPI

import lbmd


def trajectory():
    s = lbmd.System(box_l=[6.0, 6.0, 6.0])
    s.time_step = 0.005
    rng = np.random.default_rng(11)
    g = np.mgrid[0:4, 0:4, 0:4].reshape(3, -1).T * 1.5 + 0.3
    s.part.add(pos=g + rng.uniform(-0.05, 0.05, g.shape), v=rng.normal(size=g.shape))
    s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.5, n=12, cutoff=2.0)
    s.thermostat.set_langevin(kT=1.0, gamma=0.5, seed=7)
    s.integrator.run(500)
    return s.part.all().pos, s.analysis.energy()["total"]


class MpiLauncher(unittest.TestCase):
    def test_ranks_agree(self):
        comm = MPI.COMM_WORLD
        pos, energy = trajectory()
        all_pos = comm.allgather(pos)
        all_energy = comm.allgather(energy)
        for p, e in zip(all_pos, all_energy):
            np.testing.assert_array_equal(p, all_pos[0])
            self.assertEqual(e, all_energy[0])
        # every rank also agrees with a second (serial) run of itself
        pos2, energy2 = trajectory()
        np.testing.assert_array_equal(pos2, pos)
        self.assertTrue(np.isfinite(energy))

    def test_cell_output_outcome_shared_by_all_ranks(self):
        """Only rank 0 writes cell files; a refused append must be refused on
        every rank (before, only rank 0 raised and rank 1 read a file that
        rank 0 was still replacing)."""
        import os
        import tempfile

        import oif
        comm = MPI.COMM_WORLD
        folder = comm.bcast(tempfile.mkdtemp() if comm.Get_rank() == 0 else None, root=0)
        s = lbmd.System(box_l=[40.0, 30.0, 30.0])
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(3.0, 3.0, 3.0))
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[10, 15, 15])
        for i in range(10):
            name = os.path.join(folder, f"c{i}.vtk")
            cell.output_vtk_pos(name)
            cell.append_point_data_to_vtk(file_name=name, data_name="a", data=np.zeros(162),
                                          first_append=True)
            with self.assertRaisesRegex(ValueError, "already has a POINT_DATA section"):
                cell.append_point_data_to_vtk(file_name=name, data_name="b", data=np.ones(162),
                                              first_append=True)
        comm.Barrier()
        if comm.Get_rank() == 0:
            with open(os.path.join(folder, "c9.vtk")) as f:
                self.assertEqual(f.read().count("POINT_DATA"), 1)

    def test_bad_polydata_refused_on_every_rank(self):
        """Polygons that are not index lists (and a file name under a file):
        every rank raises. Before, the writing rank raised while formatting,
        before the shared outcome, and the others waited for it forever."""
        import os
        import tempfile

        from oif import vtk
        comm = MPI.COMM_WORLD
        folder = comm.bcast(tempfile.mkdtemp() if comm.Get_rank() == 0 else None, root=0)
        points = np.zeros((3, 3))
        with self.assertRaisesRegex(TypeError, "polygons must be lists of point indices"):
            vtk.write_polydata(os.path.join(folder, "bad.vtk"), points, polygons=[[0, "a", 2]])
        if comm.Get_rank() == 0:
            open(os.path.join(folder, "afile"), "w").close()
        comm.Barrier()
        with self.assertRaisesRegex(ValueError, "is a file, not a folder"):
            vtk.write_polydata(os.path.join(folder, "afile", "x.vtk"), points, polygons=[[0, 1, 2]])
        vtk.write_polydata(os.path.join(folder, "good.vtk"), points, polygons=[[0, 1, 2]])
        comm.Barrier()
        self.assertTrue(os.path.exists(os.path.join(folder, "good.vtk")))

    def test_cell_series_written_once(self):
        """oif.CellSeries under MPI: every rank calls write, rank 0 writes the
        .vtp and .pvd (whose content does not depend on the rank count), and a
        refused step is refused on every rank."""
        import os
        import shutil
        import tempfile
        import xml.etree.ElementTree as ET

        import oif
        comm = MPI.COMM_WORLD
        folder = comm.bcast(tempfile.mkdtemp() if comm.Get_rank() == 0 else None, root=0)
        s = lbmd.System(box_l=[40.0, 30.0, 30.0])
        s.time_step = 0.01
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(3.0, 3.0, 3.0), ks=0.05)
        cells = [oif.OifCell(cell_type=ct, particle_type=0, origin=[10, 15, 15]),
                 oif.OifCell(cell_type=ct, particle_type=0, origin=[41, 15, 15])]
        series = oif.CellSeries(os.path.join(folder, "cells.pvd"))
        for k in range(2):
            name = series.write(cells, 0.5 * k)
        if comm.Get_rank() == 0:
            os.mkdir(os.path.join(folder, "cells_000002.vtp"))
        comm.Barrier()
        with self.assertRaisesRegex(ValueError, "cells_000002.vtp"):
            series.write(cells, 1.0)
        pos = np.vstack([c.mesh.positions() for c in cells])
        if comm.Get_rank() == 0:
            import vtk
            from vtk.util.numpy_support import vtk_to_numpy
            reader = vtk.vtkXMLPolyDataReader()
            reader.SetFileName(name)
            reader.Update()
            pts = vtk_to_numpy(reader.GetOutput().GetPoints().GetData())
            pos[162:, 0] -= 40.0  # the folded image of the cell centred at x = 41
            np.testing.assert_array_equal(pts, pos)
            self.assertEqual(len(ET.parse(os.path.join(folder, "cells.pvd")).getroot().find("Collection")), 2)
        comm.Barrier()
        if comm.Get_rank() == 0:
            shutil.rmtree(folder)

    def test_fluid_series_written_once(self):
        """lbmd.vtk_output under MPI: each rank sends its own nodes to rank 0 (collective),
        rank 0 writes the .vti, .pvd and wall .vtp; the image holds the whole
        lattice whatever the rank count."""
        import os
        import shutil
        import tempfile

        comm = MPI.COMM_WORLD
        folder = comm.bcast(tempfile.mkdtemp() if comm.Get_rank() == 0 else None, root=0)
        s = lbmd.System(box_l=[8.0, 4.0, 4.0], periodicity=[True, True, False])
        s.time_step = 0.01
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=10.0, tau=0.01, ext_force_density=[0.1, 0, 0])
        s.actors.add(lbf)
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0)))
        s.integrator.run(4)
        series = lbmd.vtk_output.FluidSeries(os.path.join(folder, "fluid.pvd"), lbf)
        name = series.write(s.time)
        wall = lbmd.vtk_output.write_wall_surface(os.path.join(folder, "walls.vtp"), lbf)
        u = lbf[:, :, :].velocity
        if comm.Get_rank() == 0:
            import vtk
            from vtk.util.numpy_support import vtk_to_numpy
            reader = vtk.vtkXMLImageDataReader()
            reader.SetFileName(name)
            reader.Update()
            self.assertEqual(reader.GetOutput().GetDimensions(), (8, 4, 4))
            read = vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("velocity"))
            np.testing.assert_array_equal(read.reshape(4, 4, 8, 3).transpose(2, 1, 0, 3), u)
            poly = vtk.vtkXMLPolyDataReader()
            poly.SetFileName(wall)
            poly.Update()
            self.assertGreater(poly.GetOutput().GetNumberOfCells(), 0)
            self.assertEqual(sorted(os.listdir(folder)), ["fluid.pvd", "fluid_000000.vti", "walls.vtp"])
        comm.Barrier()
        if comm.Get_rank() == 0:
            shutil.rmtree(folder)

    def test_world_size(self):
        self.assertGreaterEqual(MPI.COMM_WORLD.Get_size(), 1)


if __name__ == "__main__":
    unittest.main()
