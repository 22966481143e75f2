"""lbmd.shapes: parameters read back as set, distances and normals through
Python at hand-computed points, and every bad input raising a clear
ValueError/TypeError that names the parameter."""
import math
import unittest

import numpy as np

import lbmd
import lbmd.shapes as shapes

TOL = 1e-12


class ParamsRoundTrip(unittest.TestCase):
    def check(self, shape, params):
        got = shape.get_params()
        self.assertEqual(set(got), set(params))
        for k, v in params.items():
            np.testing.assert_array_equal(got[k], v, err_msg=k)
            np.testing.assert_array_equal(getattr(shape, k), v, err_msg=k)
        self.assertIsNotNone(shape._core)
        self.assertIn(type(shape).__name__, repr(shape))

    def test_all_shapes(self):
        cases = [
            (shapes.Wall, dict(normal=[0, 0, 2], dist=1.5)),
            (shapes.Sphere, dict(center=[1, 2, 3], radius=2.5, direction=-1)),
            (shapes.Cylinder, dict(center=[1, 2, 3], axis=[0, 0, 2], radius=1.5, length=4.0,
                                   direction=-1, open=True)),
            (shapes.Rhomboid, dict(corner=[1, 1, 1], a=[2, 0, 0], b=[1, 3, 0], c=[0, 0, 4],
                                   direction=1)),
            (shapes.SimplePore, dict(center=[5, 5, 5], axis=[1, 0, 0], length=4.0, radius=1.0,
                                     smoothing_radius=0.5)),
        ]
        for cls, params in cases:
            with self.subTest(cls.__name__):
                self.check(cls(**params), params)

    def test_defaults(self):
        s = shapes.Sphere(center=[0, 0, 0], radius=1)
        self.assertEqual(s.direction, 1)
        self.assertIsInstance(s.radius, float)
        c = shapes.Cylinder(center=[0, 0, 0], axis=[1, 0, 0], radius=1, length=2)
        self.assertEqual((c.direction, c.open), (1, False))
        self.assertEqual(shapes.Rhomboid(corner=[0, 0, 0], a=[1, 0, 0], b=[0, 1, 0],
                                         c=[0, 0, 1]).direction, 1)

    def test_params_are_copies(self):
        s = shapes.Sphere(center=[1, 2, 3], radius=1)
        s.get_params()["center"][0] = 99
        np.testing.assert_array_equal(s.center, [1, 2, 3])


