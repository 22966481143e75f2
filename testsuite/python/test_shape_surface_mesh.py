"""shapes.SurfaceMesh: a closed triangulated surface as a shape.

An icosphere (4 subdivisions of an icosahedron, 5120 triangles, vertices on
the sphere of radius R = 4.3) read from ASCII and binary STL is compared with
shapes.Sphere. Its faceting error h = R - (smallest distance of a triangle's
plane from the centre) bounds |d_mesh - d_sphere| everywhere (the mesh lies
between the spheres of radii R - h and R, and every point of either surface
is within h of the other); the sign agrees exactly wherever |d_sphere| > h;
the normals agree within twice the largest angular circumradius of a triangle
seen from the centre. A cube mesh equals shapes.Rhomboid to rounding; lattice
flags of the STL sphere equal those of shapes.Sphere off the band |d| <= h.
Broken meshes (open, non-manifold, inconsistently oriented, degenerate) and
bad files are refused naming the edge, triangle or file."""
import os
import pickle
import tempfile
import unittest
import warnings

import numpy as np

import lbmd
import lbmd.checkpoint
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes as shapes

R = 4.3
CENTER = np.array([6.0, 6.0, 6.0])


def icosphere(subdivisions, radius=1.0, center=(0, 0, 0)):
    """Vertices on the sphere and outward (counter-clockwise) triangles."""
    t = (1 + 5 ** 0.5) / 2
    verts = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
             [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    faces = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
             [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
             [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    verts = [list(np.array(v) / np.linalg.norm(v)) for v in verts]
    for _ in range(subdivisions):
        cache, new_faces = {}, []

        def middle(i, j):
            key = (min(i, j), max(i, j))
            if key not in cache:
                m = np.add(verts[i], verts[j])
                verts.append(list(m / np.linalg.norm(m)))
                cache[key] = len(verts) - 1
            return cache[key]
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new_faces += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = new_faces
    return radius * np.array(verts) + np.asarray(center, float), np.array(faces)


def faceting(vertices, triangles, center, radius):
    """(h, theta): the largest gap between a triangle's plane and the sphere,
    and the largest angle between a triangle's normal and a ray from the
    centre through a point of the triangle."""
    a, b, c = (vertices[triangles[:, k]] - center for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    plane = np.einsum("ij,ij->i", a, n)
    cos = np.min([np.einsum("ij,ij->i", v, n) / radius for v in (a, b, c)], axis=0)
    return radius - plane.min(), np.arccos(cos.min())


def write_stl_ascii(path, vertices, triangles):
    with open(path, "w") as f:
        f.write("solid icosphere\n")
        for tri in triangles:
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for v in vertices[tri]:
                f.write("      vertex {!r} {!r} {!r}\n".format(*map(float, v)))
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid icosphere\n")


def write_stl_binary(path, vertices, triangles):
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    data = np.zeros(len(triangles), record)
    data["corners"] = vertices[triangles]
    with open(path, "wb") as f:
        f.write(b"binary STL written by test_shape_surface_mesh".ljust(80, b" "))
        f.write(np.uint32(len(triangles)).tobytes())
        f.write(data.tobytes())


def cube(lo=(0, 0, 0), size=(1, 1, 1)):
    corners = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    tris = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return corners * size + lo, np.array(tris)


def random_points(rng, n, lo, hi):
    return rng.uniform(lo, hi, size=(n, 3))


class Sphere(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        # float32 coordinates: what a binary STL holds; the ASCII file gets the same
        v, t = icosphere(4, R, CENTER)
        cls.vertices, cls.triangles = v.astype(np.float32).astype(float), t
        cls.h, cls.theta = faceting(cls.vertices, t, CENTER, R)
        cls.tmp = tempfile.TemporaryDirectory()
        cls.ascii = os.path.join(cls.tmp.name, "sphere_ascii.stl")
        cls.binary = os.path.join(cls.tmp.name, "sphere_binary.STL")
        write_stl_ascii(cls.ascii, cls.vertices, t)
        write_stl_binary(cls.binary, cls.vertices, t)
        cls.sphere = shapes.Sphere(center=CENTER, radius=R)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_faceting_error(self):
        # the bound the other tests use: 5120 triangles of a sphere of radius 4.3
        self.assertLess(self.h, 0.004 * R)
        self.assertLess(np.degrees(self.theta), 3.0)

    def test_ascii_and_binary_stl(self):
        a = shapes.SurfaceMesh(file=self.ascii)
        b = shapes.SurfaceMesh(file=self.binary)
        self.assertEqual(len(a.vertices), len(self.vertices))  # shared corners merged
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.triangles, b.triangles)
        self.assertAlmostEqual(a.volume, 4 / 3 * np.pi * R ** 3, delta=3 * self.h * 4 * np.pi * R ** 2)
        self.assertIn("sphere_ascii.stl", repr(a))

    def test_against_sphere(self):
        mesh = shapes.SurfaceMesh(file=self.binary)
        rng = np.random.default_rng(1)
        points = random_points(rng, 3000, CENTER - 1.6 * R, CENTER + 1.6 * R)
        # points close to the surface, where the sign is hardest
        directions = rng.normal(size=(2000, 3))
        directions /= np.linalg.norm(directions, axis=1)[:, None]
        points = np.vstack([points, CENTER + directions * R * rng.uniform(0.98, 1.02, (2000, 1))])
        n_decided = 0
        for p in points:
            d_mesh, n_mesh = mesh.calc_dist(p)
            d_sphere, n_sphere = self.sphere.calc_dist(p)
            self.assertLessEqual(abs(d_mesh - d_sphere), self.h * (1 + 1e-9) + 1e-12, msg=str(p))
            if abs(d_sphere) > self.h:
                n_decided += 1
                self.assertEqual(d_mesh > 0, d_sphere > 0, msg=str(p))
                self.assertEqual(mesh.is_inside(p), self.sphere.is_inside(p))
            self.assertAlmostEqual(np.linalg.norm(n_mesh), 1.0, delta=1e-12)
            # pos - dist * normal is on the surface
            self.assertLess(abs(mesh.calc_dist(p - d_mesh * n_mesh)[0]), 1e-9)
            if abs(np.linalg.norm(p - CENTER) - R) < 0.5 * R and abs(d_sphere) > self.h:
                angle = np.arccos(np.clip(np.dot(n_mesh, n_sphere), -1, 1))
                self.assertLessEqual(angle, 2 * self.theta, msg=str(p))
        self.assertGreater(n_decided, 4000)

    def test_direction_and_scale(self):
        hollow = shapes.SurfaceMesh(file=self.ascii, direction=-1)
        solid = shapes.SurfaceMesh(file=self.ascii)
        p = CENTER + [0.3, 1.0, -0.2]
        d, n = solid.calc_dist(p)
        dh, nh = hollow.calc_dist(p)
        self.assertLess(d, 0)
        self.assertEqual(dh, -d)
        np.testing.assert_array_equal(nh, -n)
        # scale and offset: the unit icosphere made the same sphere
        v, t = icosphere(4)
        moved = shapes.SurfaceMesh(vertices=v, triangles=t, scale=R, offset=CENTER)
        self.assertAlmostEqual(moved.calc_dist(CENTER)[0], -(R - self.h), delta=1e-6)
        self.assertAlmostEqual(moved.calc_dist(CENTER + [2 * R, 0, 0])[0], R, delta=1e-9)

    def test_lattice_flags(self):
        """Boundary nodes of the STL sphere and of an 80-triangle icosphere
        (h = 0.066 R: nodes in its band) equal those of shapes.Sphere at every
        node farther than h from the sphere, and the mesh's own is_inside in
        the band."""
        s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        s.time_step = 0.1
        lbf = s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=self.sphere))
        sphere_flags = np.asarray(lbf[:, :, :].boundary)
        self.assertGreater(sphere_flags.sum(), 300)
        nodes = np.stack(np.meshgrid(*[np.arange(12) + 0.5] * 3, indexing="ij"), axis=-1)
        d_sphere = np.linalg.norm(nodes - CENTER, axis=-1) - R
        coarse = icosphere(1, R, CENTER)
        for mesh, h in ((shapes.SurfaceMesh(file=self.ascii), self.h),
                        (shapes.SurfaceMesh(vertices=coarse[0], triangles=coarse[1]),
                         faceting(*coarse, CENTER, R)[0])):
            s.lbboundaries.clear()
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=mesh))
            mesh_flags = np.asarray(lbf[:, :, :].boundary)
            away = np.abs(d_sphere) > h
            np.testing.assert_array_equal(mesh_flags[away], sphere_flags[away])
            band = np.argwhere(~away)
            for i, j, k in band:
                self.assertEqual(mesh_flags[i, j, k], mesh.is_inside(nodes[i, j, k]))
        self.assertGreater(len(band), 100)

    def test_pickle_and_checkpoint(self):
        mesh = shapes.SurfaceMesh(file=self.binary, offset=[0.1, 0, 0])
        copy = pickle.loads(pickle.dumps(mesh))
        p = CENTER + [1.0, 2.0, 0.5]
        self.assertEqual(copy.calc_dist(p)[0], mesh.calc_dist(p)[0])
        s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        s.time_step = 0.1
        lbf = s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=mesh))
        path = os.path.join(self.tmp.name, "mesh.h5")
        lbmd.checkpoint.save(path, s, mesh=mesh, lbf=lbf)
        os.rename(self.binary, self.binary + ".moved")  # the file is not needed to load
        try:
            ns = lbmd.checkpoint.load(path)
        finally:
            os.rename(self.binary + ".moved", self.binary)
        self.assertEqual(ns.mesh.calc_dist(p)[0], mesh.calc_dist(p)[0])
        np.testing.assert_array_equal(ns.lbf[:, :, :].boundary, lbf[:, :, :].boundary)

    def test_obj_and_ply_through_meshio(self):
        import meshio
        obj = os.path.join(self.tmp.name, "sphere.obj")
        with open(obj, "w") as f:
            f.writelines("v {!r} {!r} {!r}\n".format(*v) for v in self.vertices)
            f.writelines("f {} {} {}\n".format(*(t + 1)) for t in self.triangles)
        ply = os.path.join(self.tmp.name, "sphere.ply")
        meshio.write(ply, meshio.Mesh(self.vertices, [("triangle", self.triangles.astype(np.int32))]))
        direct = shapes.SurfaceMesh(vertices=self.vertices, triangles=self.triangles)
        rng = np.random.default_rng(2)
        points = random_points(rng, 50, CENTER - 1.5 * R, CENTER + 1.5 * R)
        for path in (obj, ply):
            mesh = shapes.SurfaceMesh(file=path)
            np.testing.assert_array_equal(mesh.triangles, self.triangles)
            for p in points:
                self.assertEqual(mesh.calc_dist(p)[0], direct.calc_dist(p)[0])


