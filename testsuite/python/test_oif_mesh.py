"""oif meshes: reading, checking (bad inputs name file and line), orientation
repair, the shipped meshes' volume and surface against the analytic sphere
and the Evans-Fung red blood cell, topology of the bending angles."""
import os
import re
import tempfile
import unittest

import numpy as np
from scipy.integrate import quad

import lbmd
import oif

from testsuite_data import TEST_MESHES


def evans_fung_volume_area():
    """Volume and area of the Evans & Fung (1972) discocyte with R0 = 1 by
    numerical integration of z(s) = +/- sqrt(1-s^2)(c0 + c1 s^2 + c2 s^4)/(2 R0),
    c = (0.81, 7.83, -4.39) um, R0 = 3.91 um (written independently of the
    mesh generator)."""
    c = [x / (2 * 3.91) for x in (0.81, 7.83, -4.39)]

    def g(q):
        return c[0] + c[1] * q + c[2] * q * q

    volume = 2.0 * quad(lambda s: 2 * np.pi * s * np.sqrt(1 - s * s) * g(s * s), 0, 1, epsabs=1e-13)[0]

    # area as a surface of revolution in the polar parameter a: rho = sin a,
    # z = cos a g(sin^2 a) (smooth at the rim, where dz/ds is infinite)
    def d_area(a):
        dz = -np.sin(a) * g(np.sin(a) ** 2) + np.cos(a) * (c[1] + 2 * c[2] * np.sin(a) ** 2) * 2 * np.sin(a) * np.cos(a)
        return 2 * np.pi * np.sin(a) * np.hypot(np.cos(a), dz)
    area = quad(d_area, 0, np.pi, limit=200, epsabs=1e-13)[0]
    return volume, area


