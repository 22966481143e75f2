"""OifCell placement and analysis: rotation/translation as PyOIF, volume,
surface, diameter, centre, velocity, bounds, edge lengths, exclusions,
VTK output read back with VTK, saving and re-seeding nodes, shape VTK."""
import contextlib
import io
import os
import tempfile
import unittest

import numpy as np

import lbmd
import oif
from oif import mesh_io
from testsuite_data import TEST_MESHES

R_RBC = 3.91


def pyoif_rotation(a, b, c):
    """The rotation matrix written out as in PyOIF's Mesh.copy (angles about x, y, z)."""
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    return np.array([[cb * cc, sa * sb * cc - ca * sc, sc * sa + cc * sb * ca],
                     [cb * sc, ca * cc + sa * sb * sc, sc * sb * ca - cc * sa],
                     [-sb, cb * sa, ca * cb]])


def read_vtk(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkPolyDataReader()
    reader.SetFileName(path)
    reader.ReadAllScalarsOn()
    reader.ReadAllVectorsOn()
    reader.Update()
    poly = reader.GetOutput()
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    cells = []
    polys = poly.GetPolys()
    ids = vtk_to_numpy(polys.GetData()) if polys.GetNumberOfCells() else np.zeros(0, dtype=int)
    k = 0
    while k < len(ids):
        cells.append(ids[k + 1:k + 1 + ids[k]].tolist())
        k += ids[k] + 1
    pd = poly.GetPointData()
    data = {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}
    return pts, cells, data


class TestOifCell(unittest.TestCase):

    def setUp(self):
        self.system = lbmd.System(box_l=[40.0, 30.0, 30.0])
        self.system.time_step = 0.1
        self.tmp = tempfile.TemporaryDirectory()
        self.ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=self.system, resize=(R_RBC,) * 3)

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def test_placement_like_pyoif(self):
        rot = (0.3, -1.1, 2.0)
        origin = np.array([10.0, 12.0, 14.0])
        cell = oif.OifCell(cell_type=self.ct, particle_type=3, origin=origin, rotate=rot, particle_mass=0.5)
        nodes0 = np.loadtxt(oif.mesh_files("rbc374")[0]) * R_RBC
        expected = nodes0 @ pyoif_rotation(*rot).T + origin
        np.testing.assert_allclose(cell.mesh.positions(), expected, atol=1e-12)
        p = cell.particles
        np.testing.assert_array_equal(p.type, 3)
        np.testing.assert_allclose(p.mass, 0.5)
        np.testing.assert_array_equal(p.mol_id, cell.cell_id)
        self.assertEqual(cell.get_n_nodes(), 374)
        self.assertEqual(cell.get_n_triangles(), 744)
        self.assertEqual(cell.get_n_edges(), 1116)
        # rigid motion keeps volume, surface, edges, diameter (RBC diameter 2 R)
        self.assertAlmostEqual(cell.volume(), self.ct.volume0, places=9)
        self.assertAlmostEqual(cell.surface(), self.ct.surface0, places=9)
        # diameter: exact largest node distance; the rim nodes lie within 0.5 % of r = R
        pos = cell.mesh.positions()
        brute = max(np.linalg.norm(pos - q, axis=1).max() for q in pos)
        self.assertAlmostEqual(cell.diameter(), brute, places=12)
        self.assertLessEqual(cell.diameter(), 2 * R_RBC + 1e-9)
        self.assertGreater(cell.diameter(), 0.995 * 2 * R_RBC)
        self.assertAlmostEqual(cell.aver_edge_length(), self.ct.mesh.aver_edge_length(), places=10)
        self.assertAlmostEqual(cell.min_edge_length(), self.ct.mesh.min_edge_length(), places=10)
        self.assertAlmostEqual(cell.max_edge_length(), self.ct.mesh.max_edge_length(), places=10)
        np.testing.assert_allclose(cell.get_origin(), expected.mean(axis=0), atol=1e-12)
        # approximate centre: mean of the nodes extremal in x, y, z of the relaxed mesh
        ext = np.r_[nodes0.argmin(axis=0), nodes0.argmax(axis=0)]
        np.testing.assert_allclose(cell.get_approx_origin(), expected[ext].mean(axis=0), atol=1e-12)
        np.testing.assert_allclose(cell.get_approx_origin(), origin, atol=0.3 * R_RBC)
        b = cell.pos_bounds()
        np.testing.assert_allclose(b[0::2], expected.min(axis=0))
        np.testing.assert_allclose(b[1::2], expected.max(axis=0))

    def test_two_cells_distinct_ids_one_type(self):
        c1 = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        c2 = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[30, 15, 15])
        self.assertNotEqual(c1.cell_id, c2.cell_id)
        self.assertEqual(self.system.max_oif_objects, 2)
        self.assertEqual(len(set(c1.mesh.part_ids) & set(c2.mesh.part_ids)), 0)
        self.assertEqual(len(self.system.part), 748)

    def test_energies_per_cell(self):
        """OifCell.get_energies(): each term near zero for a relaxed cell; for
        a deformed one the volume and global-area terms equal kv/2 (V - V0)^2
        / V0 and ka_g (S - S0)^2 / (4 S0) of that cell (doc/interactions.md,
        rtol 1e-10), the other terms are positive; a modulus that is off
        gives 0.0; the cells' totals add up to the bonded energy (rtol
        1e-12), so no cell's energy is counted in another's."""
        s = self.system
        moduli = dict(ks=0.02, kb=0.01, kal=0.02, kag=0.7, kv=0.9)
        full = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(R_RBC,) * 3, **moduli)
        partial = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(R_RBC,) * 3, ks=0.02, kv=0.9)
        relaxed = oif.OifCell(cell_type=full, particle_type=0, origin=[10, 8, 8])
        rng = np.random.default_rng(5)
        deformed = []
        for ct, origin in ((full, [30, 8, 8]), (full, [10, 22, 22]), (partial, [30, 22, 22])):
            cell = oif.OifCell(cell_type=ct, particle_type=0, origin=origin)
            # stretched along x by 4 %, squeezed along y by 3 %, and rough
            x = (cell.particles.pos - origin) * [1.04, 0.97, 1.0] + rng.normal(0, 0.02, (374, 3))
            cell.particles.pos = x + origin
            deformed.append(cell)
        terms = ("stretching", "bending", "local_area", "global_area", "volume")
        e = relaxed.get_energies()
        self.assertEqual(set(e), set(terms) | {"total"})
        scale = deformed[0].get_energies()["total"]
        for term in terms:
            self.assertLess(abs(e[term]), 1e-12 * scale, term)
        total = e["total"]
        for cell in deformed:
            ct = cell.cell_type
            e = cell.get_energies()
            V, S = cell.volume(), cell.surface()
            self.assertAlmostEqual(e["volume"], 0.45 * (V - ct.volume0) ** 2 / ct.volume0,
                                   delta=1e-10 * e["volume"])
            self.assertAlmostEqual(e["global_area"], ct.kag * (S - ct.surface0) ** 2 / (4 * ct.surface0),
                                   delta=1e-10 * max(e["global_area"], 1e-300))
            on = [t for t in terms if t in ("stretching", "volume")
                  or ct is full]  # the partial type has ks and kv only
            for term in terms:
                if term in on:
                    self.assertGreater(e[term], 0.0, term)
                else:
                    self.assertEqual(e[term], 0.0, term)
            self.assertAlmostEqual(e["total"], sum(e[t] for t in terms), delta=1e-14 * e["total"])
            total += e["total"]
        # the two deformed cells of one type differ (different random parts)
        self.assertNotEqual(deformed[0].get_energies()["bending"], deformed[1].get_energies()["bending"])
        self.assertAlmostEqual(total, s.analysis.energy()["bonded"], delta=1e-12 * total)
        # all cells of a type at once: the same values, each type its own cells
        by_cell = full.get_energies()
        self.assertEqual(set(by_cell), {relaxed.cell_id, deformed[0].cell_id, deformed[1].cell_id})
        for cell in (relaxed, deformed[0], deformed[1]):
            self.assertEqual(by_cell[cell.cell_id], cell.get_energies())
        self.assertEqual(set(partial.get_energies()), {deformed[2].cell_id})

    def test_motion(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        cell.set_origin([20.0, 10.0, 5.0])
        np.testing.assert_allclose(cell.get_origin(), [20, 10, 5], atol=1e-12)
        self.assertAlmostEqual(cell.volume(), self.ct.volume0, places=9)
        cell.set_velocity([0.1, -0.2, 0.3])
        np.testing.assert_allclose(cell.get_velocity(), [0.1, -0.2, 0.3])
        cell.particles.v = np.random.default_rng(1).normal(size=(374, 3))
        np.testing.assert_allclose(cell.get_velocity(), cell.particles.v.mean(axis=0))
        # folded origin: a cell moved by whole boxes folds back
        cell.set_origin([20.0 + 2 * 40.0, 10.0 - 30.0, 5.0])
        np.testing.assert_allclose(cell.get_origin_folded(), [20, 10, 5], atol=1e-9)

    def test_rotation_angles(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[20, 15, 15])
        np.testing.assert_allclose(cell.get_rotation_angles(), 0.0, atol=1e-6)
        pos = cell.mesh.positions() - cell.get_origin()
        rot = pyoif_rotation(0.0, 0.0, 0.4)
        cell.particles.pos = pos @ rot.T + cell.get_origin()
        ang = np.array(cell.get_rotation_angles())
        ref = [oif.oif_utils.angle_btw_vectors(pos[i], rot @ pos[i]) for i in cell.rot_ids]
        np.testing.assert_allclose(ang, ref, atol=1e-9)
        # the x and y extremal nodes lie near the rotation plane: turned by about 0.4
        np.testing.assert_allclose(ang[:4], 0.4, atol=2e-3)

    def test_exclusion_rings(self):
        """Excluded pairs are those at most k edges apart (checked against a
        plain breadth-first search)."""
        m = self.ct.mesh
        nb = [set() for _ in range(m.get_n_nodes())]
        for a, b in m.edge_ids.tolist():
            nb[a].add(b)
            nb[b].add(a)
        for k in (1, 2, 3):
            expected = set()
            for s in range(m.get_n_nodes()):
                dist = {s: 0}
                front = [s]
                for d in range(k):
                    front = [y for x in front for y in nb[x] if y not in dist]
                    for y in front:
                        dist[y] = d + 1
                expected |= {(s, t) for t in dist if t > s}
            got = {tuple(p) for p in self.ct.exclusion_pairs(k).tolist()}
            self.assertEqual(got, expected)
        self.assertEqual(len(self.ct.exclusion_pairs(1)), m.get_n_edges())
        cut = 0.5 * R_RBC
        pairs = self.ct.exclusion_pairs(0, distance=cut)
        d = np.linalg.norm(m.positions()[pairs[:, 0]] - m.positions()[pairs[:, 1]], axis=1)
        self.assertTrue(np.all(d < cut))
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[20, 15, 15], exclusion_neighbours=1)
        self.assertEqual(cell.n_exclusions, m.get_n_edges())

    def test_vtk_output_reads_back(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[20, 15, 15], rotate=(0.1, 0.2, 0.3))
        forces = np.random.default_rng(2).normal(size=(374, 3))
        cell.output_vtk_pos(self.path("cell.vtk"), point_data={"force": forces, "fx": forces[:, 0]})
        pts, cells, data = read_vtk(self.path("cell.vtk"))
        np.testing.assert_allclose(pts, cell.mesh.positions(), atol=1e-12)
        self.assertEqual(len(cells), 744)
        tris = np.array(cells)
        # written with outward normals (ParaView shading): positive oriented volume
        self.assertAlmostEqual(mesh_io.signed_volume(pts, tris), self.ct.volume0, places=6)
        np.testing.assert_allclose(data["force"], forces)
        np.testing.assert_allclose(data["fx"], forces[:, 0])
        # folded: moved by box periods, written back inside the box
        cell.set_origin([20 + 40.0, 15 - 30.0, 15 + 60.0])
        cell.output_vtk_pos_folded(self.path("folded.vtk"))
        pts, _, _ = read_vtk(self.path("folded.vtk"))
        np.testing.assert_allclose(pts.mean(axis=0), [20, 15, 15], atol=1e-9)
        # PyOIF's append_point_data_to_vtk on top
        cell.append_point_data_to_vtk(self.path("folded.vtk"), "ids", np.arange(374.0), first_append=True)
        _, _, data = read_vtk(self.path("folded.vtk"))
        np.testing.assert_allclose(data["ids"], np.arange(374.0))
        with self.assertRaisesRegex(ValueError, "point data 'bad'"):
            cell.output_vtk_pos(self.path("x.vtk"), point_data={"bad": np.zeros(3)})

    def test_save_and_reseed(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        rng = np.random.default_rng(3)
        deformed = cell.mesh.positions() * [1.2, 0.9, 1.0] + rng.normal(scale=0.05, size=(374, 3))
        cell.particles.pos = deformed
        cell.output_mesh_nodes(self.path("saved_nodes.dat"))
        new = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[30, 15, 15])
        new.set_mesh_points(self.path("saved_nodes.dat"))
        np.testing.assert_allclose(new.mesh.positions() - new.get_origin(),
                                   deformed - deformed.mean(axis=0), atol=1e-12)
        np.testing.assert_allclose(new.get_origin(), [30, 15, 15] + self.ct.mesh.positions().mean(axis=0),
                                   atol=1e-12)
        self.assertAlmostEqual(new.volume(), cell.volume(), places=9)
        # the saved shape as a new cell type (relaxed state = that shape)
        ct2 = oif.OifCellType(self.path("saved_nodes.dat"), oif.mesh_files("rbc374")[1], system=self.system)
        self.assertAlmostEqual(ct2.volume0, cell.volume(), places=9)
        with self.assertRaisesRegex(ValueError, "has 6 nodes"):
            np.savetxt(self.path("few.dat"), np.zeros((6, 3)))
            new.set_mesh_points(self.path("few.dat"))

    def test_print_info_and_gamma(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.ct.print_info()
            cell.print_info()
            cell.print_mesh_analysis()
        self.assertIn("n_nodes: 374", out.getvalue())
        self.assertIn("cell_id (mol_id): 0", out.getvalue())
        # calibration point of PyOIF's formula: 393 nodes, surface 201.06, visc 1.5, dens 1.025 -> 1.82
        sphere = oif.OifCellType(os.path.join(TEST_MESHES, "sphere393nodes.dat"),
                                 os.path.join(TEST_MESHES, "sphere393triangles.dat"), system=self.system)
        g = sphere.suggest_LBgamma(visc=1.5, dens=1.025)
        self.assertAlmostEqual(g, 1.82 * np.sqrt(sphere.surface0 / 201.0619), places=12)
        # finer mesh: friction per node scales with 1/n
        self.assertAlmostEqual(cell.suggest_LBgamma(visc=1.5, dens=1.025),
                               1.82 * 393 / 374 * np.sqrt(self.ct.surface0 / 201.0619), places=12)

    def test_bad_arguments(self):
        with self.assertRaisesRegex(TypeError, "cell_type"):
            oif.OifCell(cell_type=None, particle_type=0, origin=[1, 2, 3])
        with self.assertRaisesRegex(ValueError, "origin"):
            oif.OifCell(cell_type=self.ct, particle_type=0, origin=[1, 2])
        with self.assertRaisesRegex(TypeError, "particle_type"):
            oif.OifCell(cell_type=self.ct, particle_type=-1, origin=[1, 2, 3])
        with self.assertRaisesRegex(ValueError, "particle_mass"):
            oif.OifCell(cell_type=self.ct, particle_type=0, origin=[1, 2, 3], particle_mass=0.0)
        with self.assertRaisesRegex(ValueError, "either 'ks'"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=self.system, ks=0.1, kslin=0.1)
        with self.assertRaisesRegex(ValueError, "'kb' must be >= 0"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=self.system, kb=-1.0)
        # a modulus that is no number: TypeError; NaN or infinite: ValueError
        # (as for every finite-number parameter of lbmd and oif)
        with self.assertRaisesRegex(TypeError, "'kal' must be a number"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=self.system, kal="0.1")
        with self.assertRaisesRegex(ValueError, "'kv' must be finite"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=self.system, kv=float("nan"))
        with self.assertRaisesRegex(ValueError, "'resize'"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=self.system, resize=(1.0, 0.0, 1.0))
        with self.assertRaisesRegex(TypeError, "system"):
            oif.OifCellType(*oif.mesh_files("rbc162"), system=None)
        with self.assertRaisesRegex(ValueError, "no shipped mesh 'rbc9'"):
            oif.mesh_files("rbc9")

    def test_pyoif_views(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        m = cell.mesh
        self.assertEqual(len(m.points), 374)
        p = m.points[7]
        np.testing.assert_allclose(p.get_pos(), m.positions()[7])
        self.assertEqual(p.part_id, m.part_ids[7])
        t = m.triangles[5]
        self.assertAlmostEqual(t.area(), oif.oif_utils.area_triangle(*m.positions()[m.triangle_ids[5]]))
        a = m.angles[11]
        self.assertAlmostEqual(a.size(), self.ct.phi0[11], places=10)
        e = m.edges[3]
        self.assertAlmostEqual(e.length(), self.ct.mesh.edges[3].length(), places=10)
        # a PyOIF script may restrict the triangles to analyse
        m.triangles = m.triangles[:20]
        self.assertAlmostEqual(cell.surface(), sum(t.area() for t in m.triangles[:20]), places=10)

    def test_three_neighbors_and_force_output(self):
        """PyOIF's ThreeNeighbors (normal=True) span a plane whose normal points
        out of the cell; elastic_forces writes per-node magnitudes to VTK and
        one force as raw rows."""
        ct = oif.OifCellType(*oif.mesh_files("sphere642"), system=self.system, resize=(3.0, 3.0, 3.0),
                             ks=0.05, kb=0.02, kv=0.5, normal=True)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20, 15, 15])
        centre = cell.get_origin()
        for nb, p in zip(cell.mesh.neighbors, cell.mesh.points):
            self.assertGreater(np.dot(nb.outer_normal(), p.get_pos() - centre), 0.0)
            self.assertEqual(len({nb.A.id, nb.B.id, nb.C.id}), 3)
            self.assertIn(nb.A.id, p.neighbour_ids)
        cell.particles.pos = (cell.mesh.positions() - centre) * [1.2, 1.0, 0.9] + centre
        self.system.integrator.run(0, recalc_forces=True)
        cell.elastic_forces(el_forces=(1, 1, 0, 0, 1, 1), vtk_file=self.path("el.vtk"))
        _, _, data = read_vtk(self.path("el.vtk"))
        self.assertEqual(sorted(data), ["kav_f_metric", "kb_f_metric", "ks_f_metric", "total_f_metric"])
        np.testing.assert_allclose(data["total_f_metric"], np.linalg.norm(cell.particles.f, axis=1), rtol=1e-9)
        cell.elastic_forces(el_forces=(0, 0, 0, 0, 0, 1), raw_data_file=self.path("raw.dat"))
        np.testing.assert_allclose(np.loadtxt(self.path("raw.dat")), cell.particles.f, rtol=1e-9, atol=1e-15)
        self.assertEqual(cell.elastic_forces(), 0)
        with self.assertRaisesRegex(ValueError, "exactly one"):
            cell.elastic_forces(el_forces=(1, 1, 0, 0, 0, 0), raw_data_file=self.path("raw.dat"))
        with self.assertRaisesRegex(ValueError, "vtk_file needs"):
            cell.elastic_forces(el_forces=6 * [0], vtk_file=self.path("x.vtk"))

    def test_failed_constructor_leaves_nothing(self):
        """Arguments are checked before particles are added; a failure after
        that removes the particles again and does not use up a cell id."""
        from unittest import mock
        for ids, exc in (([500], ValueError), (5, TypeError), (None, TypeError), (["a"], ValueError)):
            with self.assertRaisesRegex(exc, "'rotation_ids'"):
                oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15], rotation_ids=ids)
        with self.assertRaisesRegex(TypeError, "'particle_type'"):
            oif.OifCell(cell_type=self.ct, particle_type=2**31, origin=[10, 15, 15])
        for bad in (dict(origin=["1", "2", "3"]), dict(origin=[10, 15, 15], rotate="abc")):
            with self.assertRaisesRegex(TypeError, "must be 3 numbers"):
                oif.OifCell(cell_type=self.ct, particle_type=0, **bad)
        with mock.patch.object(oif.OifCell, "_add_bonds", side_effect=RuntimeError("engine failure")):
            with self.assertRaisesRegex(RuntimeError, "engine failure"):
                oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        self.assertEqual(len(self.system.part), 0)
        self.assertEqual(self.system.max_oif_objects, 0)
        # the last cell id: refused before anything is added (it used to add
        # the particles, then fail to advance the counter)
        self.system.max_oif_objects = 2**31 - 1
        with self.assertRaisesRegex(ValueError, "no cell ids left"):
            oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        self.assertEqual(len(self.system.part), 0)
        self.system.max_oif_objects = 0
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15], rotation_ids=[5])
        self.assertEqual(cell.cell_id, 0)
        self.assertEqual(len(self.system.part), 374)

    def test_periodic_extent_rule(self):
        """A cell as wide as a periodic box overlaps its own image, and edges
        of a quarter box would be cut by nearest-image bonds: refused. A cell
        between half and a whole box length is fine (its volume exact). Along
        an axis that is not periodic the cell must lie inside the box."""
        big = oif.OifCellType(*oif.mesh_files("sphere162"), system=self.system, resize=(16.0, 16.0, 16.0))
        with self.assertRaisesRegex(ValueError, r"spans 32(\.0*)? along y, not less than the periodic box "
                                                r"length 30.*own periodic image"):
            oif.OifCell(cell_type=big, particle_type=0, origin=[20, 15, 15])
        self.assertEqual(len(self.system.part), 0)
        # an octahedron of radius 5: 10 wide, edges 7.07
        with open(self.path("octa_nodes.dat"), "w") as f:
            f.write("5 0 0\n-5 0 0\n0 5 0\n0 -5 0\n0 0 5\n0 0 -5\n")
        with open(self.path("octa_triangles.dat"), "w") as f:
            f.write("0 2 4\n2 1 4\n1 3 4\n3 0 4\n2 0 5\n1 2 5\n3 1 5\n0 3 5\n")
        coarse = oif.OifCellType(self.path("octa_nodes.dat"), self.path("octa_triangles.dat"),
                                 system=self.system, kslin=1.0)
        self.system.box_l = [40.0, 12.0, 30.0]  # the 10-wide cell fits, its 7.07 edges do not
        with self.assertRaisesRegex(ValueError, r"longest edge 7\.07\d* is not less than a quarter of the "
                                                r"periodic box length 12 along y"):
            oif.OifCell(cell_type=coarse, particle_type=0, origin=[20, 6, 15])
        self.system.box_l = [40.0, 30.0, 30.0]
        half = oif.OifCellType(*oif.mesh_files("sphere162"), system=self.system, resize=(8.0, 8.0, 8.0))
        cell = oif.OifCell(cell_type=half, particle_type=0, origin=[20, 29, 15])  # 16 wide, across y = 30
        self.assertAlmostEqual(cell.volume(), half.volume0, places=9)
        # along an axis that is not periodic there is no image, and no room
        # either: a cell wider than the box is refused, saying how to port it
        # (ESPResSo 4.1's OIF test builds one; doc/porting.md)
        cell.mesh._parts.remove()
        self.system.periodicity = [True, False, False]
        with self.assertRaisesRegex(ValueError, r"spans y = -1\.*0*\.\.31.*not periodic.*make box_l\[1\] at "
                                                r"least 32.*porting\.md"):
            oif.OifCell(cell_type=big, particle_type=0, origin=[20, 15, 15])
        with self.assertRaisesRegex(ValueError, r"spans z = .*Move its origin so that it lies inside \(origin z "
                                                r"within 8\.\.22\)"):
            oif.OifCell(cell_type=half, particle_type=0, origin=[20, 15, 25])
        oif.OifCell(cell_type=half, particle_type=0, origin=[20, 15, 22])

    def test_stale_cell_objects(self):
        """After clear() or removal, a cell object refuses to compute on other particles."""
        oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 8, 8])  # cell_id 0
        a = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 22, 22])
        b = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[30, 15, 15])
        b.particles[5].remove()
        for call in (b.volume, b.surface, b.get_origin, b.diameter, lambda: b.mesh.positions(),
                     lambda: b.elastic_forces(f_metric=(1, 1, 1, 1, 1, 1)), lambda: b.particles,
                     lambda: b.output_vtk_pos(self.path("b.vtk")), b.print_info):
            with self.assertRaisesRegex(RuntimeError, r"OifCell \(cell_id 2\): its particles were removed"):
                call()
        self.assertFalse(os.path.exists(self.path("b.vtk")))
        self.system.part.clear()
        # new particles reuse the ids of a's particles: a must not compute on them
        # (they get mol_id 0 by default, so cell 0 could not tell; cell ids never repeat)
        self.system.part.add(pos=np.random.default_rng(0).random((1000, 3)) * 20)
        for call in (a.volume, lambda: a.set_origin([5, 5, 5]), a.get_rotation_angles):
            with self.assertRaisesRegex(RuntimeError, r"OifCell \(cell_id 1\): its particles were removed or "
                                                      r"replaced \(particle 374 has mol_id 0, not 1\)"):
                call()

    def test_output_files(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        # a symlink keeps pointing at the (rewritten) target
        target = self.path("target.vtk")
        with open(target, "w") as f:
            f.write("old\n")
        os.symlink(target, self.path("link.vtk"))
        cell.output_vtk_pos(self.path("link.vtk"))
        self.assertTrue(os.path.islink(self.path("link.vtk")))
        self.assertEqual(len(read_vtk(target)[0]), 374)
        os.mkdir(self.path("folder.vtk"))
        os.mkfifo(self.path("fifo.vtk"))
        with open(self.path("afile"), "w") as f:
            f.write("x")
        for name, pattern in (("folder.vtk", "is a directory"), ("fifo.vtk", "not a regular file"),
                              ("afile/x.vtk", "'.*afile' is a file, not a folder"), ("", "file name is empty")):
            for write in (cell.output_vtk_pos, cell.output_mesh_nodes):
                with self.subTest(name=name, write=write.__name__):
                    with self.assertRaisesRegex(ValueError, pattern):
                        write(self.path(name) if name else "")
        self.assertEqual([f for f in os.listdir(self.tmp.name) if f.endswith(".tmp")], [])
        # every writer creates a missing folder, as output_vtk_* does
        cell.output_mesh_nodes(self.path("new1/n.dat"))
        cell.output_raw_data(self.path("new2/r.dat"), data=cell.particles.v)
        self.ct.mesh.output_mesh_triangles(self.path("new3/t.dat"))
        self.ct.mesh.mirror(mirror_x=1, out_file_name=self.path("new4/m.dat"))
        cell.elastic_forces(el_forces=(0, 0, 0, 0, 0, 1), raw_data_file=self.path("new5/e.dat"))
        self.assertEqual(np.loadtxt(self.path("new1/n.dat")).shape, (374, 3))
        self.assertEqual(np.loadtxt(self.path("new3/t.dat"), dtype=int).shape, (self.ct.mesh.get_n_triangles(), 3))
        for bad in (None, "110000"):
            with self.assertRaisesRegex(TypeError, "'f_metric' must be a list of 6 flags"):
                cell.elastic_forces(f_metric=bad)
        with self.assertRaisesRegex(TypeError, "point_data must be a dict"):
            cell.output_vtk_pos(self.path("pd.vtk"), point_data=np.zeros(374))
        with self.assertRaisesRegex(TypeError, "'lbfluid'"):
            cell.total_fluid_force(None, 1.0)

    def test_append_point_data(self):
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15])
        f = self.path("c.vtk")
        with self.assertRaisesRegex(ValueError, "not an existing VTK file"):
            cell.append_point_data_to_vtk(file_name=f, data_name="a", data=np.zeros(374), first_append=True)
        self.assertFalse(os.path.exists(f))
        cell.output_vtk_pos(f)
        with self.assertRaisesRegex(ValueError, "'data_name' must be a non-empty string without spaces"):
            cell.append_point_data_to_vtk(file_name=f, data_name="a b", data=np.zeros(374), first_append=True)
        with self.assertRaisesRegex(ValueError, "no POINT_DATA section yet"):
            cell.append_point_data_to_vtk(file_name=f, data_name="a", data=np.zeros(374), first_append=False)
        cell.append_point_data_to_vtk(file_name=f, data_name="a", data=np.arange(374.0), first_append=True)
        with self.assertRaisesRegex(ValueError, "already has a POINT_DATA section"):
            cell.append_point_data_to_vtk(file_name=f, data_name="b", data=np.zeros(374), first_append=True)
        cell.append_point_data_to_vtk(file_name=f, data_name="b", data=np.ones(374), first_append=False)
        _, _, data = read_vtk(f)
        np.testing.assert_array_equal(data["a"], np.arange(374.0))
        np.testing.assert_array_equal(data["b"], np.ones(374))
        cell.output_vtk_pos(self.path("d.vtk"), point_data={"v": np.zeros(374)})
        with self.assertRaisesRegex(ValueError, "already has a POINT_DATA section"):
            cell.append_point_data_to_vtk(file_name=self.path("d.vtk"), data_name="y", data=np.zeros(374),
                                          first_append=True)

    def test_gamma_out_of_range_and_many_rings(self):
        with self.assertRaisesRegex(ValueError, "visc=0.01 and dens=0.01 are outside the range"):
            self.ct.suggest_LBgamma(visc=0.01, dens=0.01)
        # rings beyond the mesh's edge-graph diameter: all pairs, at the cost of the diameter
        cell = oif.OifCell(cell_type=self.ct, particle_type=0, origin=[10, 15, 15], exclusion_neighbours=10**7)
        self.assertEqual(cell.n_exclusions, 374 * 373 // 2)

    def test_shape_vtk(self):
        from lbmd import shapes
        rh = shapes.Rhomboid(corner=[1, 2, 3], a=[4, 0, 0], b=[0, 5, 0], c=[0, 0, 6], direction=1)
        oif.output_vtk_rhomboid(rh, out_file=self.path("rh.vtk"))
        pts, cells, _ = read_vtk(self.path("rh.vtk"))
        np.testing.assert_allclose(pts.min(axis=0), [1, 2, 3])
        np.testing.assert_allclose(pts.max(axis=0), [5, 7, 9])
        self.assertEqual(len(cells), 6)
        cyl = shapes.Cylinder(center=[5, 5, 5], axis=[1, 1, 0], radius=2.0, length=4.0, direction=1)
        oif.output_vtk_cylinder(cyl, n=24, out_file=self.path("cyl.vtk"))
        pts, cells, _ = read_vtk(self.path("cyl.vtk"))
        axis = np.array([1, 1, 0]) / np.sqrt(2)
        rel = pts - [5, 5, 5]
        along = rel @ axis
        np.testing.assert_allclose(np.abs(along), 2.0, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(rel - along[:, None] * axis, axis=1), 2.0, atol=1e-12)
        self.assertEqual(len(cells), 26)
        oif.output_vtk_pore(axis=[1, 0, 0], length=4.0, outer_rad_left=6.0, outer_rad_right=6.0,
                            pos=[10, 10, 10], rad_left=2.0, rad_right=3.0, smoothing_radius=1.0, m=5,
                            out_file=self.path("pore.vtk"))
        pts, cells, _ = read_vtk(self.path("pore.vtk"))
        r = np.hypot(pts[:, 1] - 10, pts[:, 2] - 10)
        self.assertAlmostEqual(r.min(), 2.0)
        self.assertAlmostEqual(r.max(), 6.0)


if __name__ == "__main__":
    unittest.main()