def voxel_surface(voxels):
    """The boundary of a union of unit voxels (integer corners): two outward
    triangles per face between a voxel and an empty neighbour, and the faces
    as axis-aligned squares (lo, hi) for a brute-force distance."""
    filled = set(map(tuple, voxels))
    ids, triangles, squares = {}, [], []

    def vid(corner):
        return ids.setdefault(tuple(corner), len(ids))
    for v in filled:
        for axis in range(3):
            for side in (0, 1):
                step = np.eye(3, dtype=int)[axis]
                if tuple(np.add(v, step if side else -step)) in filled:
                    continue
                u, w = np.eye(3, dtype=int)[(axis + 1) % 3], np.eye(3, dtype=int)[(axis + 2) % 3]
                origin = np.add(v, side * step)
                quad = [origin, origin + u, origin + u + w, origin + w]
                if not side:  # u x w is +axis: reverse for the face at the low side
                    quad = quad[::-1]
                q = [vid(c) for c in quad]
                triangles += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                squares.append((origin, origin + u + w))
    vertices = np.array(sorted(ids, key=ids.get), float)
    return vertices, np.array(triangles), squares


class NonConvex(unittest.TestCase):
    """A U-shaped block of voxels with a voxel on top: concave edges and
    corners, where a plain face-normal sign test fails."""

    def test_against_brute_force(self):
        voxels = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (2, 1, 0), (0, 0, 1)]
        v, t, squares = voxel_surface(voxels)
        mesh = shapes.SurfaceMesh(vertices=v, triangles=t)
        self.assertAlmostEqual(mesh.volume, len(voxels), delta=1e-12)
        union = shapes.Union(shapes=[shapes.Rhomboid(corner=c, a=[1, 0, 0], b=[0, 1, 0],
                                                     c=[0, 0, 1]) for c in voxels])
        lo = np.array([[min(a[k], b[k]) for k in range(3)] for a, b in squares], float)
        hi = np.array([[max(a[k], b[k]) for k in range(3)] for a, b in squares], float)
        rng = np.random.default_rng(4)
        points = random_points(rng, 3000, [-1, -1, -1], [4, 3, 3])
        n_inside = 0
        for p in points:
            d_mesh, n_mesh = mesh.calc_dist(p)
            exact = np.linalg.norm(p - np.clip(p, lo, hi), axis=1).min()
            inside = union.is_inside(p)
            n_inside += inside
            self.assertEqual(mesh.is_inside(p), inside, msg=str(p))
            self.assertAlmostEqual(d_mesh, -exact if inside else exact, delta=1e-12, msg=str(p))
            self.assertLess(abs(mesh.calc_dist(p - d_mesh * n_mesh)[0]), 1e-12)
        self.assertGreater(n_inside, 100)
        # the same body given inside out: turned outward, the same distances
        with self.assertWarnsRegex(UserWarning, "turned outward"):
            inverted = shapes.SurfaceMesh(vertices=v, triangles=t[:, ::-1])
        for p in points[:500]:
            self.assertAlmostEqual(inverted.calc_dist(p)[0], mesh.calc_dist(p)[0], delta=1e-12)

    def test_sharp_tetrahedron(self):
        """Edges with small dihedral angles: the sign from the nearest face's
        normal alone would be wrong beside them; the pseudo-normals are not."""
        v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 3.0]])
        t = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
        mesh = shapes.SurfaceMesh(vertices=v, triangles=t)
        with self.assertWarnsRegex(UserWarning, "turned outward"):
            inverted = shapes.SurfaceMesh(vertices=v, triangles=t[:, ::-1])
        a, b, c = (v[t[:, k]] for k in range(3))
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n, axis=1)[:, None]
        rng = np.random.default_rng(5)
        n_inside = 0
        for p in random_points(rng, 4000, [-0.5, -0.5, -0.5], [1.5, 1.5, 3.5]):
            planes = np.einsum("ij,ij->i", p - a, n)  # signed distances from the 4 planes
            d_mesh = mesh.calc_dist(p)[0]
            inside = bool(np.all(planes < 0))
            n_inside += inside
            self.assertEqual(d_mesh < 0, inside, msg=str(p))
            self.assertEqual(inverted.calc_dist(p)[0] < 0, inside, msg=str(p))
            if inside:  # convex: the nearest face plane
                self.assertAlmostEqual(d_mesh, planes.max(), delta=1e-12)
            else:
                self.assertGreaterEqual(d_mesh, planes.max() - 1e-12)
        self.assertGreater(n_inside, 50)