class MeshFiles:
    """Write small meshes as nodes/triangles files into a temporary folder."""

    def __init__(self, folder):
        self.folder = folder
        self.count = 0

    def write(self, nodes, triangles, nodes_text=None, triangles_text=None):
        self.count += 1
        nf = os.path.join(self.folder, f"m{self.count}nodes.dat")
        tf = os.path.join(self.folder, f"m{self.count}triangles.dat")
        with open(nf, "w") as f:
            f.write(nodes_text if nodes_text is not None else
                    "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(nodes, dtype=float)))
        with open(tf, "w") as f:
            f.write(triangles_text if triangles_text is not None else
                    "".join(f"{a} {b} {c}\n" for a, b, c in triangles))
        return nf, tf


def octahedron():
    nodes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    # PyOIF orientation (normals inward)
    tris = [[0, 4, 2], [2, 4, 1], [1, 4, 3], [3, 4, 0], [0, 2, 5], [2, 1, 5], [1, 3, 5], [3, 0, 5]]
    return nodes, [list(t) for t in tris]


class TestMeshInput(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.files = MeshFiles(cls.tmp.name)
        cls.system = lbmd.System(box_l=[20.0, 20.0, 20.0])

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def cell_type(self, nf, tf, **kw):
        return oif.OifCellType(nodes_file=nf, triangles_file=tf, system=self.system, **kw)

    def assert_rejected(self, nf, tf, path, line, words, **kw):
        with self.assertRaises(ValueError) as cm:
            self.cell_type(nf, tf, **kw)
        msg = str(cm.exception)
        self.assertIn(f"{path}, line {line}", msg)
        self.assertIn(words, msg)

    def test_octahedron_reads(self):
        nodes, tris = octahedron()
        ct = self.cell_type(*self.files.write(nodes, tris))
        self.assertAlmostEqual(ct.volume0, 4.0 / 3.0, places=12)  # two pyramids of base 2, height 1
        self.assertAlmostEqual(ct.surface0, 8 * np.sqrt(3) / 2, places=12)
        self.assertEqual(ct.mesh.get_n_edges(), 12)

    def test_bad_node_lines(self):
        nodes, tris = octahedron()
        text = "1 0 0\n-1 0 0\n\n0 1 0\n0 -1\n0 0 1\n0 0 -1\n"  # line 5 has two values
        nf, tf = self.files.write(nodes, tris, nodes_text=text)
        self.assert_rejected(nf, tf, nf, 5, "expected 3")
        text = "1 0 0\n-1 0 0\n0 1 0\n0 -1 x\n0 0 1\n0 0 -1\n"
        nf, tf = self.files.write(nodes, tris, nodes_text=text)
        self.assert_rejected(nf, tf, nf, 4, "must be numbers")
        text = "1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 nan\n0 0 -1\n"
        nf, tf = self.files.write(nodes, tris, nodes_text=text)
        self.assert_rejected(nf, tf, nf, 5, "finite")

    def test_bad_triangle_lines(self):
        nodes, tris = octahedron()
        t = [list(x) for x in tris]
        t[3] = [3, 4, 6]
        nf, tf = self.files.write(nodes, t)
        self.assert_rejected(nf, tf, tf, 4, "out of range")
        t = [list(x) for x in tris]
        t[2] = [1, 4, 1]
        nf, tf = self.files.write(nodes, t)
        self.assert_rejected(nf, tf, tf, 3, "degenerate")
        text = "".join(f"{a} {b} {c}\n" for a, b, c in tris[:5]) + "1 2.5 5\n" + \
            "".join(f"{a} {b} {c}\n" for a, b, c in tris[6:])
        nf, tf = self.files.write(nodes, tris, triangles_text=text)
        self.assert_rejected(nf, tf, tf, 6, "integers")

    def test_unused_and_duplicate_nodes(self):
        nodes, tris = octahedron()
        nf, tf = self.files.write(np.vstack([nodes, [[0.5, 0.5, 0.5]]]), tris)
        self.assert_rejected(nf, tf, nf, 7, "not used")
        # node 6 at the place of node 4, used instead of 4 in two triangles
        t = [list(x) for x in tris]
        t[0] = [0, 6, 2]
        t[1] = [2, 6, 1]
        nf, tf = self.files.write(np.vstack([nodes, [[0, 0, 1]]]), t)
        self.assert_rejected(nf, tf, nf, 7, "duplicates node 4")

    def test_degenerate_area(self):
        # a flattened octahedron pole: node 4 on the equator plane between 0 and 2
        nodes, tris = octahedron()
        nodes[4] = [0.5, 0.5, 0.0]
        nf, tf = self.files.write(nodes, tris)
        self.assert_rejected(nf, tf, tf, 1, "zero area")

    def test_open_and_overfull_edges(self):
        nodes, tris = octahedron()
        nf, tf = self.files.write(nodes, tris[:-1])  # hole: last triangle removed
        with self.assertRaises(ValueError) as cm:
            self.cell_type(nf, tf)
        self.assertIn("open edge", str(cm.exception))
        self.assertRegex(str(cm.exception), re_line(tf))
        # a fin: an extra triangle on the edge (0, 4) -> edge in three triangles
        nf, tf = self.files.write(np.vstack([nodes, [[1, 1, 1]]]), tris + [[0, 4, 6]])
        with self.assertRaises(ValueError) as cm:
            self.cell_type(nf, tf)
        self.assertIn("more than two triangles", str(cm.exception))
        self.assertIn("line(s) 1, 4, 9", str(cm.exception))

    def test_non_manifold_vertex_and_two_components(self):
        nodes, tris = octahedron()
        # second octahedron touching the first at node 0 (1, 0, 0): its node 1 is our node 0
        map2 = {0: 6, 1: 0, 2: 7, 3: 8, 4: 9, 5: 10}
        second = np.array([nodes[k] + [2.0, 0.0, 0.0] for k in (0, 2, 3, 4, 5)])
        tris2 = [[map2[a] for a in t] for t in tris]
        nf, tf = self.files.write(np.vstack([nodes, second]), tris + tris2)
        with self.assertRaises(ValueError) as cm:
            self.cell_type(nf, tf)
        self.assertIn("node 0 joins separate sheets", str(cm.exception))
        self.assertRegex(str(cm.exception), re_line(tf))
        # two separate octahedra
        nodes2 = np.vstack([nodes, nodes + [5.0, 0, 0]])
        nf, tf = self.files.write(nodes2, tris + [[a + 6 for a in t] for t in tris])
        self.assert_rejected(nf, tf, tf, 9, "more than one connected surface")

    def test_orientation_detect_and_fix(self):
        nodes, tris = octahedron()
        t = [list(x) for x in tris]
        t[5] = t[5][::-1]
        nf, tf = self.files.write(nodes, t)
        self.assert_rejected(nf, tf, tf, 6, "check_orientation=True", check_orientation=False)
        ct = self.cell_type(nf, tf, check_orientation=True)
        self.assertAlmostEqual(ct.volume0, 4.0 / 3.0, places=12)
        self.assertEqual(int(ct.mesh.flipped_triangles.sum()), 1)
        # all outward-ordered: flip every triangle, volume still positive
        nf, tf = self.files.write(nodes, [x[::-1] for x in tris])
        self.assertAlmostEqual(self.cell_type(nf, tf, check_orientation=False).volume0, 4.0 / 3.0, places=12)

    def test_orientation_fix_on_large_mesh(self):
        rng = np.random.default_rng(5)
        nodes = np.loadtxt(oif.mesh_files("rbc374")[0])
        tris = np.loadtxt(oif.mesh_files("rbc374")[1], dtype=int)
        ref = self.cell_type(*oif.mesh_files("rbc374"), check_orientation=False)
        bad = tris.copy()
        flip = rng.random(len(tris)) < 0.4
        bad[flip] = bad[flip][:, ::-1]
        nf, tf = self.files.write(nodes, bad)
        ct = self.cell_type(nf, tf)
        self.assertEqual(int(ct.mesh.flipped_triangles.sum()), int(flip.sum()))
        self.assertAlmostEqual(ct.volume0, ref.volume0, places=10)
        np.testing.assert_array_equal(np.sort(ct.mesh.triangle_ids, axis=1), np.sort(tris, axis=1))
        # written back, the fixed mesh passes without check_orientation
        out = os.path.join(self.tmp.name, "fixed_triangles.dat")
        ct.mesh.output_mesh_triangles(out)
        self.assertAlmostEqual(self.cell_type(nf, out, check_orientation=False).volume0, ref.volume0, places=10)

    def test_missing_and_empty_files(self):
        nodes, tris = octahedron()
        nf, tf = self.files.write(nodes, tris)
        with self.assertRaisesRegex(ValueError, "does not exist"):
            self.cell_type(nf + "x", tf)
        nf2, tf2 = self.files.write(nodes, tris, triangles_text="# nothing\n\n")
        with self.assertRaisesRegex(ValueError, "no data"):
            self.cell_type(nf2, tf2)

    def test_meshio_formats(self):
        import meshio
        nodes = np.loadtxt(oif.mesh_files("sphere162")[0])
        tris = np.loadtxt(oif.mesh_files("sphere162")[1], dtype=int)
        ref = self.cell_type(*oif.mesh_files("sphere162"))
        for ext in ("stl", "off", "msh"):
            path = os.path.join(self.tmp.name, f"sphere.{ext}")
            kw = {"binary": False} if ext == "stl" else ({"file_format": "gmsh22", "binary": False} if ext == "msh" else {})
            meshio.write(path, meshio.Mesh(nodes, [("triangle", tris[:, ::-1])]), **kw)
            ct = self.cell_type(path, "")
            self.assertEqual(ct.mesh.get_n_nodes(), 162, ext)
            self.assertAlmostEqual(ct.volume0, ref.volume0, places=5, msg=ext)
            self.assertAlmostEqual(ct.surface0, ref.surface0, places=5, msg=ext)

    def test_unreadable_files_and_directories(self):
        nodes, tris = octahedron()
        nf, tf = self.files.write(nodes, tris)
        # binary bytes on line 3: a ValueError naming file and line, not UnicodeDecodeError
        bad = os.path.join(self.tmp.name, "binary_nodes.dat")
        with open(bad, "wb") as f:
            f.write(b"1 0 0\n-1 0 0\n0 1 \x80\xff 0\n0 -1 0\n0 0 1\n0 0 -1\n")
        with self.assertRaisesRegex(ValueError, f"{re_line(bad)[:-6]}3: not UTF-8 text"):
            self.cell_type(bad, tf)
        # an index too large for any integer type: ValueError with file and line, not OverflowError
        huge = os.path.join(self.tmp.name, "huge_triangles.dat")
        with open(huge, "w") as f:
            f.write("0 4 2\n2 4 1\n1 4 " + "9" * 30 + "\n")
        with self.assertRaisesRegex(ValueError, f"{re_line(huge)[:-6]}3: triangle node index value out of range"):
            self.cell_type(nf, huge)
        with self.assertRaisesRegex(ValueError, "is a directory"):
            self.cell_type(self.tmp.name, tf)
        with self.assertRaisesRegex(ValueError, "is a directory"):
            self.cell_type(self.tmp.name + os.sep, "")
        with self.assertRaisesRegex(TypeError, "'nodes_file' must be a file name"):
            self.cell_type(np.array(nodes), tf)

    def test_meshio_non_finite_points(self):
        nodes, tris = octahedron()
        path = os.path.join(self.tmp.name, "nan.off")
        with open(path, "w") as f:
            f.write("OFF\n6 8 0\n")
            for i, p in enumerate(nodes):
                f.write("nan 0 0\n" if i == 2 else f"{p[0]} {p[1]} {p[2]}\n")
            f.write("".join(f"3 {a} {b} {c}\n" for a, b, c in tris))
        with self.assertRaisesRegex(ValueError, "point 2 has non-finite coordinates"):
            self.cell_type(path, "")

    def test_meshio_indices_and_unparsable_files(self):
        """An OFF index -1 meant the last node to numpy (accepted, before); an
        empty .vtk made meshio call sys.exit, which ended the script."""
        nodes, tris = octahedron()
        for bad in (-1, 6):
            path = os.path.join(self.tmp.name, f"index{bad}.off")
            with open(path, "w") as f:
                f.write("OFF\n6 8 0\n" + "".join(f"{p[0]} {p[1]} {p[2]}\n" for p in nodes))
                rows = [list(t) for t in tris]
                rows[3][2] = bad
                f.write("".join(f"3 {a} {b} {c}\n" for a, b, c in rows))
            with self.assertRaisesRegex(ValueError, rf"triangle 3 .*{bad}\] refers to a node outside 0..5"):
                self.cell_type(path, "")
        empty = os.path.join(self.tmp.name, "empty.vtk")
        open(empty, "w").close()
        with self.assertRaisesRegex(ValueError, "cannot read .*empty.vtk"):
            self.cell_type(empty, "")

    def test_meshio_errors_name_the_triangle(self):
        """Files read through meshio have no line per triangle: a bad mesh is
        located by the triangle's place among the file's triangles (counted
        from 0), not by a line number (before: every one was 'line 0'), and
        nodes are named by the file's point indices, also where points were
        dropped (here an unused point 0 shifts every index by one)."""
        nodes, tris = octahedron()
        path = os.path.join(self.tmp.name, "open.off")
        with open(path, "w") as f:  # the octahedron without its triangle 5: open edges
            f.write("OFF\n7 7 0\n9 9 9\n" + "".join(f"{p[0]} {p[1]} {p[2]}\n" for p in nodes))
            f.write("".join(f"3 {a + 1} {b + 1} {c + 1}\n" for k, (a, b, c) in enumerate(tris) if k != 5))
        with self.assertRaises(ValueError) as cm:
            self.cell_type(path, "")
        msg = str(cm.exception)
        self.assertNotIn("line", msg)
        # the open edges are those of the missing triangle; the first one named
        # lies in a triangle that shares it, and that triangle is listed
        k = int(re.search(r"open[.]off, triangle ([0-9]+) \(counted from 0", msg).group(1))
        kept = [[v + 1 for v in t] for j, t in enumerate(tris) if j != 5]
        edge = [int(v) for v in re.search(r"edge \[([0-9]+), ([0-9]+)\]", msg).groups()]
        self.assertTrue(set(edge) <= set(kept[k]) and set(edge) <= {v + 1 for v in tris[5]}, msg)
        self.assertIn(f"(the file's triangle(s) {k})", msg)

    def test_from_arrays_checks(self):
        nodes, tris = octahedron()
        m = oif.Mesh.from_arrays(self.system, nodes, np.array(tris, dtype=float))  # whole floats pass
        self.assertAlmostEqual(m.volume(), 4.0 / 3.0, places=12)
        bad_nodes = nodes.copy()
        bad_nodes[4, 1] = np.nan
        cases = [(ValueError, "'nodes' must be an N x 3 array", nodes[:, :2], tris),
                 (ValueError, "'nodes' must be an N x 3 array", nodes.ravel(), tris),
                 (ValueError, r"node 4 \(row 4 of 'nodes'\) has non-finite", bad_nodes, tris),
                 (TypeError, "'nodes' must be an N x 3 array of numbers", "abc", tris),
                 (ValueError, "'triangles' must be an M x 3 array", nodes, np.ravel(tris)),
                 (ValueError, "'triangles' must be an M x 3 array", nodes, [[0, 1, 2], [0, 1]]),
                 (ValueError, r"triangle 1 \(row 1 of 'triangles'\) has non-integer", nodes,
                  np.array(tris) + np.array([[0, 0, 0]] + [[0.5, 0, 0]] * 7)),
                 (TypeError, "integer node indices", nodes, np.array(tris) > 0)]
        for exc, pattern, n, t in cases:
            with self.subTest(pattern=pattern):
                with self.assertRaisesRegex(exc, pattern):
                    oif.Mesh.from_arrays(self.system, n, t)

    def test_mesh_without_files_and_parameters(self):
        empty = oif.Mesh(system=self.system)
        for call in (empty.volume, empty.surface, empty.get_n_nodes, empty.min_angle, empty.positions):
            with self.assertRaisesRegex(ValueError, "has no nodes and triangles"):
                call()
        nf, tf = self.files.write(*octahedron())
        with self.assertRaisesRegex(ValueError, "'particle_type'"):
            oif.Mesh(nodes_file=nf, triangles_file=tf, system=self.system, particle_type=-5)
        with self.assertRaisesRegex(ValueError, "'particle_mass'"):
            oif.Mesh(nodes_file=nf, triangles_file=tf, system=self.system, particle_mass=-1)
        with self.assertRaisesRegex(TypeError, "'resize' must be 3 numbers"):
            oif.Mesh(nodes_file=nf, triangles_file=tf, system=self.system, resize=("1", "1", "1"))
        with self.assertRaisesRegex(TypeError, "'resize' must be 3 numbers"):
            self.cell_type(nf, tf, resize=("1", "1", "1"))

    def test_volume_far_from_origin(self):
        """Positions relative to a node: a cell 10^6 away keeps its volume."""
        from oif import geometry
        nodes = np.loadtxt(oif.mesh_files("sphere642")[0]) * 3.0
        tris = self.cell_type(*oif.mesh_files("sphere642")).mesh.triangle_ids
        v0 = geometry.volume(nodes, tris)
        self.assertAlmostEqual(geometry.volume(nodes + 1e6, tris) / v0, 1.0, places=9)
        self.assertEqual(str(geometry.volume(nodes, tris[:0])), "0.0")


def re_line(path):
    return f"{path.replace('.', '[.]')}, line [0-9]+"


class TestShippedMeshes(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.system = lbmd.System(box_l=[20.0, 20.0, 20.0])

    def load(self, name):
        return oif.OifCellType(*oif.mesh_files(name), system=self.system, check_orientation=False)

    def test_spheres_second_order(self):
        """Inscribed polyhedra: volume and surface below 4/3 pi and 4 pi,
        error proportional to (edge length)^2: about 4x smaller per subdivision."""
        errors = []
        for name in ("sphere162", "sphere642", "sphere2562"):
            ct = self.load(name)
            r = np.linalg.norm(ct.mesh.positions(), axis=1)
            np.testing.assert_allclose(r, 1.0, atol=1e-12)
            h = ct.mesh.aver_edge_length()
            dv = ct.volume0 / (4.0 / 3.0 * np.pi) - 1.0
            da = ct.surface0 / (4.0 * np.pi) - 1.0
            self.assertLess(dv, 0.0)
            self.assertLess(da, 0.0)
            # leading-order bounds for near-equilateral inscribed triangles
            self.assertLess(abs(dv), 0.45 * h * h, name)
            self.assertLess(abs(da), 0.25 * h * h, name)
            errors.append((dv, da))
        for (v1, a1), (v2, a2) in zip(errors, errors[1:]):
            self.assertAlmostEqual(v1 / v2, 4.0, delta=0.3)
            self.assertAlmostEqual(a1 / a2, 4.0, delta=0.3)

    def test_rbc_evans_fung(self):
        """Nodes on the Evans-Fung surface; volume and area converge to the
        integrals of the profile, error below ~(h/R)^2."""
        volume, area = evans_fung_volume_area()
        self.assertAlmostEqual(volume, 1.57405, delta=1e-4)
        prev = None
        c = [x / (2 * 3.91) for x in (0.81, 7.83, -4.39)]
        for name in ("rbc374", "rbc642", "rbc1002", "rbc2562"):
            ct = self.load(name)
            p = ct.mesh.positions()
            s2 = np.minimum(p[:, 0] ** 2 + p[:, 1] ** 2, 1.0)
            z = np.sqrt(1 - s2) * (c[0] + c[1] * s2 + c[2] * s2 * s2)
            np.testing.assert_allclose(np.abs(p[:, 2]), z, atol=1e-9)
            h = ct.mesh.aver_edge_length()
            dv = ct.volume0 / volume - 1.0
            da = ct.surface0 / area - 1.0
            self.assertLess(dv, 0.0)
            self.assertLess(da, 0.0)
            self.assertLess(abs(dv), 1.0 * h * h, name)
            self.assertLess(abs(da), 0.6 * h * h, name)
            if prev is not None:
                self.assertLess(abs(dv), abs(prev[0]))
                self.assertLess(abs(da), abs(prev[1]))
            prev = (dv, da)
        # rbc374: within 3 % in volume, 1.5 % in area
        ct = self.load("rbc374")
        self.assertLess(abs(ct.volume0 / volume - 1), 0.03)
        self.assertLess(abs(ct.surface0 / area - 1), 0.015)

    def test_espresso_meshes(self):
        """ESPResSo's PyOIF meshes read unchanged (their orientation is the
        stored one) and approximate the same Evans-Fung cell."""
        volume, area = evans_fung_volume_area()
        folder = TEST_MESHES
        for n in (141, 374, 958):
            ct = oif.OifCellType(os.path.join(folder, f"rbc{n}nodes.dat"),
                                 os.path.join(folder, f"rbc{n}triangles.dat"),
                                 system=self.system, check_orientation=False)
            self.assertFalse(ct.mesh.flipped_triangles.any())
            self.assertLess(abs(ct.volume0 / volume - 1), 0.09, n)
            self.assertLess(abs(ct.surface0 / area - 1), 0.035, n)
        ct = oif.OifCellType(os.path.join(folder, "sphere393nodes.dat"),
                             os.path.join(folder, "sphere393triangles.dat"),
                             system=self.system, check_orientation=True)
        self.assertFalse(ct.mesh.flipped_triangles.any())
        self.assertAlmostEqual(ct.volume0 / (4 / 3 * np.pi * 4 ** 3), 1, delta=0.02)

    def test_angle_topology(self):
        ct = self.load("rbc374")
        m = ct.mesh
        ang = m.angle_ids
        self.assertEqual(len(ang), m.get_n_edges())
        self.assertEqual(m.get_n_nodes() - m.get_n_edges() + m.get_n_triangles(), 2)  # sphere topology
        # every edge once, as the shared edge BC of its angle
        np.testing.assert_array_equal(np.sort(ang[:, 1:3], axis=1), m.edge_ids)
        # (B, C, A) ... the two triangles of each angle exist with the mesh's orientation:
        # D follows B -> C, A follows C -> B
        tri = {tuple(np.roll(t, k)) for t in m.triangle_ids.tolist() for k in range(3)}
        for a, b, c, d in ang.tolist():
            self.assertIn((b, c, d), tri)
            self.assertIn((c, b, a), tri)
        # relaxed dihedral angles: convex sphere all on one side of pi
        sphere = self.load("sphere642")
        phi = sphere.phi0
        self.assertTrue(np.all(phi < np.pi) or np.all(phi > np.pi))

    def test_min_angle(self):
        ct = self.load("sphere642")
        phi, ids = ct.mesh.min_angle()
        self.assertAlmostEqual(phi, ct.phi0.min())
        self.assertEqual(len(ids), 4)
        # pull one node out: the sharpest bend is at that node
        nodes = ct.mesh.positions()
        nodes[100] *= 1.5
        m = oif.Mesh.from_arrays(self.system, nodes, ct.mesh.triangle_ids)
        phi2, ids2 = m.min_angle()
        self.assertIn(100, ids2)
        self.assertLess(abs(phi2 - np.pi), 10 * abs(phi - np.pi) + 1.0)
        self.assertGreater(abs(phi2 - np.pi), abs(phi - np.pi))


if __name__ == "__main__":
    unittest.main()
