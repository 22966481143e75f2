"""ESPResSo <= 4.1 names and ESPResSo 4.2 package-level helpers that ported
PyOIF scripts use (doc/porting.md): LBFluid.print_vtk_velocity and
print_vtk_boundary, system.part[...] indexing, system.part.writevtk,
oif.norm & co., and
elastic_forces on a cell whose triangle list the script cut."""
import os
import tempfile
import unittest
import warnings

import numpy as np

import lbmd
import lbmd.old_names
import oif

from testsuite_data import TEST_MESHES

# what ESPResSo 4.2.2's object_in_fluid/__init__.py exports
ESPRESSO_422_EXPORTS = """FixedPoint PartPoint Edge Triangle Angle ThreeNeighbors Mesh OifCellType OifCell
custom_str get_triangle_normal norm vec_distance area_triangle angle_btw_triangles discard_epsilon
oif_neo_hookean_nonlin oif_calc_stretching_force oif_calc_linear_stretching_force oif_calc_bending_force
oif_calc_local_area_force oif_calc_global_area_force oif_calc_volume_force output_vtk_rhomboid
output_vtk_cylinder output_vtk_lines""".split()


class OldNames(unittest.TestCase):

    def setUp(self):
        lbmd.old_names._warned.clear()
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def record(self, fn):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fn()
        return result, [w for w in caught if issubclass(w.category, lbmd.OldNameWarning)]

    def test_lb_writers(self):
        s = lbmd.System(box_l=[6.0, 4.0, 5.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, ext_force_density=[0.01, 0, 0])
        s.actors.add(lbf)
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0)))
        s.integrator.run(5)
        for old, new in (("print_vtk_velocity", "write_vtk_velocity"), ("print_vtk_boundary", "write_vtk_boundary")):
            getattr(lbf, new)(self.path(new + ".vtk"))
            _, caught = self.record(lambda: getattr(lbf, old)(self.path(old + ".vtk")))
            self.assertEqual(len(caught), 1, old)
            self.assertIn(f"LBFluid.{old} is the ESPResSo <= 4.1 name of LBFluid.{new}", str(caught[0].message))
            with open(self.path(old + ".vtk")) as f_old, open(self.path(new + ".vtk")) as f_new:
                self.assertEqual(f_old.read(), f_new.read())
            # once per name
            _, caught = self.record(lambda: getattr(lbf, old)(self.path(old + "2.vtk")))
            self.assertEqual(caught, [])
        with self.assertRaisesRegex(ValueError, "'bb1'"):
            lbf.print_vtk_velocity(self.path("v.vtk"), bb1=[0, 0, 0], bb2=[2, 2, 2])

    def test_lb_fric(self):
        """ESPResSo <= 4.0's LBFluid(fric=gamma) (and set_lb(kT=...) without a
        fluid): the particles couple with that friction, exactly as with
        thermostat.set_lb(LB_fluid=lbf, gamma=gamma); each form warns once."""
        def run(old):
            s = lbmd.System(box_l=[8.0] * 3)
            s.time_step = 0.1
            s.cell_system.skin = 0.2
            p = s.part.add(pos=[4.0, 4.0, 4.0])
            params = dict(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[1e-3, 0, 0])
            if old:
                lbf, caught = self.record(lambda: lbmd.lb.LBFluid(fric=2.0, **params))
                self.assertEqual(len(caught), 1)
                self.assertIn("LBFluid(fric=...)", str(caught[0].message))
                s.actors.add(lbf)
                _, caught = self.record(lambda: s.thermostat.set_lb(kT=0.0))
                self.assertEqual(len(caught), 1)
            else:
                lbf = lbmd.lb.LBFluid(**params)
                s.actors.add(lbf)
                s.thermostat.set_lb(LB_fluid=lbf, gamma=2.0)
            s.integrator.run(100)
            return s.thermostat.get_state(), p.v.copy()

        old_state, old_v = run(True)
        new_state, new_v = run(False)
        self.assertEqual(old_state, new_state)
        np.testing.assert_array_equal(old_v, new_v)
        self.assertGreater(old_v[0], 0.0)  # carried by the fluid
        with self.assertRaisesRegex(ValueError, "'fric' must be >= 0"):
            lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, fric=-1.0)
        s = lbmd.System(box_l=[8.0] * 3)
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
        s.actors.add(lbf)
        with self.assertRaisesRegex(ValueError, "'kT'.*the fluid's"):
            s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0, kT=1.0)

    def test_cell_wider_than_closed_box(self):
        """ESPResSo 4.1's OIF test builds a cell wider than its non-periodic
        box: refused, the message says how to port it (doc/porting.md)."""
        s = lbmd.System(box_l=[22.0, 14.0, 15.0], periodicity=[True, True, False])
        ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(8.0,) * 3, ks=0.05)
        with self.assertRaisesRegex(ValueError, r"the cell spans z = .*not periodic.*wider than the box.*porting.md"):
            oif.OifCell(cell_type=ct, particle_type=0, origin=[11.0, 7.0, 7.5], rotate=[np.pi / 2, 0, 0])
        self.assertEqual(len(s.part), 0)

    def test_particle_indexing(self):
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        for pid in (0, 1, 2, 3, 5, 8):
            s.part.add(id=pid, pos=[pid, 0.5, 0.5], type=pid % 2)
        p, caught = self.record(lambda: s.part[3])
        self.assertEqual(p, s.part.by_id(3))
        self.assertEqual(len(caught), 1)
        self.assertIn("system.part.by_id(id)", str(caught[0].message))
        self.assertEqual(s.part[np.int64(5)].pos[0], 5.0)
        p.v = [1.0, 2.0, 3.0]  # the handle writes through
        np.testing.assert_array_equal(s.part.by_id(3).v, [1.0, 2.0, 3.0])
        # slices run over the ids 0..highest, missing ids left out (ESPResSo 4.1)
        self.assertEqual(list(s.part[:].id), [0, 1, 2, 3, 5, 8])
        self.assertEqual(list(s.part[2:6].id), [2, 3, 5])
        self.assertEqual(list(s.part[::2].id), [0, 2, 8])
        self.assertEqual(list(s.part[-3:].id), [8])
        np.testing.assert_array_equal(s.part[:].pos, s.part.all().pos)
        self.assertEqual(list(s.part[[8, 0]].id), [8, 0])
        self.assertEqual(list(s.part[np.array([1, 2])].type), [1, 0])
        with self.assertRaisesRegex(IndexError, "4 does not exist"):
            s.part[4]
        with self.assertRaisesRegex(IndexError, "4 does not exist"):
            s.part[[3, 4]]
        with self.assertRaises((TypeError, ValueError)):
            s.part["3"]
        with self.assertRaisesRegex(TypeError, "slice start"):
            s.part[0.5:3]
        s.part.clear()
        self.assertEqual(len(s.part[:]), 0)

    def test_particle_writevtk(self):
        """ESPResSo's system.part.writevtk (4.1 and 4.2): folded positions of
        the chosen types and their velocities."""
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s.part.add(pos=[[1, 2, 3], [12, 2, 3], [4, 5, 6]], v=[[1, 0, 0], [0, 2, 0], [0, 0, 3]], type=[0, 1, 2])

        def read(path):
            with open(path) as f:
                lines = f.read().splitlines()
            i = lines.index(next(ln for ln in lines if ln.startswith("POINTS")))
            n = int(lines[i].split()[1])
            pos = np.array([[float(x) for x in ln.split()] for ln in lines[i + 1:i + 1 + n]]).reshape(-1, 3)
            j = lines.index("VECTORS velocity double")
            vel = np.array([[float(x) for x in ln.split()] for ln in lines[j + 1:j + 1 + n]]).reshape(-1, 3)
            self.assertIn(f"VERTICES {n} {2 * n}", lines)
            return pos, vel

        s.part.writevtk(self.path("all.vtk"))
        pos, vel = read(self.path("all.vtk"))
        np.testing.assert_array_equal(pos, [[1, 2, 3], [2, 2, 3], [4, 5, 6]])  # folded
        np.testing.assert_array_equal(vel, [[1, 0, 0], [0, 2, 0], [0, 0, 3]])
        s.part.writevtk(self.path("some.vtk"), types=[0, 2])
        np.testing.assert_array_equal(read(self.path("some.vtk"))[1], [[1, 0, 0], [0, 0, 3]])
        s.part.writevtk(self.path("one.vtk"), types=1)
        np.testing.assert_array_equal(read(self.path("one.vtk"))[0], [[2, 2, 3]])
        s.part.writevtk(self.path("none.vtk"), types=[7])
        self.assertEqual(len(read(self.path("none.vtk"))[0]), 0)
        with self.assertRaisesRegex(ValueError, "'types'"):
            s.part.writevtk(self.path("x.vtk"), types="some")
        with self.assertRaisesRegex(ValueError, "types"):
            s.part.writevtk(self.path("x.vtk"), types=[-1])
        with self.assertRaisesRegex(TypeError, "'fname'"):
            s.part.writevtk(None)

    def test_oif_package_level_helpers(self):
        for name in ESPRESSO_422_EXPORTS:
            with self.subTest(name=name):
                self.assertTrue(hasattr(oif, name))
                self.assertIn(name, oif.__all__)
                if hasattr(oif.oif_utils, name):
                    self.assertIs(getattr(oif, name), getattr(oif.oif_utils, name))
        self.assertEqual(oif.norm([3.0, 4.0, 0.0]), 5.0)
        self.assertEqual(oif.vec_distance([1, 1, 1], [1, 4, 5]), 5.0)

    def test_elastic_forces_of_cut_mesh(self):
        """ESPResSo computes elastic_forces over the mesh's current lists: a
        script that keeps 20 triangles gets the local-area forces of those
        20, by PyOIF's per-triangle formula."""
        s = lbmd.System(box_l=[30.0, 30.0, 30.0])
        ct = oif.OifCellType(nodes_file=os.path.join(TEST_MESHES, "sphere393nodes.dat"),
                             triangles_file=os.path.join(TEST_MESHES, "sphere393triangles.dat"),
                             system=s, kal=1.0, check_orientation=False, resize=(2.0, 2.0, 2.0))
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[15.0, 15.0, 15.0])
        parts = cell.particles
        parts.pos = (parts.pos - 15.0) * [1.2, 1.0, 0.9] + 15.0
        whole = cell.elastic_forces(f_metric=(0, 0, 1, 0, 0, 0))[2]
        cell.mesh.triangles = cell.mesh.triangles[:20]
        cut = cell.elastic_forces(f_metric=(0, 0, 1, 0, 0, 0))[2]
        ref = ct.mesh.positions()
        forces = np.zeros((cell.get_n_nodes(), 3))
        for t in cell.mesh.triangles:
            f = oif.oif_calc_local_area_force(ct.kal, t.A.get_pos(), t.B.get_pos(), t.C.get_pos(),
                                              oif.area_triangle(ref[t.A.id], ref[t.B.id], ref[t.C.id]), t.area())
            for k, point in enumerate((t.A, t.B, t.C)):
                forces[point.id] += f[3 * k:3 * k + 3]
        expected = np.linalg.norm(forces, axis=1).sum()
        self.assertAlmostEqual(cut, expected, delta=1e-12 * expected)
        self.assertLess(cut, 0.2 * whole)


if __name__ == "__main__":
    unittest.main()