class Cube(unittest.TestCase):

    def test_equals_rhomboid(self):
        lo, size = np.array([1.0, 2.0, 3.0]), np.array([2.0, 3.0, 4.0])
        v, t = cube(lo, size)
        mesh = shapes.SurfaceMesh(vertices=v, triangles=t)
        box = shapes.Rhomboid(corner=lo, a=[size[0], 0, 0], b=[0, size[1], 0], c=[0, 0, size[2]])
        self.assertAlmostEqual(mesh.volume, np.prod(size), delta=1e-12)
        rng = np.random.default_rng(3)
        for p in random_points(rng, 2000, lo - 2, lo + size + 2):
            d_mesh, n_mesh = mesh.calc_dist(p)
            d_box, n_box = box.calc_dist(p)
            self.assertAlmostEqual(d_mesh, d_box, delta=1e-12, msg=str(p))
            np.testing.assert_allclose(n_mesh, n_box, atol=1e-12, err_msg=str(p))
            self.assertEqual(mesh.is_inside(p), box.is_inside(p))

    def test_obj_quads(self):
        """An OBJ file of quads (read through meshio): each split in two."""
        v, _ = cube()
        quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "cube.obj")
            with open(path, "w") as f:
                f.writelines("v {} {} {}\n".format(*c) for c in v)
                f.writelines("f {} {} {} {}\n".format(*(np.add(q, 1))) for q in quads)
            mesh = shapes.SurfaceMesh(file=path, scale=2.0)
        self.assertEqual(len(mesh.triangles), 12)
        self.assertAlmostEqual(mesh.volume, 8.0, delta=1e-12)
        self.assertEqual(mesh.calc_dist([1.0, 1.0, 2.5])[0], 0.5)

    def test_inverted_turned_outward(self):
        v, t = cube()
        with self.assertWarnsRegex(UserWarning, "face inward.*turned outward"):
            mesh = shapes.SurfaceMesh(vertices=v, triangles=t[:, ::-1])
        np.testing.assert_array_equal(mesh.calc_dist([0.5, 0.5, 0.4])[1], [0, 0, -1])
        self.assertLess(mesh.calc_dist([0.5, 0.5, 0.4])[0], 0)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the kept triangles face outward: no second warning
            pickle.loads(pickle.dumps(mesh))

    def test_broken_meshes_refused(self):
        v, t = cube()
        with self.assertRaisesRegex(ValueError, r"open \(not watertight\): edge between vertices "
                                    r"0 \(0, 0, 0\) and 2 \(0, 1, 0\) belongs to only one triangle"):
            shapes.SurfaceMesh(vertices=v, triangles=t[1:])
        flipped = t.copy()
        flipped[3] = flipped[3, ::-1]
        with self.assertRaisesRegex(ValueError, "inconsistent orientation: triangles .* run "
                                    "through their shared edge between vertices"):
            shapes.SurfaceMesh(vertices=v, triangles=flipped)
        # two tetrahedra sharing the edge 0-1: four triangles on one edge
        tv = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0], [0, 0, -1]], float)
        tt = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3],
                       [0, 1, 4], [0, 5, 1], [0, 4, 5], [1, 5, 4]])
        with self.assertRaisesRegex(ValueError, r"non-manifold: edge between vertices 0 \(0, 0, 0\) "
                                    r"and 1 \(1, 0, 0\) belongs to 4 triangles"):
            shapes.SurfaceMesh(vertices=tv, triangles=tt)
        # two cubes touching at the corner (1, 1, 1): no bad edge, a bad vertex
        v2, t2 = cube(lo=(1, 1, 1))
        with self.assertRaisesRegex(ValueError, r"non-manifold at vertex 7 \(1, 1, 1\): its "
                                    "triangles form separate fans"):
            shapes.SurfaceMesh(vertices=np.vstack([v, v2[1:]]),
                               triangles=np.vstack([t, np.where(t2 == 0, 7, t2 + 7)]))
        degenerate = np.vstack([v, [0.5, 0, 0]])
        with self.assertRaisesRegex(ValueError, "triangle 0 is degenerate"):
            shapes.SurfaceMesh(vertices=degenerate, triangles=np.vstack([[[0, 8, 1]], t]))
        with self.assertRaisesRegex(ValueError, "'triangles' must be integers in 0..7, got 8"):
            shapes.SurfaceMesh(vertices=v, triangles=t + 1)
        with self.assertRaisesRegex(ValueError, "'vertices' must be an N x 3"):
            shapes.SurfaceMesh(vertices=v[:, :2], triangles=t)
        with self.assertRaisesRegex(ValueError, "vertex 2 is not finite"):
            shapes.SurfaceMesh(vertices=np.where(np.arange(8)[:, None] == 2, np.nan, v), triangles=t)
        with self.assertRaisesRegex(TypeError, "missing parameter 'file', or 'vertices'"):
            shapes.SurfaceMesh(vertices=v)
        with self.assertRaisesRegex(TypeError, "not both"):
            shapes.SurfaceMesh(file="x.stl", vertices=v, triangles=t)
        with self.assertRaisesRegex(ValueError, "scale"):
            shapes.SurfaceMesh(vertices=v, triangles=t, scale=0.0)
        with self.assertRaisesRegex(ValueError, "direction"):
            shapes.SurfaceMesh(vertices=v, triangles=t, direction=0)
        with self.assertRaises(AttributeError):
            shapes.SurfaceMesh(vertices=v, triangles=t).scale = 2.0

    def test_bad_files_refused(self):
        with tempfile.TemporaryDirectory() as tmp:
            missing = os.path.join(tmp, "missing.stl")
            with self.assertRaisesRegex(FileNotFoundError, "no such file.*missing.stl"):
                shapes.SurfaceMesh(file=missing)
            for name, content, message in (
                    ("empty.stl", b"", "empty.stl' is empty"),
                    ("empty.obj", b"", "empty.obj' is empty"),
                    ("garbage.stl", b"\xff\xfe not a mesh", "garbage.stl' is neither a binary STL"),
                    ("text.stl", b"hello\n", "text.stl' is neither a binary STL"),
                    ("bad.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2\n",
                     r"bad.stl' line 4: expected 'vertex x y z'"),
                    ("nothing.stl", b"solid x\nendsolid x\n", "nothing.stl' has no triangles"),
                    ("points.obj", b"v 0 0 0\nv 1 0 0\n", "points.obj"),
                    ("garbage.ply", b"not a ply file\n", "cannot read .*garbage.ply")):
                path = os.path.join(tmp, name)
                with open(path, "wb") as f:
                    f.write(content)
                with self.assertRaisesRegex(ValueError, message):
                    shapes.SurfaceMesh(file=path)
            # an open STL: the edge is named after reading
            v, t = cube()
            path = os.path.join(tmp, "open.stl")
            write_stl_ascii(path, v, t[:-1])
            with self.assertRaisesRegex(ValueError, "open .*belongs to only one triangle"):
                shapes.SurfaceMesh(file=path)


if __name__ == "__main__":
    unittest.main()
