"""Boundary set-up (also run on 2 ranks): the flags are computed once, by
the explicit collective step system.prepare() (which every run and every
collective data call of the fluid begins with), in one pass per boundary
over its bounding box. They equal a reference from Python (shape.is_inside
at every node centre, the first boundary in the list that contains the
node wins), whether the boundaries are added one by one, before or after
the fluid, or as one Union; adding ten boundaries flags once (the fluid's
n_flaggings counter); the fluid's plain attributes never flag (they raise
while boundaries are pending, naming system.prepare()); boundaries that
leave no fluid are refused, by name, at the first use of the fluid."""
import unittest

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes as shapes

GOOD = dict(agrid=1.0, dens=1.0, visc=1.0, tau=0.1)
BOX = (14.0, 11.0, 9.0)


def system(box=BOX, dt=0.05):
    s = lbmd.System(box_l=list(box))
    s.time_step = dt
    return s


def overlapping_shapes():
    """Overlapping shapes, some reaching out of the box (no periodic image:
    a node is tested at its centre inside the box), one unbounded."""
    return [
        shapes.Rhomboid(corner=[2.2, 1.0, -1.0], a=[6.0, 1.5, 0.0], b=[0.0, 3.0, 0.0],
                        c=[0.0, 0.0, 11.0]),
        shapes.Cylinder(center=[6.0, 4.0, 4.5], axis=[1, 1, 0], radius=2.6, length=9.0),
        shapes.Sphere(center=[13.5, 10.0, 1.0], radius=3.2),  # over a box corner
        shapes.Wall(normal=[0, 0, 1], dist=1.0),
        shapes.Sphere(center=[6.0, 4.0, 4.5], radius=1.5),  # inside the cylinder: never wins
        shapes.Rhomboid(corner=[9.0, 6.0, 2.0], a=[3.0, 0.0, 0.0], b=[0.0, 3.0, 0.0],
                        c=[0.0, 0.0, 3.0]),
        shapes.Cylinder(center=[0.5, 8.0, 4.5], axis=[0, 0, 1], radius=1.7, length=20.0),
        shapes.SimplePore(center=[7.0, 5.5, 6.0], axis=[1, 0, 0], length=4.0, radius=1.5,
                          smoothing_radius=0.5),
    ]


def reference_flags(shape_list, box, agrid):
    """0 fluid, b + 1 for the first shape b containing the node centre."""
    n = [int(round(L / agrid)) for L in box]
    flags = np.zeros(n, dtype=int)
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                pos = (np.array([i, j, k]) + 0.5) * agrid
                for b, shape in enumerate(shape_list):
                    if shape.is_inside(pos):
                        flags[i, j, k] = b + 1
                        break
    return flags


class Flags(unittest.TestCase):

    def check_against_reference(self, box, agrid):
        s = system(box)
        shape_list = overlapping_shapes()
        lbf = s.actors.add(lbmd.lb.LBFluid(**dict(GOOD, agrid=agrid)))
        for sh in shape_list:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=sh))
        flags = lbf[:, :, :].boundary
        ref = reference_flags(shape_list, box, agrid)
        # every boundary but the one hidden in the cylinder owns nodes
        self.assertEqual(sorted(set(np.unique(ref)) - {0}), [1, 2, 3, 4, 6, 7, 8])
        np.testing.assert_array_equal(flags, ref)
        return s, lbf, ref

    def test_one_by_one_equals_reference(self):
        self.check_against_reference(BOX, 1.0)

    def test_finer_lattice_equals_reference(self):
        # node centres off the integers, bounding boxes cut between nodes
        self.check_against_reference(BOX, 0.5)

    def test_boundaries_before_the_fluid(self):
        s = system()
        shape_list = overlapping_shapes()
        for sh in shape_list:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=sh))
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        np.testing.assert_array_equal(lbf[:, :, :].boundary, reference_flags(shape_list, BOX, 1.0))

    def test_union_gives_the_same_solid_nodes(self):
        s1, lbf1, ref = self.check_against_reference(BOX, 1.0)
        s2 = system()
        lbf2 = s2.actors.add(lbmd.lb.LBFluid(**GOOD))
        s2.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=shapes.Union(shapes=overlapping_shapes())))
        union_flags = lbf2[:, :, :].boundary
        np.testing.assert_array_equal(union_flags, (ref > 0).astype(int))
        self.assertEqual(lbf1._core.n_fluid_nodes, lbf2._core.n_fluid_nodes)
        self.assertEqual(lbf1._core.n_links, lbf2._core.n_links)
        self.assertEqual(lbf1._core.n_fluid_nodes, int(np.sum(ref == 0)))

    def test_unions_among_boundaries(self):
        """A Union (nested too) between other boundaries: its members flag
        its nodes, the first boundary containing a node still wins."""
        sh = overlapping_shapes()
        inner = shapes.Union(shapes=[sh[1], sh[2]])
        shape_list = [sh[4], shapes.Union(shapes=[sh[0], inner]), sh[3], shapes.Union(), sh[5],
                      shapes.Union(shapes=[sh[6], sh[7]])]
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        for x in shape_list:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=x))
        ref = reference_flags(shape_list, BOX, 1.0)
        self.assertEqual(sorted(set(np.unique(ref)) - {0}), [1, 2, 3, 5, 6])
        np.testing.assert_array_equal(lbf[:, :, :].boundary, ref)

    def test_remove_and_clear(self):
        s, lbf, _ = self.check_against_reference(BOX, 1.0)
        shape_list = [b.shape for b in s.lbboundaries]
        s.lbboundaries.remove(s.lbboundaries[1])
        del shape_list[1]
        np.testing.assert_array_equal(lbf[:, :, :].boundary, reference_flags(shape_list, BOX, 1.0))
        s.lbboundaries.clear()
        self.assertEqual(int(np.max(lbf[:, :, :].boundary)), 0)
        self.assertEqual(lbf._core.n_fluid_nodes, 14 * 11 * 9)


