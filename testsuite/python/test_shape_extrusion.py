"""lbmd.shapes.Extrusion: 2D layouts extruded along z. Distances and normals
at random points against a brute-force reference (every edge, even-odd
crossing number); layouts read back from DXF (written with ezdxf), SVG
(written as text) and a PNG mask (drawn with PIL); lattice flags equal to
those of the equivalent Rhomboid/Cylinder union; pickling and checkpoints;
every bad input a clear exception naming the file, polygon or parameter."""
import math
import os
import pickle
import shutil
import tempfile
import unittest

import numpy as np

import lbmd
from lbmd import checkpoint, lb, lbboundaries, shapes

RNG = np.random.default_rng(7)


def reference(polygons, z, pts):
    """(dist, normal) of pts (n, 3) by brute force over all edges."""
    a = np.concatenate([np.asarray(p, float) for p in polygons])
    b = np.concatenate([np.roll(np.asarray(p, float), -1, axis=0) for p in polygons])
    p = pts[:, None, :2]
    w = b - a
    t = np.clip(((p - a) * w).sum(-1) / (w * w).sum(-1), 0, 1)
    q = a + t[..., None] * w
    d2 = ((p - q) ** 2).sum(-1)
    best = d2.argmin(1)
    qb = q[np.arange(len(pts)), best]
    e = np.sqrt(d2.min(1))
    px, py = pts[:, None, 0], pts[:, None, 1]
    straddle = (a[:, 1] > py) != (b[:, 1] > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    inside2 = (straddle & (px < xint)).sum(1) % 2 == 1
    e = np.where(inside2, -e, e)
    zc = pts[:, 2]
    s = np.maximum(z[0] - zc, zc - z[1])
    dist = np.where((e > 0) | (s > 0), np.hypot(np.maximum(e, 0), np.maximum(s, 0)), np.maximum(e, s))
    normal = np.zeros_like(pts)
    for i in range(len(pts)):
        if dist[i] > 0:
            c = np.array([*(qb[i] if e[i] > 0 else pts[i, :2]), np.clip(zc[i], *z)])
            normal[i] = (pts[i] - c) / dist[i]
        elif e[i] >= s[i]:
            normal[i, :2] = (qb[i] - pts[i, :2]) / -e[i]
        else:
            normal[i, 2] = 1.0 if zc[i] - z[1] >= z[0] - zc[i] else -1.0
    return dist, normal


def square(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def circle(cx, cy, r, tolerance):
    """Inscribed polygon no farther than tolerance from the circle."""
    n = math.ceil(math.pi / math.acos(1 - tolerance / r))
    t = 2 * math.pi * np.arange(n) / n
    return np.stack([cx + r * np.cos(t), cy + r * np.sin(t)], 1)


L_SHAPE = np.array([[0, 0], [6, 0], [6, 2], [2, 2], [2, 5], [0, 5]], float)


class Exactness(unittest.TestCase):
    def compare(self, polygons, z, n=3000, margin=2.0):
        shape = shapes.Extrusion(polygons=polygons, z=z)
        allv = np.concatenate(polygons)
        lo = np.r_[allv.min(0) - margin, z[0] - margin]
        hi = np.r_[allv.max(0) + margin, z[1] + margin]
        pts = lo + (hi - lo) * RNG.random((n, 3))
        # some points in the slab and on vertices, edges and their extensions
        pts[: n // 4, 2] = z[0] + (z[1] - z[0]) * RNG.random(n // 4)
        pts[:20, :2] = allv[RNG.integers(0, len(allv), 20)] + RNG.normal(0, 1e-3, (20, 2))
        dist, normal = shape._core.calc_dists(pts)
        rdist, rnormal = reference(polygons, z, pts)
        np.testing.assert_allclose(dist, rdist, atol=1e-12, rtol=0)
        np.testing.assert_allclose(normal, rnormal, atol=1e-9, rtol=0)
        self.assertTrue((dist < 0).any() and (dist > 0).any())
        # one point through Python: the same as the batch
        d, nrm = shape.calc_dist(pts[0])
        self.assertEqual(d, dist[0])
        np.testing.assert_array_equal(nrm, normal[0])
        hollow = shapes.Extrusion(polygons=polygons, z=z, direction=-1)
        hd, hn = hollow._core.calc_dists(pts[:50])
        np.testing.assert_array_equal(hd, -dist[:50])
        np.testing.assert_array_equal(hn, -normal[:50])
        return shape

    def test_square_and_rhomboid(self):
        shape = self.compare([square(0, 0, 4, 3)], [1.0, 2.5])
        box = shapes.Rhomboid(corner=[0, 0, 1], a=[4, 0, 0], b=[0, 3, 0], c=[0, 0, 1.5])
        for pos in RNG.uniform(-2, 6, (300, 3)):
            d, n = shape.calc_dist(pos)
            rd, rn = box.calc_dist(pos)
            self.assertAlmostEqual(d, rd, delta=1e-12)
            np.testing.assert_allclose(n, rn, atol=1e-9)
        self.assertEqual(shape._core.num_edges(), 4)

    def test_l_shape(self):
        self.compare([L_SHAPE], [0.0, 1.0])
        self.compare([L_SHAPE[::-1]], [-1.0, 3.0])  # clockwise: the same solid

    def test_square_with_hole_and_island(self):
        polygons = [square(0, 0, 10, 10), square(2, 2, 8, 8)[::-1], square(4, 4, 6, 6)]
        shape = self.compare(polygons, [0.0, 2.0])
        self.assertLess(shape.calc_dist([1, 5, 1])[0], 0)   # the ring
        self.assertGreater(shape.calc_dist([3, 5, 1])[0], 0)  # the hole
        self.assertLess(shape.calc_dist([5, 5, 1])[0], 0)   # the island
        d, n = shape.calc_dist([3, 5, 1])
        self.assertAlmostEqual(d, 1.0, delta=1e-14)
        np.testing.assert_allclose(n, [1, 0, 0], atol=1e-15)  # out of the ring's inner face

    def test_pinched_squares(self):
        """Two squares that share one corner (diagonal pixels): the four
        sectors around the shared vertex alternate solid and free."""
        polygons = [square(0, 0, 1, 1), square(1, 1, 2, 2)]
        shape = self.compare(polygons, [0.0, 1.0], margin=0.5)
        for (x, y), inside in (((0.9, 0.95), True), ((1.1, 1.05), True),
                               ((1.1, 0.95), False), ((0.9, 1.05), False)):
            self.assertEqual(shape.is_inside([x, y, 0.5]), inside, (x, y))

    def test_circle_against_cylinder(self):
        tol = 0.01
        poly = circle(5, 5, 3, tol)
        shape = self.compare([poly], [0.0, 4.0], n=1500)
        cyl = shapes.Cylinder(center=[5, 5, 2], axis=[0, 0, 1], radius=3, length=4)
        pts = RNG.uniform([0, 0, -2], [10, 10, 6], (2000, 3))
        dist, _ = shape._core.calc_dists(pts)
        cdist = np.array([cyl.calc_dist(p)[0] for p in pts])
        self.assertLessEqual(np.abs(dist - cdist).max(), tol + 1e-12)
        self.assertGreater(np.abs(dist - cdist).max(), 0.1 * tol)  # really a polygon

    def test_many_edges(self):
        """A deep hierarchy: a wavy outline of 2000 edges with a wavy hole."""
        t = 2 * math.pi * np.arange(2000) / 2000
        r = 10 + 2 * np.sin(7 * t)
        outer = np.stack([r * np.cos(t), r * np.sin(t)], 1)
        hole = 0.4 * outer[::-4]
        shape = self.compare([outer, hole], [0.0, 5.0], n=600)
        self.assertEqual(shape._core.num_edges(), 2500)

    def test_bounding_box_and_surface(self):
        shape = shapes.Extrusion(polygons=[L_SHAPE], z=[1, 2])
        self.assertEqual(shape.calc_dist([1, 1, 1.5])[0], -min(1, 0.5))
        d, n = shape.calc_dist([4, 2, 1.5])  # on the inner face
        self.assertEqual(d, 0.0)
        np.testing.assert_allclose(n, [0, 1, 0], atol=1e-15)
        self.assertTrue(shape.is_inside([4, 2, 1.5]))
        # outside the box [lo, hi] the constraints skip the shape
        d, _ = shape.calc_dist([20, 20, 1.5])
        self.assertGreaterEqual(d, math.hypot(14, 15))


class Layouts(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="test_extrusion_")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def path(self, name):
        return os.path.join(self.dir, name)

    def test_dxf(self):
        import ezdxf
        doc = ezdxf.new()
        msp = doc.modelspace()
        msp.add_lwpolyline([(0, 0), (20, 0), (20, 10), (0, 10)], close=True, dxfattribs={"layer": "chip"})
        msp.add_circle((5, 5), 2, dxfattribs={"layer": "chip"})  # a hole
        # a slot with round ends from two LINEs and two ARCs
        msp.add_line((11, 4), (15, 4), dxfattribs={"layer": "chip"})
        msp.add_arc((15, 5), 1, -90, 90, dxfattribs={"layer": "chip"})
        msp.add_line((15, 6), (11, 6), dxfattribs={"layer": "chip"})
        msp.add_arc((11, 5), 1, 90, 270, dxfattribs={"layer": "chip"})
        # an elliptic hole, a POLYLINE island beside, a closed SPLINE island
        msp.add_ellipse((15, 8.5), major_axis=(2, 0), ratio=0.25, dxfattribs={"layer": "chip"})
        msp.add_polyline2d([(22, 1), (28, 1), (28, 3), (22, 3)], close=True, dxfattribs={"layer": "chip"})
        spline = msp.add_spline(dxfattribs={"layer": "chip"})
        spline.set_closed([(22, 5, 0), (26, 5, 0), (26, 9, 0), (22, 9, 0)])
        msp.add_text("label", dxfattribs={"layer": "chip"})
        msp.add_line((100, 100), (110, 100), dxfattribs={"layer": "notes"})
        doc.saveas(self.path("chip.dxf"))
        tol = 1e-3
        shape = shapes.Extrusion.from_dxf(self.path("chip.dxf"), layer="chip", z=[0, 3], tolerance=tol,
                                          scale=0.5, origin=(1, 1))
        self.assertEqual(len(shape.polygons), 6)
        at = lambda x, y: [1 + 0.5 * x, 1 + 0.5 * y, 1.5]  # noqa: E731 (file units to the shape's)
        self.assertFalse(shape.is_inside(at(15, 8.5)))   # in the ellipse
        self.assertTrue(shape.is_inside(at(15, 9.2)))    # beside it
        self.assertAlmostEqual(shape.calc_dist(at(15, 9.3))[0], -0.5 * 0.3, delta=0.5 * tol + 1e-12)
        self.assertTrue(shape.is_inside(at(25, 2)))      # the POLYLINE
        self.assertAlmostEqual(shape.calc_dist(at(25, 2))[0], -0.5 * 1, delta=1e-12)
        self.assertTrue(shape.is_inside(at(24, 7)))      # the spline's inside
        self.assertFalse(shape.is_inside(at(24, 10.5)))
        self.assertTrue(shape.is_inside([1 + 0.5 * 1, 1 + 0.5 * 1, 1]))
        self.assertFalse(shape.is_inside([1 + 0.5 * 5, 1 + 0.5 * 5, 1]))  # in the circle
        self.assertFalse(shape.is_inside([1 + 0.5 * 13, 1 + 0.5 * 5, 1]))  # in the slot
        d = shape.calc_dist([1 + 0.5 * 5, 1 + 0.5 * 5, 1.5])[0]
        self.assertAlmostEqual(d, 0.5 * 2, delta=0.5 * tol + 1e-12)
        d = shape.calc_dist([1 + 0.5 * 15.5, 1 + 0.5 * 5, 1.5])[0]  # the slot's round end
        self.assertAlmostEqual(d, 0.5 * 0.5, delta=0.5 * tol + 1e-12)
        # the whole file: the stray LINE on layer 'notes' closes nothing
        with self.assertRaisesRegex(ValueError, r"chip\.dxf.*LINE \(handle .*layer 'notes'\).*not part of a closed contour"):
            shapes.Extrusion.from_dxf(self.path("chip.dxf"), z=[0, 1])
        with self.assertRaisesRegex(ValueError, r"chip\.dxf.*no closed contour on layer 'nothing'"):
            shapes.Extrusion.from_dxf(self.path("chip.dxf"), layer="nothing", z=[0, 1])

    def test_dxf_flattening_tolerance(self):
        """Curves flattened with vertices on the curve and chords no farther
        than tolerance from it: a CIRCLE, a circle of two bulges, the same
        mirrored (extrusion (0, 0, -1): x -> -x in the world frame)."""
        import ezdxf
        doc = ezdxf.new()
        msp = doc.modelspace()
        msp.add_circle((0, 0), 10)
        msp.add_lwpolyline([(20, 0, 0, 0, 1.0), (30, 0, 0, 0, 1.0)], format="xyseb", close=True)
        msp.add_lwpolyline([(20, 0, 0, 0, -1.0), (30, 0, 0, 0, -1.0)], format="xyseb", close=True,
                           dxfattribs={"extrusion": (0, 0, -1)})
        doc.saveas(self.path("circles.dxf"))
        for tol in (1e-2, 1e-6):
            shape = shapes.Extrusion.from_dxf(self.path("circles.dxf"), z=[0, 1], tolerance=tol)
            for (cx, r), poly in zip([(0, 10), (25, 5), (-25, 5)], shape.polygons):
                radius = np.hypot(poly[:, 0] - cx, poly[:, 1])
                mid = 0.5 * (poly + np.roll(poly, -1, 0))
                sagitta = r - np.hypot(mid[:, 0] - cx, mid[:, 1])
                np.testing.assert_allclose(radius, r, atol=1e-12)
                self.assertLessEqual(sagitta.max(), tol * (1 + 1e-9))
                self.assertGreater(sagitta.max(), 0.3 * tol)  # not finer than asked
                self.assertAlmostEqual(shape.calc_dist([cx, 0, 0.5])[0], -0.5, delta=1e-12)

    def test_dxf_errors(self):
        import ezdxf
        doc = ezdxf.new()
        doc.modelspace().add_lwpolyline([(0, 0), (4, 4), (4, 0), (0, 4)], close=True)
        doc.saveas(self.path("bowtie.dxf"))
        with self.assertRaisesRegex(ValueError, r"bowtie\.dxf: Extrusion: LWPOLYLINE \(handle \w+, layer '0'\) "
                                                r"\(edge from vertex 0 .* crosses"):
            shapes.Extrusion.from_dxf(self.path("bowtie.dxf"), z=[0, 1])
        with self.assertRaisesRegex(FileNotFoundError, "no such file '.*missing.dxf'"):
            shapes.Extrusion.from_dxf(self.path("missing.dxf"), z=[0, 1])
        with open(self.path("garbage.dxf"), "w") as f:
            f.write("this is not a drawing\n")
        with self.assertRaisesRegex(ValueError, r"garbage\.dxf' is not a readable DXF file"):
            shapes.Extrusion.from_dxf(self.path("garbage.dxf"), z=[0, 1])
        with self.assertRaisesRegex(ValueError, "parameter 'z'"):
            shapes.Extrusion.from_dxf(self.path("bowtie.dxf"), z=[1, 1])

    def test_svg(self):
        with open(self.path("chip.svg"), "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="40" height="20" viewBox="0 0 40 20">\n'
                    '<rect id="outline" x="0" y="0" width="40" height="20"/>\n'
                    '<circle id="pillar" cx="10" cy="5" r="3"/>\n'
                    '<path id="blob" d="M 25 5 C 35 5 35 15 25 15 Z"/>\n'
                    '<line x1="0" y1="0" x2="1" y2="1"/>\n'
                    '</svg>\n')
        tol = 1e-3
        with self.assertRaisesRegex(ValueError, r"chip\.svg.*<line>.*not part of a closed contour"):
            shapes.Extrusion.from_svg(self.path("chip.svg"), z=[0, 1], tolerance=tol)
        with open(self.path("chip.svg"), "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="40" height="20" viewBox="0 0 40 20">\n'
                    '<rect id="outline" x="0" y="0" width="40" height="20"/>\n'
                    '<circle id="pillar" cx="10" cy="5" r="3"/>\n'
                    '<path id="blob" d="M 25 5 C 35 5 35 15 25 15 Z"/>\n'
                    '</svg>\n')
        shape = shapes.Extrusion.from_svg(self.path("chip.svg"), z=[0, 1], tolerance=tol)
        self.assertEqual(len(shape.polygons), 3)
        # the circle at y_svg = 5 is at y = 20 - 5 = 15 after the flip
        d = shape.calc_dist([10, 15, 0.5])[0]
        self.assertAlmostEqual(d, 3.0, delta=tol + 1e-12)
        self.assertFalse(shape.is_inside([10, 15, 0.5]))
        self.assertTrue(shape.is_inside([10, 5, 0.5]))
        self.assertFalse(shape.is_inside([28, 10, 0.5]))  # in the blob (a hole)
        self.assertTrue(shape.is_inside([34, 10, 0.5]))   # right of the blob's apex x = 32.5
        # the circle's vertices on the circle, chords within tol of it
        circle_poly = min(shape.polygons, key=lambda p: np.ptp(p[:, 0]))
        radius = np.hypot(circle_poly[:, 0] - 10, circle_poly[:, 1] - 15)
        np.testing.assert_allclose(radius, 3.0, atol=1e-9)
        mid = 0.5 * (circle_poly + np.roll(circle_poly, -1, 0))
        self.assertLessEqual((3.0 - np.hypot(mid[:, 0] - 10, mid[:, 1] - 15)).max(), tol * (1 + 1e-9))
        # a drawing in mm (viewBox units), with transforms
        with open(self.path("mm.svg"), "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="60mm" height="20mm" viewBox="0 0 60 20">\n'
                    '<g transform="translate(10,0)"><rect x="0" y="0" width="5" height="5"/></g>\n'
                    '<rect x="20" y="0" width="5" height="5" transform="scale(2)"/>\n</svg>\n')
        mm = shapes.Extrusion.from_svg(self.path("mm.svg"), z=[0, 1])
        np.testing.assert_allclose(sorted(map(tuple, mm.polygons[0])), [(10, 15), (10, 20), (15, 15), (15, 20)],
                                   atol=1e-9)
        np.testing.assert_allclose(sorted(map(tuple, mm.polygons[1])), [(40, 10), (40, 20), (50, 10), (50, 20)],
                                   atol=1e-9)
        # a viewBox drawn smaller than its units (0.1 px each): the tolerance still in units
        with open(self.path("small.svg"), "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10" viewBox="0 0 100 100">'
                    '<circle cx="50" cy="50" r="30"/></svg>')
        small = shapes.Extrusion.from_svg(self.path("small.svg"), z=[0, 1], tolerance=0.01)
        poly = small.polygons[0]
        mid = 0.5 * (poly + np.roll(poly, -1, 0))
        sagitta = 30 - np.hypot(mid[:, 0] - 50, mid[:, 1] - 50)
        self.assertTrue(0.3 * 0.01 < sagitta.max() <= 0.01 * (1 + 1e-9), sagitta.max())
        with open(self.path("bad.svg"), "w") as f:
            f.write("<svg><rect")
        with self.assertRaisesRegex(ValueError, r"bad\.svg' is not a readable SVG file"):
            shapes.Extrusion.from_svg(self.path("bad.svg"), z=[0, 1])
        with open(self.path("empty.svg"), "w") as f:
            f.write('<svg xmlns="http://www.w3.org/2000/svg" width="4" height="4"></svg>')
        with self.assertRaisesRegex(ValueError, r"empty\.svg' holds no closed contour"):
            shapes.Extrusion.from_svg(self.path("empty.svg"), z=[0, 1])

    def test_mask(self):
        from PIL import Image, ImageDraw
        img = Image.new("L", (30, 20), 255)
        draw = ImageDraw.Draw(img)
        draw.rectangle([2, 3, 20, 15], fill=0)        # a black block
        draw.rectangle([6, 6, 9, 9], fill=255)        # a white hole in it
        draw.ellipse([22, 2, 28, 8], fill=0)          # a disc
        draw.point([(25, 17), (26, 18)], fill=0)      # diagonal pixels
        img.save(self.path("mask.png"))
        px = 0.5
        shape = shapes.Extrusion.from_mask(self.path("mask.png"), pixel_size=px, z=[0, 1], origin=(1, 2))
        black = np.asarray(img) < 128
        rows, cols = black.shape
        j, i = np.mgrid[0:rows, 0:cols]
        centres = np.stack([1 + (i.ravel() + 0.5) * px, 2 + (rows - j.ravel() - 0.5) * px,
                            np.full(i.size, 0.5)], 1)
        dist, _ = shape._core.calc_dists(centres)
        np.testing.assert_array_equal(dist < 0, black.ravel())
        # exact pixel edges: a centre next to the outline is half a pixel away
        # (beside an edge or diagonally off a corner)
        near = np.abs(dist[np.abs(dist) < px]) / px
        self.assertTrue(np.all(np.isclose(near, 0.5) | np.isclose(near, math.sqrt(0.5))))
        self.assertTrue(np.isclose(near, 0.5).any() and np.isclose(near, math.sqrt(0.5)).any())
        white = shapes.Extrusion.from_mask(self.path("mask.png"), pixel_size=px, z=[0, 1], origin=(1, 2),
                                           solid="white")
        wdist, _ = white._core.calc_dists(centres)
        np.testing.assert_array_equal(wdist < 0, ~black.ravel())
        with self.assertRaisesRegex(ValueError, "pixel_size' must be > 0"):
            shapes.Extrusion.from_mask(self.path("mask.png"), pixel_size=0, z=[0, 1])
        with self.assertRaisesRegex(ValueError, "solid' must be 'black' or 'white'"):
            shapes.Extrusion.from_mask(self.path("mask.png"), pixel_size=1, z=[0, 1], solid="grey")
        # transparent black counts as white: one opaque black pixel
        rgba = Image.new("RGBA", (4, 3), (0, 0, 0, 0))
        rgba.putpixel((1, 0), (0, 0, 0, 255))
        rgba.save(self.path("alpha.png"))
        one = shapes.Extrusion.from_mask(self.path("alpha.png"), pixel_size=1, z=[0, 1])
        np.testing.assert_array_equal(sorted(map(tuple, one.polygons[0])), [(1, 2), (1, 3), (2, 2), (2, 3)])
        Image.new("L", (4, 4), 255).save(self.path("white.png"))
        with self.assertRaisesRegex(ValueError, r"white\.png' holds no closed contour"):
            shapes.Extrusion.from_mask(self.path("white.png"), pixel_size=1, z=[0, 1])
        with open(self.path("fake.png"), "w") as f:
            f.write("not an image")
        with self.assertRaisesRegex(ValueError, r"fake\.png' is not a readable image"):
            shapes.Extrusion.from_mask(self.path("fake.png"), pixel_size=1, z=[0, 1])
        with self.assertRaisesRegex(OSError, r"no such file '.*nope\.png'"):
            shapes.Extrusion.from_mask(self.path("nope.png"), pixel_size=1, z=[0, 1])

    def test_shipped_layouts(self):
        """samples/data's constriction: the DXF and the SVG give the same solid."""
        data = os.path.join(os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")),
                            "samples", "data")
        tol = 0.005
        a = shapes.Extrusion.from_dxf(os.path.join(data, "constriction.dxf"), z=[0, 20], direction=-1,
                                      tolerance=tol)
        b = shapes.Extrusion.from_svg(os.path.join(data, "constriction.svg"), z=[0, 20], direction=-1,
                                      tolerance=tol)
        pts = RNG.uniform([-1, -1, -0.5], [61, 21, 20.5], (2000, 3))
        # both flattened no farther than tol from the same arcs
        np.testing.assert_allclose(a._core.calc_dists(pts)[0], b._core.calc_dists(pts)[0], atol=2 * tol)
        self.assertAlmostEqual(a.calc_dist([30, 10, 10])[0], 3.0, delta=tol)  # the 6-wide throat
        self.assertTrue(a.is_inside([30, 10, -0.2]) and not a.is_inside([5, 10, 10]))


class Flags(unittest.TestCase):
    def flags(self, shape):
        s = lbmd.System(box_l=[16.0, 12.0, 8.0])
        s.time_step = 0.1
        lbf = s.actors.add(lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1))
        s.lbboundaries.add(lbboundaries.LBBoundary(shape=shape))
        return np.asarray(lbf[:, :, :].boundary)

    def test_equal_to_rhomboid_cylinder_union(self):
        # an L of two boxes and a round pillar, between z = 1.3 and 6.6 (no node on a face:
        # there the Rhomboid's rounding decides)
        L = np.array([[1.2, 1.2], [9.7, 1.2], [9.7, 4.3], [4.1, 4.3], [4.1, 10.6], [1.2, 10.6]])
        tol = 1e-3
        pillar = circle(12.0, 7.0, 2.3, tol)
        nodes = np.arange(16) + 0.5
        # no lattice node within the flattening tolerance of the circle
        r = np.hypot(*np.meshgrid(nodes - 12.0, np.arange(12) + 0.5 - 7.0))
        self.assertGreater(np.abs(r - 2.3).min(), tol)
        ext = shapes.Extrusion(polygons=[L, pillar], z=[1.3, 6.6])
        union = shapes.Union(shapes=[
            shapes.Rhomboid(corner=[1.2, 1.2, 1.3], a=[8.5, 0, 0], b=[0, 3.1, 0], c=[0, 0, 5.3]),
            shapes.Rhomboid(corner=[1.2, 4.3, 1.3], a=[2.9, 0, 0], b=[0, 6.3, 0], c=[0, 0, 5.3]),
            shapes.Cylinder(center=[12.0, 7.0, 3.95], axis=[0, 0, 1], radius=2.3, length=5.3)])
        f_ext, f_union = self.flags(ext), self.flags(union)
        self.assertGreater(f_ext.sum(), 100)
        np.testing.assert_array_equal(f_ext, f_union)


class Persistence(unittest.TestCase):
    def test_pickle_and_checkpoint(self):
        shape = shapes.Extrusion(polygons=[square(0, 0, 10, 10), square(2, 2, 8, 8)], z=[0, 2], direction=-1)
        pts = RNG.uniform(-1, 11, (200, 3))
        expected = shape._core.calc_dists(pts)
        again = pickle.loads(pickle.dumps(shape))
        for got, want in zip(again._core.calc_dists(pts), expected):
            np.testing.assert_array_equal(got, want)
        self.assertEqual(again.direction, -1)
        folder = tempfile.mkdtemp(prefix="test_extrusion_ckpt_")
        try:
            s = lbmd.System(box_l=[4.0, 4.0, 4.0])
            path = checkpoint.save(os.path.join(folder, "c.h5"), s, layout=shape)
            loaded = checkpoint.load(path).layout
            for got, want in zip(loaded._core.calc_dists(pts), expected):
                np.testing.assert_array_equal(got, want)
        finally:
            shutil.rmtree(folder)
        params = shape.get_params()
        params["polygons"][0][0, 0] = 99
        self.assertEqual(shape.polygons[0][0, 0], 0)
        self.assertIn("2 polygon(s), 8 vertices", repr(shape))


class BadInput(unittest.TestCase):
    def test_errors(self):
        sq = square(0, 0, 1, 1)
        cases = [
            (TypeError, "missing required parameter 'z'", dict(polygons=[sq])),
            (ValueError, r"'z' must be \[z0, z1\] with finite z0 < z1", dict(polygons=[sq], z=[2, 1])),
            (ValueError, r"'z' must be", dict(polygons=[sq], z=[0, 1, 2])),
            (ValueError, "at least one polygon", dict(polygons=[], z=[0, 1])),
            (TypeError, "'polygons' must be a list", dict(polygons=3, z=[0, 1])),
            (ValueError, r"polygon 0 must be an \(N, 2\) array", dict(polygons=[[1, 2, 3]], z=[0, 1])),
            (ValueError, "polygon 1 has vertices that are not finite",
             dict(polygons=[sq, [[0, 0], [1, np.nan], [1, 1]]], z=[0, 1])),
            (ValueError, "polygon 0 is degenerate: it has 2 distinct vertices",
             dict(polygons=[[[0, 0], [1, 1], [1, 1], [0, 0]]], z=[0, 1])),
            (ValueError, "polygon 0 is degenerate: its vertices lie on one line",
             dict(polygons=[[[0, 0], [1, 1], [2, 2]]], z=[0, 1])),
            (ValueError, r"polygon 0 \(edge from vertex 0 \(0, 0\) to vertex 1 \(2, 2\)\) crosses polygon 0 "
                         r"\(edge from vertex 2 \(2, 0\) to vertex 3 \(0, 2\)\)",
             dict(polygons=[[[0, 0], [2, 2], [2, 0], [0, 2]]], z=[0, 1])),
            (ValueError, "polygon 0 .* crosses polygon 1",
             dict(polygons=[square(0, 0, 2, 2), square(1, 1, 3, 3)], z=[0, 1])),
            (ValueError, "touches", dict(polygons=[square(0, 0, 2, 2), square(2, 0.5, 3, 1.5)], z=[0, 1])),
            (ValueError, "coincides", dict(polygons=[square(0, 0, 2, 2), square(0, 0, 2, 2)], z=[0, 1])),
            (ValueError, "direction", dict(polygons=[sq], z=[0, 1], direction=0)),
        ]
        for exc, pattern, kwargs in cases:
            with self.subTest(pattern):
                with self.assertRaisesRegex(exc, pattern):
                    shapes.Extrusion(**kwargs)
        with self.assertRaisesRegex(TypeError, "parameters are keywords"):
            shapes.Extrusion([sq], [0, 1])
        shape = shapes.Extrusion(polygons=[sq], z=[0, 1])
        with self.assertRaisesRegex(AttributeError, "cannot be changed"):
            shape.z = [0, 2]


if __name__ == "__main__":
    unittest.main()
