"""Shape-based constraints: a particle at a known distance from each shape
feels the soft-sphere force of the pair (particle type, constraint type),
F = n a (d - offset)^-(n+1) along the shape's outward normal (model eq. 8),
none beyond the range cutoff + offset; the constraint's total_force is minus
the force on the particles; a particle inside a non-penetrable shape stops
the run with SimulationInstability, inside a penetrable one it does not
and feels, as in ESPResSo, the interaction at the mirrored distance (pushed
away from the surface, deeper in), or nothing with only_positive; closer to
the surface than the offset (either side) neither force nor energy (the
energy was (d - offset)^-n there: -2000 for d = offset / 2);
a member added to or removed from a union constraint between two runs acts
from the next run's first half kick.

The distances and normals below are computed by hand (not by the code under
test): faces, edges, rims and the pore's rounded mouth, both directions."""
import contextlib
import unittest

import numpy as np

import lbmd
import lbmd.constraints
import lbmd.shapes as shapes

A, N, CUTOFF, OFFSET = 2.0, 3.0, 2.5, 0.2
RTOL = 1e-12
WALL_TYPE = 1


def soft_sphere_force(d):
    return N * A * (d - OFFSET) ** -(N + 1)


def cases():
    """(label, shape, particle position, distance, outward normal), hand-computed."""
    c = np.array([5.0, 5.0, 5.0])
    return [
        ("wall", shapes.Wall(normal=[0, 0, 2], dist=1), [5, 5, 2.5], 1.5, [0, 0, 1]),
        ("sphere", shapes.Sphere(center=c, radius=2), c + [0, 0, 3], 1.0, [0, 0, 1]),
        ("hollow sphere", shapes.Sphere(center=c, radius=3, direction=-1), c + [0, 2, 0], 1.0,
         [0, -1, 0]),
        ("cylinder rim", shapes.Cylinder(center=c, axis=[0, 0, 1], radius=2, length=4),
         c + [2.6, 0, 2.8], 1.0, [0.6, 0, 0.8]),
        ("cylinder cap", shapes.Cylinder(center=c, axis=[0, 0, -3], radius=2, length=4),
         c + [1, 1, -3.1], 1.1, [0, 0, -1]),
        ("hollow cylinder", shapes.Cylinder(center=c, axis=[0, 0, 1], radius=3, length=8,
                                            direction=-1), c + [1.5, 0, 0], 1.5, [-1, 0, 0]),
        ("open pipe", shapes.Cylinder(center=c, axis=[1, 0, 0], radius=3, length=10,
                                      direction=-1, open=True), c + [4.9, 0, -1.7], 1.3,
         [0, 0, 1]),
        ("rhomboid edge", shapes.Rhomboid(corner=[3, 3, 3], a=[4, 0, 0], b=[0, 4, 0],
                                          c=[0, 0, 4]), [7.6, 7.8, 5], 1.0, [0.6, 0.8, 0]),
        ("rhomboid corner", shapes.Rhomboid(corner=[3, 3, 3], a=[4, 0, 0], b=[0, 4, 0],
                                            c=[0, 0, 4]), [2.6, 2.2, 2.2], 1.2,
         [-1, -2, -2]),
        ("hollow rhomboid", shapes.Rhomboid(corner=[1, 1, 1], a=[8, 0, 0], b=[0, 8, 0],
                                            c=[0, 0, 8], direction=-1), [2.2, 5, 5], 1.2,
         [1, 0, 0]),
        ("pore channel", shapes.SimplePore(center=c, axis=[0, 0, 1], length=4, radius=2,
                                           smoothing_radius=1), c + [0, -0.5, 0], 1.5, [0, 1, 0]),
        ("pore rounding", shapes.SimplePore(center=c, axis=[0, 0, 1], length=4, radius=2,
                                            smoothing_radius=1), c + [1.8, 0, 2.6], 1.0,
         [-0.6, 0, 0.8]),
        ("union", shapes.Union(shapes=[shapes.Sphere(center=c, radius=1),
                                       shapes.Wall(normal=[0, 0, 1], dist=0.5)]),
         c + [0, 0, -2.5], 1.5, [0, 0, -1]),
    ]