class Lazy(unittest.TestCase):

    def test_ten_adds_flag_once(self):
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        core = lbf._core
        before = core.n_flaggings
        for x in range(10):
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
                shape=shapes.Sphere(center=[x + 1.0, 5.0, 4.0], radius=1.2)))
        self.assertEqual(core.n_flaggings, before)
        self.assertTrue(core.boundaries_pending)
        self.assertGreater(lbf[2, 5, 4].boundary, 0)  # a collective query prepares: flags once
        self.assertEqual(core.n_flaggings, before + 1)
        self.assertFalse(core.boundaries_pending)
        lbf.total_mass()
        s.integrator.run(4)
        self.assertEqual(core.n_flaggings, before + 1)
        # a run flags too, once, whatever was added since
        for x in range(3):
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
                shape=shapes.Sphere(center=[x + 1.0, 2.0, 2.0], radius=1.0)))
        s.integrator.run(2)
        self.assertEqual(core.n_flaggings, before + 2)
        self.assertEqual(len(s.lbboundaries), 13)

    def test_every_entry_point_flags(self):
        """The collective calls begin with system.prepare(); the plain
        attributes of the fluid never communicate: they raise while
        boundaries are pending, and read after system.prepare()."""
        wall = shapes.Wall(normal=[0, 0, 1], dist=2.0)
        for query in (lambda s, lbf: lbf.total_mass(),
                      lambda s, lbf: lbf.total_momentum(),
                      lambda s, lbf: lbf[0, 0, 0].density,
                      lambda s, lbf: s.lbboundaries[0].get_force(),
                      lambda s, lbf: lbf.get_interpolated_velocity([1.0, 1.0, 1.0]),
                      lambda s, lbf: s.integrator.run(1),
                      lambda s, lbf: s.check_settings(),
                      lambda s, lbf: s.prepare()):
            s = system()
            lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=wall))
            self.assertTrue(lbf._core.boundaries_pending)
            query(s, lbf)
            self.assertFalse(lbf._core.boundaries_pending)
            self.assertEqual(lbf._core.n_fluid_nodes, 14 * 11 * 7)
        for attribute in ("n_fluid_nodes", "n_links", "local_shape", "local_origin", "decomposition",
                          "halo_bytes", "shared_halo_peers"):
            s = system()
            lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=wall))
            with self.subTest(attribute=attribute):
                with self.assertRaisesRegex(ValueError, r"call system\.prepare\(\) first"):
                    getattr(lbf._core, attribute)
                self.assertTrue(lbf._core.boundaries_pending)
                s.prepare()
                getattr(lbf._core, attribute)
                self.assertFalse(lbf._core.boundaries_pending)

    def test_populations_kept_until_flagged(self):
        """Nodes that turn solid lose their populations and come back at
        rest at dens, as before; a boundary added and removed before any
        use changes nothing (before: its nodes came back at rest)."""
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        lbf[:, :, :].velocity = [0.01, 0.0, 0.0]
        b = s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
            shape=shapes.Sphere(center=[7.0, 5.5, 4.5], radius=2.0)))
        s.lbboundaries.remove(b)
        np.testing.assert_allclose(lbf[7, 5, 4].velocity, [0.01, 0.0, 0.0], atol=1e-15)
        s.lbboundaries.add(b)
        self.assertEqual(lbf[7, 5, 4].boundary, 1)
        s.lbboundaries.remove(b)
        self.assertEqual(lbf[7, 5, 4].boundary, 0)
        np.testing.assert_allclose(lbf[7, 5, 4].velocity, [0.0, 0.0, 0.0], atol=1e-15)
        self.assertAlmostEqual(lbf[7, 5, 4].density, 1.0, delta=1e-14)


class Errors(unittest.TestCase):

    def test_cheap_checks_at_add(self):
        s = system()
        s.actors.add(lbmd.lb.LBFluid(**GOOD))
        with self.assertRaisesRegex(TypeError, "LBBoundary"):
            s.lbboundaries.add(shapes.Wall(normal=[0, 0, 1], dist=1.0))
        with self.assertRaisesRegex(ValueError, "velocity"):
            lbmd.lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, 1], dist=1.0),
                                         velocity=[0, 0, float("nan")])
        self.assertEqual(len(s.lbboundaries), 0)

    def test_no_fluid_left_named_at_first_use(self):
        s = system()
        lbf = s.actors.add(lbmd.lb.LBFluid(**GOOD))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, 1], dist=4.0)))
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=shapes.Wall(normal=[0, 0, -1], dist=-4.0)))
        msg = r"the 2 boundaries of system.lbboundaries \(0: Wall, 1: Wall\) cover every lattice node, " \
              "no fluid is left"
        for use in (lambda: lbf.total_mass(), lambda: s.integrator.run(1),
                    lambda: lbf[0, 0, 0].boundary):
            with self.assertRaisesRegex(ValueError, msg):
                use()
        s.lbboundaries.remove(s.lbboundaries[1])
        self.assertEqual(lbf[0, 0, 3].boundary, 1)
        self.assertEqual(lbf[0, 0, 4].boundary, 0)
        self.assertAlmostEqual(lbf.total_mass(), 14 * 11 * 5, delta=1e-9)


if __name__ == "__main__":
    unittest.main()