class DistancesThroughPython(unittest.TestCase):
    def expect(self, shape, pos, dist, normal):
        d, n = shape.calc_dist(pos)
        self.assertAlmostEqual(d, dist, delta=TOL)
        np.testing.assert_allclose(n, np.asarray(normal, float) / np.linalg.norm(normal),
                                   atol=TOL, rtol=0)
        # ESPResSo's form: the vector from the closest surface point to pos.
        d2, vec = shape.calc_distance(position=pos)
        self.assertEqual(d2, d)
        np.testing.assert_allclose(vec, d * n, atol=TOL, rtol=0)
        self.assertEqual(shape.is_inside(pos), d <= 0)

    def test_sphere(self):
        s = shapes.Sphere(center=[1, 2, 3], radius=2)
        self.expect(s, [1, 2, 6], 1.0, [0, 0, 1])
        self.expect(s, [1, 2, 3.5], -1.5, [0, 0, 1])
        h = shapes.Sphere(center=[1, 2, 3], radius=2, direction=-1)
        self.expect(h, [1, 2, 6], -1.0, [0, 0, -1])
        self.expect(h, [1, 2, 3.5], 1.5, [0, 0, -1])

    def test_cylinder(self):
        c = shapes.Cylinder(center=[0, 0, 0], axis=[0, 0, 3], radius=1, length=4)
        self.expect(c, [4, 0, 6], 5.0, [3, 0, 4])  # the rim
        self.expect(c, [0, 0, 1.8], -0.2, [0, 0, 1])  # inside, cap nearer
        self.expect(c, [0, 3, 0], 2.0, [0, 1, 0])
        pipe = shapes.Cylinder(center=[0, 0, 0], axis=[0, 0, 1], radius=1, length=4,
                               direction=-1, open=True)
        self.expect(pipe, [0.5, 0, 1.9], 0.5, [-1, 0, 0])

    def test_rhomboid(self):
        r = shapes.Rhomboid(corner=[1, 1, 1], a=[2, 0, 0], b=[0, 3, 0], c=[0, 0, 4])
        self.expect(r, [5, 6, 2], math.sqrt(8), [1, 1, 0])  # edge
        self.expect(r, [0, 0, 0], math.sqrt(3), [-1, -1, -1])  # corner
        self.expect(r, [1.5, 2, 3], -0.5, [-1, 0, 0])  # inside
        box = shapes.Rhomboid(corner=[1, 1, 1], a=[2, 0, 0], b=[0, 3, 0], c=[0, 0, 4],
                              direction=-1)
        self.expect(box, [1.5, 2, 3], 0.5, [1, 0, 0])

    def test_simple_pore(self):
        p = shapes.SimplePore(center=[0, 0, 0], axis=[0, 0, 1], length=4, radius=1,
                              smoothing_radius=0.5)
        self.expect(p, [0.5, 0, 0], 0.5, [-1, 0, 0])
        self.expect(p, [3, 0, 1.5], -0.5, [0, 0, 1])
        self.expect(p, [0.9, 0, 2.3], 0.5, [-0.6, 0, 0.8])  # the rounded mouth

    def test_union(self):
        sphere = shapes.Sphere(center=[0, 0, 5], radius=1)
        wall = shapes.Wall(normal=[0, 0, 1], dist=0)
        u = shapes.Union()
        self.assertEqual(u.size(), 0)
        self.assertEqual(u.calc_dist([0, 0, 1])[0], math.inf)
        u.add([sphere, wall])
        self.assertEqual(u.size(), 2)
        self.assertEqual(list(u), [sphere, wall])
        self.expect(u, [0, 0, 1.5], 1.5, [0, 0, 1])
        self.expect(u, [0, 0, 3.5], 0.5, [0, 0, -1])
        u.remove(sphere)
        self.expect(u, [0, 0, 3.5], 3.5, [0, 0, 1])
        self.assertEqual(u.get_params(), {"shapes": [wall]})
        u.clear()
        self.assertEqual(len(u), 0)
        u2 = shapes.Union(shapes=[sphere, wall])
        self.assertEqual(u2.shapes, [sphere, wall])
        self.expect(u2, [0, 0, 3.5], 0.5, [0, 0, -1])
        # Nested unions work; a union inside itself is refused.
        outer = shapes.Union()
        outer.add(u2)
        self.expect(outer, [0, 0, 3.5], 0.5, [0, 0, -1])
        with self.assertRaises(ValueError):
            u2.add(outer)
        # a union changed after it became a member: the outer one sees the
        # change (its bounds are not those of the time of the add)
        # and does not skip it for a nearer wall found first
        inner = shapes.Union(shapes=[shapes.Sphere(center=[0, 0, 0], radius=1)])
        outer2 = shapes.Union(shapes=[shapes.Wall(normal=[-1, 0, 0], dist=-20), inner])
        inner.add(shapes.Sphere(center=[10, 0, 0], radius=1))
        self.expect(outer2, [12.5, 0, 0], 1.5, [1, 0, 0])

    def test_signed_distances_in_one_call_equal_calc_dist(self):
        """The bulk call the seeding uses (fluid volume, clearance) gives
        each point's calc_dist exactly; beyond `range` any value >= range."""
        rng = np.random.default_rng(4)
        points = rng.uniform(-3.0, 8.0, size=(400, 3))
        for shape in (shapes.Sphere(center=[1, 2, 3], radius=2),
                      shapes.Cylinder(center=[0, 0, 0], axis=[0, 0, 3], radius=1, length=4),
                      shapes.Rhomboid(corner=[1, 1, 1], a=[2, 0, 0], b=[0, 3, 0], c=[0, 0, 4]),
                      shapes.Wall(normal=[0, 0, 1], dist=0.5),
                      shapes.SimplePore(center=[0, 0, 0], axis=[0, 0, 1], length=4, radius=1,
                                        smoothing_radius=0.5),
                      shapes.Union(shapes=[shapes.Sphere(center=[0, 0, 5], radius=1),
                                           shapes.Wall(normal=[0, 0, 1], dist=0)])):
            with self.subTest(shape=type(shape).__name__):
                one_by_one = np.array([shape.calc_dist(p)[0] for p in points])
                together = shape._core.signed_distances(points)
                np.testing.assert_array_equal(together, one_by_one)
                near = shape._core.signed_distances(points, 1.0)
                close = one_by_one < 1.0
                np.testing.assert_array_equal(near[close], one_by_one[close])
                self.assertTrue(np.all(near[~close] >= 1.0))

    def test_ported_through_lbmd_namespace(self):
        import lbmd.shapes as s2
        self.assertIs(lbmd.shapes.Sphere, s2.Sphere)