class ShapeConstraintForces(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.system = lbmd.System(box_l=[10.0, 10.0, 10.0])
        cls.system.time_step = 0.01
        cls.system.cell_system.skin = 0.4
        cls.system.non_bonded_inter[0, WALL_TYPE].soft_sphere.set_params(
            a=A, n=N, cutoff=CUTOFF, offset=OFFSET)

    def tearDown(self):
        self.clear()

    def clear(self):
        self.system.constraints.clear()
        self.system.part.clear()

    @contextlib.contextmanager
    def cleared(self):
        """Each sub-test starts from no constraints and no particles, even
        after a failed one."""
        self.clear()
        try:
            yield
        finally:
            self.clear()

    def add(self, shape, penetrable=False, only_positive=False):
        return self.system.constraints.add(lbmd.constraints.ShapeBasedConstraint(
            shape=shape, particle_type=WALL_TYPE, penetrable=penetrable,
            only_positive=only_positive))

    def test_force_is_analytic_soft_sphere(self):
        for label, shape, pos, dist, normal in cases():
            with self.subTest(label), self.cleared():
                normal = np.asarray(normal, float) / np.linalg.norm(normal)
                # The shape agrees with the hand computation...
                d, n = shape.calc_dist(pos)
                self.assertAlmostEqual(d, dist, delta=1e-12)
                np.testing.assert_allclose(n, normal, atol=1e-12)
                # ...and the particle feels the soft sphere at that distance.
                c = self.add(shape)
                p = self.system.part.add(pos=pos, type=0)
                self.system.integrator.run(0, recalc_forces=True)
                expected = soft_sphere_force(dist) * normal
                np.testing.assert_allclose(p.f, expected, rtol=RTOL, atol=1e-14)
                np.testing.assert_allclose(c.total_force(), -expected, rtol=RTOL, atol=1e-14)

    def test_no_force_beyond_the_range(self):
        for label, shape, pos, dist, normal in cases():
            with self.subTest(label), self.cleared():
                normal = np.asarray(normal, float) / np.linalg.norm(normal)
                # Move out along the normal to just past cutoff + offset, where
                # the normal is still the same (all cases are on flat or convex parts).
                far = np.asarray(pos, float) + (CUTOFF + OFFSET + 0.01 - dist) * normal
                d, _ = shape.calc_dist(far)
                if label in ("hollow sphere", "hollow cylinder", "hollow rhomboid", "open pipe",
                             "pore channel", "union"):
                    continue  # concave free space: moving along the normal leaves the region
                self.assertAlmostEqual(d, CUTOFF + OFFSET + 0.01, delta=1e-12)
                c = self.add(shape)
                p = self.system.part.add(pos=far, type=0)
                self.system.integrator.run(0, recalc_forces=True)
                np.testing.assert_array_equal(p.f, [0, 0, 0])
                np.testing.assert_array_equal(c.total_force(), [0, 0, 0])

    def test_force_just_inside_the_range(self):
        shape = shapes.Wall(normal=[0, 0, 1], dist=1)
        self.add(shape)
        d = CUTOFF + OFFSET - 1e-3
        p = self.system.part.add(pos=[5, 5, 1 + d], type=0)
        self.system.integrator.run(0, recalc_forces=True)
        np.testing.assert_allclose(p.f, [0, 0, soft_sphere_force(d)], rtol=RTOL)

    def test_several_particles_sum_in_total_force(self):
        shape = shapes.Sphere(center=[5, 5, 5], radius=2)
        c = self.add(shape)
        dists = [0.5, 1.0, 1.7]
        dirs = np.array([[1, 0, 0], [0, -1, 0], [0, 0.6, 0.8]])
        ps = [self.system.part.add(pos=np.array([5, 5, 5]) + (2 + d) * e, type=0)
              for d, e in zip(dists, dirs)]
        # A particle of a type without an interaction with the wall type feels nothing.
        other = self.system.part.add(pos=[5, 5, 7.5], type=2)
        self.system.integrator.run(0, recalc_forces=True)
        total = np.zeros(3)
        for p, d, e in zip(ps, dists, dirs):
            np.testing.assert_allclose(p.f, soft_sphere_force(d) * e, rtol=RTOL)
            total += p.f
        np.testing.assert_array_equal(other.f, [0, 0, 0])
        np.testing.assert_allclose(c.total_force(), -total, rtol=RTOL)

    def test_runs_of_particles_near_and_far(self):
        """The constraints skip runs of consecutive particles whose box is
        farther than the range from a bounded shape's box: particles near
        one of two spheres, near the other, alternating, and far from both
        (runs of each kind, and runs that mix them) must each feel the
        analytic forces of both spheres (zero beyond the range)."""
        rng = np.random.default_rng(7)
        centres = np.array([[3.5, 3.5, 3.5], [6.5, 6.5, 6.5]])
        radius = 0.5
        constraints = [self.add(shapes.Sphere(center=centre, radius=radius)) for centre in centres]

        def force_from(k, pos):
            r = pos - centres[k]
            d = np.linalg.norm(r) - radius
            return soft_sphere_force(d) * r / np.linalg.norm(r) if d < CUTOFF + OFFSET else 0 * r

        # runs of 32 consecutive particles (the run the constraints test as a
        # whole) in patches, as a membrane's nodes lie: each near one sphere,
        # along an axis (the run's box as far from the sphere's as the
        # particles themselves) or a random direction, within or beyond the
        # range; then a run alternating between the spheres and one far from
        # both (3.3 or more)
        patches = [(k, axis * sign, d) for k in (0, 1) for axis in np.eye(3) for sign in (1, -1)
                   for d in (0.6, 1.5, 2.4, 2.9)] + [(k, None, d) for k in (0, 1) for d in (0.8, 2.0)]
        parts, expected = [], []

        def place(pos):
            parts.append(self.system.part.add(pos=pos, type=0))
            expected.append([force_from(0, pos), force_from(1, pos)])

        for k, direction, d in patches:
            if direction is None:
                direction = rng.normal(size=3)
            for _ in range(32):
                e = direction + 0.05 * rng.normal(size=3)
                e /= np.linalg.norm(e)
                place(centres[k] + (radius + d + rng.uniform(-0.05, 0.05)) * e)
        for k in [0, 1] * 16:
            e = rng.normal(size=3)
            place(centres[k] + (radius + rng.uniform(0.5, 2.9)) * e / np.linalg.norm(e))
        for _ in range(32):
            place(np.array([3.0, 7.0, 5.0]) + 0.01 * rng.normal(size=3))
        expected = np.array(expected)
        self.system.integrator.run(0, recalc_forces=True)
        for p, f in zip(parts, expected):
            np.testing.assert_allclose(p.f, f.sum(axis=0), rtol=1e-10, atol=1e-12)
        self.assertTrue(np.all(np.any(expected != 0, axis=2).sum(axis=0) > 20))  # both act
        self.assertTrue(np.all(expected[-32:] == 0))
        for k, c in enumerate(constraints):
            np.testing.assert_allclose(c.total_force(), -expected[:, k].sum(axis=0), rtol=1e-10)

    def test_penetration(self):
        # inside point, its (negative) distance and the outward normal there, by hand
        inside_points = {
            "wall": ([5, 5, 0.5], -0.5, [0, 0, 1]),
            "sphere": ([5, 5, 5.5], -1.5, [0, 0, 1]),
            "hollow sphere": ([5, 5, 9.5], -1.5, [0, 0, -1]),
            "cylinder rim": ([5.5, 5, 5], -1.5, [1, 0, 0]),
            "rhomboid edge": ([4, 4.5, 5], -1.0, [-1, 0, 0]),
            "hollow rhomboid": ([0.5, 5, 5], -0.5, [1, 0, 0]),
            "pore channel": ([5, 8, 5], -1.0, [0, -1, 0]),
            "union": ([5, 5, 0.2], -0.3, [0, 0, 1]),
        }
        mirrored = []
        for label, shape, _, _, _ in cases():
            if label not in inside_points:
                continue
            with self.subTest(label), self.cleared():
                pos, d, n = inside_points[label]
                self.assertTrue(shape.is_inside(pos))
                got_d, got_n = shape.calc_dist(pos)
                self.assertAlmostEqual(got_d, d, delta=1e-12)
                np.testing.assert_allclose(got_n, n, atol=1e-12)
                self.add(shape, penetrable=False)
                self.system.part.add(pos=pos, type=0)
                with self.assertRaises(lbmd.SimulationInstability) as cm:
                    self.system.integrator.run(0, recalc_forces=True)
                self.assertIn("penetrated", str(cm.exception))
                self.clear()
                # Penetrable: no error; from inside (distance d < 0), as in
                # ESPResSo, the interaction at the mirrored distance -d along
                # d * normal, i.e. away from the surface, deeper in...
                c = self.add(shape, penetrable=True)
                p = self.system.part.add(pos=pos, type=0)
                self.system.integrator.run(0, recalc_forces=True)
                expected = (soft_sphere_force(-d) * -np.asarray(n)
                            if OFFSET < -d < CUTOFF + OFFSET else np.zeros(3))
                np.testing.assert_allclose(p.f, expected, rtol=RTOL, atol=1e-14)
                np.testing.assert_allclose(c.total_force(), -expected, rtol=RTOL, atol=1e-14)
                mirrored.append(np.linalg.norm(expected) > 0)
                self.clear()
                # ...and none with only_positive.
                c = self.add(shape, penetrable=True, only_positive=True)
                p = self.system.part.add(pos=pos, type=0)
                self.system.integrator.run(0, recalc_forces=True)
                np.testing.assert_array_equal(p.f, [0, 0, 0])
                np.testing.assert_array_equal(c.total_force(), [0, 0, 0])
        self.assertEqual(sum(mirrored), len(inside_points))

    def test_within_the_offset_no_force_no_energy(self):
        # Closer to the surface than the soft sphere's offset (outside, or
        # inside a penetrable shape), where the potential is singular: no
        # force and a zero, finite energy (not inf or NaN in the sum).
        shape = shapes.Wall(normal=[0, 0, 1], dist=1)
        self.add(shape, penetrable=True)
        for z in (1 + 0.5 * OFFSET, 1 - 0.5 * OFFSET):
            with self.subTest(z=z):
                p = self.system.part.add(pos=[5, 5, z], type=0)
                self.system.integrator.run(0, recalc_forces=True)
                np.testing.assert_array_equal(p.f, [0, 0, 0])
                self.assertEqual(self.system.analysis.energy()["non_bonded"], 0.0)
                p.remove()

    def test_particle_held_off_a_wall_by_the_constraint(self):
        # Dynamics: a particle pushed towards a sphere by a constant external
        # force comes to rest (Langevin friction) where the soft-sphere force
        # balances it: n a (d - offset)^-(n+1) = |F_ext|.
        self.system.thermostat.set_langevin(kT=0.0, gamma=2.0, seed=1)
        try:
            shape = shapes.Sphere(center=[5, 5, 5], radius=2)
            self.add(shape)
            f_ext = 3.0
            p = self.system.part.add(pos=[5, 5, 8.5], type=0, ext_force=[0, 0, -f_ext])
            self.system.integrator.run(4000)
            d_eq = OFFSET + (N * A / f_ext) ** (1.0 / (N + 1))
            self.assertAlmostEqual(p.pos[2] - 7.0, d_eq, delta=1e-6)
            np.testing.assert_allclose(p.v, [0, 0, 0], atol=1e-6)
        finally:
            self.system.thermostat.turn_off()

    def test_union_changed_between_runs(self):
        # A member added to a union that is already a constraint acts from
        # the next run's first half kick (as with recalc_forces=True), not
        # only from its second; removing it likewise.
        states = []
        for recalc in (False, True):
            with self.cleared():
                union = shapes.Union()
                self.add(union)
                p = self.system.part.add(pos=[5, 5, 6.5], v=[0, 0, 0.1], type=0)
                self.system.integrator.run(3)  # empty union: no force
                np.testing.assert_allclose(p.v, [0, 0, 0.1], rtol=1e-15)
                wall = shapes.Wall(normal=[0, 0, 1], dist=5.0)
                union.add(wall)
                self.system.integrator.run(1, recalc_forces=recalc)
                v_wall = np.copy(p.v)
                union.remove(wall)
                self.system.integrator.run(1, recalc_forces=recalc)
                states.append(np.concatenate([v_wall, p.v, p.pos]))
        np.testing.assert_array_equal(states[0], states[1])
        # first step near the wall: v gets dt/2 (F(x0) + F(x1)), F ~ 2.1 at d = 1.5
        self.assertGreater(states[0][2] - 0.1, 0.009 * soft_sphere_force(1.6))
        # after removing it: no force at all in the second run
        np.testing.assert_array_equal(states[0][3:6], states[0][:3])

    def test_bad_constraint_arguments(self):
        wall = shapes.Wall(normal=[0, 0, 1], dist=1)
        C = lbmd.constraints.ShapeBasedConstraint
        with self.assertRaises(TypeError) as cm:
            C(shape="wall", particle_type=1)
        self.assertIn("shape", str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            C(shape=wall, particle_type=-1)
        self.assertIn("particle_type", str(cm.exception))
        with self.assertRaises(TypeError) as cm:
            C(shape=wall, particle_type=1, penetrable="no")
        self.assertIn("penetrable", str(cm.exception))
        with self.assertRaises(TypeError) as cm:
            C(shape=wall, particle_type=1, stiffness=3)
        self.assertIn("stiffness", str(cm.exception))


if __name__ == "__main__":
    unittest.main()