class BadInputs(unittest.TestCase):
    def raises(self, exc, name, cls, **kwargs):
        with self.assertRaises(exc) as cm:
            cls(**kwargs)
        self.assertIn(name, str(cm.exception))

    def test_bad_values(self):
        S = dict(center=[0, 0, 0], radius=1.0)
        C = dict(center=[0, 0, 0], axis=[0, 0, 1], radius=1.0, length=2.0)
        R = dict(corner=[0, 0, 0], a=[1, 0, 0], b=[0, 1, 0], c=[0, 0, 1])
        P = dict(center=[0, 0, 0], axis=[0, 0, 1], length=2.0, radius=1.0, smoothing_radius=0.5)
        V = ValueError
        T = TypeError
        cases = [
            (V, "radius", shapes.Sphere, {**S, "radius": 0}),
            (V, "radius", shapes.Sphere, {**S, "radius": -1}),
            (V, "radius", shapes.Sphere, {**S, "radius": math.nan}),
            (V, "direction", shapes.Sphere, {**S, "direction": 0}),
            (V, "direction", shapes.Sphere, {**S, "direction": 2}),
            (T, "direction", shapes.Sphere, {**S, "direction": "in"}),
            (V, "center", shapes.Sphere, {**S, "center": [0, 0]}),
            (V, "center", shapes.Sphere, {**S, "center": [0, 0, math.inf]}),
            (T, "radius", shapes.Sphere, {**S, "radius": "1"}),
            (V, "axis", shapes.Cylinder, {**C, "axis": [0, 0, 0]}),
            (V, "radius", shapes.Cylinder, {**C, "radius": 0}),
            (V, "length", shapes.Cylinder, {**C, "length": -2}),
            (V, "direction", shapes.Cylinder, {**C, "direction": -2}),
            (T, "open", shapes.Cylinder, {**C, "open": 1}),
            (V, "'c'", shapes.Rhomboid, {**R, "c": [1, 1, 0]}),
            (V, "'a'", shapes.Rhomboid, {**R, "a": [0, 0, 0]}),
            (V, "direction", shapes.Rhomboid, {**R, "direction": 3}),
            (V, "smoothing_radius", shapes.SimplePore, {**P, "smoothing_radius": 1.5}),
            (V, "smoothing_radius", shapes.SimplePore, {**P, "smoothing_radius": -0.1}),
            (V, "radius", shapes.SimplePore, {**P, "radius": 0}),
            (V, "length", shapes.SimplePore, {**P, "length": 0}),
            (V, "axis", shapes.SimplePore, {**P, "axis": [0, 0, 0]}),
            (V, "normal", shapes.Wall, dict(normal=[0, 0, 0], dist=1)),
        ]
        for exc, name, cls, kwargs in cases:
            with self.subTest(cls=cls.__name__, param=name, kwargs=kwargs):
                self.raises(exc, name, cls, **kwargs)

    def test_missing_and_unknown_kwargs(self):
        self.raises(TypeError, "radius", shapes.Sphere, center=[0, 0, 0])
        self.raises(TypeError, "smoothing_radius", shapes.SimplePore, center=[0, 0, 0],
                    axis=[0, 0, 1], length=2.0, radius=1.0)
        self.raises(TypeError, "rad", shapes.Sphere, center=[0, 0, 0], radius=1, rad=2)
        self.raises(TypeError, "opened", shapes.Cylinder, center=[0, 0, 0], axis=[0, 0, 1],
                    radius=1, length=2, opened=True)
        self.raises(TypeError, "shape_list", shapes.Union, shape_list=[])
        with self.assertRaises(TypeError):
            shapes.Sphere([0, 0, 0], 1.0)  # keywords only, as in ESPResSo

    def test_bad_positions_and_members(self):
        s = shapes.Sphere(center=[0, 0, 0], radius=1)
        for bad in ([0, 0], "abc", [0, 0, math.nan]):
            with self.subTest(pos=bad):
                with self.assertRaises((ValueError, TypeError)) as cm:
                    s.calc_dist(bad)
                self.assertIn("pos", str(cm.exception))
        u = shapes.Union()
        with self.assertRaises(TypeError) as cm:
            u.add(3)
        self.assertIn("shape", str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            u.remove(s)
        self.assertIn("shape", str(cm.exception))


if __name__ == "__main__":
    unittest.main()
