"""Particle API: single and vectorised add, properties, slices, bonds, removal,
periodic folding (ESPResSo 4.2 semantics)."""
import unittest

import numpy as np

import lbmd
from lbmd.interactions import HarmonicBond


class ParticleApi(unittest.TestCase):
    def setUp(self):
        self.system = lbmd.System(box_l=[10.0, 10.0, 10.0])
        self.system.time_step = 0.01

    def test_single_add_and_read_back(self):
        p = self.system.part.add(pos=[1, 2, 3], v=[0.1, 0.2, 0.3], mass=2.5, type=3, mol_id=7,
                                 ext_force=[0, 0, 1], fix=[True, False, False])
        self.assertEqual(p.id, 0)
        np.testing.assert_array_equal(p.pos, [1, 2, 3])
        np.testing.assert_array_equal(p.v, [0.1, 0.2, 0.3])
        self.assertEqual((p.mass, p.type, p.mol_id), (2.5, 3, 7))
        np.testing.assert_array_equal(p.ext_force, [0, 0, 1])
        np.testing.assert_array_equal(p.fix, [True, False, False])
        q = self.system.part.by_id(0)
        self.assertEqual(p, q)

    def test_vectorised_add_returns_slice(self):
        pos = np.random.default_rng(1).random((50, 3)) * 10
        sl = self.system.part.add(pos=pos, type=np.arange(50) % 2, mass=1.5)
        self.assertEqual(len(sl), 50)
        np.testing.assert_allclose(self.system.part.all().pos, pos, rtol=0, atol=0)
        np.testing.assert_array_equal(sl.type, np.arange(50) % 2)
        np.testing.assert_array_equal(sl.mass, np.full(50, 1.5))
        sl.v = np.ones((50, 3))
        np.testing.assert_array_equal(self.system.part.by_ids([3, 4]).v, np.ones((2, 3)))
        self.assertEqual(len(self.system.part.select(type=1)), 25)
        self.assertEqual(self.system.part.highest_particle_id, 49)

    def test_explicit_ids_and_removal(self):
        self.system.part.add(id=[5, 9], pos=[[1, 1, 1], [2, 2, 2]])
        self.assertTrue(self.system.part.exists(9))
        self.assertFalse(self.system.part.exists(6))
        self.system.part.by_id(5).remove()
        self.assertEqual(len(self.system.part), 1)
        with self.assertRaises(IndexError):
            self.system.part.by_id(5)
        p = self.system.part.add(pos=[3, 3, 3])
        self.assertEqual(p.id, 10)

    def test_iteration_and_exclusions_do_not_outlive_particles(self):
        s = self.system
        s.part.add(pos=[[1, 1, 1], [1.5, 1, 1]])
        self.assertEqual([p.id for p in s.part], [0, 1])
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=1.0)
        s.part.by_id(0).add_exclusion(1)
        s.integrator.run(0, recalc_forces=True)
        np.testing.assert_array_equal(s.part.by_id(0).f, [0, 0, 0])
        s.part.clear()
        s.part.add(pos=[[1, 1, 1], [1.5, 1, 1]])  # same ids, no exclusion
        s.integrator.run(0, recalc_forces=True)
        self.assertAlmostEqual(s.part.by_id(0).f[0], -2.0 / 0.5**3)
        s.part.by_id(0).add_exclusion(1)
        s.part.by_id(1).remove()
        s.part.add(pos=[1.5, 1, 1], id=1)
        s.integrator.run(0, recalc_forces=True)
        self.assertAlmostEqual(s.part.by_id(0).f[0], -2.0 / 0.5**3)

    def test_unfolded_and_folded_positions(self):
        p = self.system.part.add(pos=[9.95, 5, 5], v=[1.0, 0, 0])
        self.system.integrator.run(10)  # moves 0.1: crosses x = 10
        np.testing.assert_allclose(p.pos, [10.05, 5, 5], atol=1e-12)
        np.testing.assert_allclose(p.pos_folded, [0.05, 5, 5], atol=1e-12)
        np.testing.assert_array_equal(p.image_box, [1, 0, 0])

    def test_ext_force_and_fixed_coordinates(self):
        p = self.system.part.add(pos=[5, 5, 5], ext_force=[1, 1, 0], fix=[False, True, False],
                                 mass=2.0)
        self.system.integrator.run(100)
        t = 100 * 0.01
        # x accelerates as F/m t^2 / 2 (exact for constant force in velocity Verlet)
        np.testing.assert_allclose(p.pos, [5 + 0.5 * 0.5 * t**2, 5, 5], atol=1e-12)
        np.testing.assert_allclose(p.v, [0.5 * t, 0, 0], atol=1e-12)

    def test_bonds_single_and_bulk(self):
        s = self.system
        s.part.add(pos=[[1, 1, 1], [2, 1, 1], [3, 1, 1], [4, 1, 1]])
        h = HarmonicBond(k=2.0, r_0=0.5)
        s.bonded_inter.add(h)
        s.part.by_id(0).add_bond((h, 1))
        s.part.by_id(1).add_bond((h, s.part.by_id(2)))
        s.part.add_bonds(h, [[2, 3]])
        self.assertEqual(s.part.by_id(1).bonds, ((h, 2),))
        s.integrator.run(0, recalc_forces=True)
        f = s.part.all().f
        # each bond stretched by 0.5: force 1.0; end particles pulled inward
        np.testing.assert_allclose(f[:, 0], [1.0, 0, 0, -1.0], atol=1e-14)
        e = s.analysis.energy()
        self.assertAlmostEqual(e["bonded"], 3 * 0.5 * 2.0 * 0.25, places=14)
        s.part.by_id(0).delete_bond((h, 1))
        self.assertEqual(s.part.by_id(0).bonds, ())

    def test_bond_across_periodic_boundary(self):
        s = self.system
        a = s.part.add(pos=[0.1, 5, 5])
        b = s.part.add(pos=[9.9, 5, 5])
        h = HarmonicBond(k=3.0, r_0=0.5)
        s.bonded_inter.add(h)
        a.add_bond((h, b))
        s.integrator.run(0, recalc_forces=True)
        # minimum-image distance 0.2 (not 9.8): compressed by 0.3
        self.assertAlmostEqual(a.f[0], 0.9, places=12)
        self.assertAlmostEqual(b.f[0], -0.9, places=12)

    def test_momentum_conserved_with_pairs_and_bonds(self):
        s = self.system
        rng = np.random.default_rng(3)
        g = np.mgrid[0:5, 0:5, 0:5].reshape(3, -1).T * 2.0 + 0.5
        s.part.add(pos=g + rng.uniform(-0.1, 0.1, g.shape), v=rng.normal(size=g.shape))
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=6, cutoff=2.5)
        h = HarmonicBond(k=5.0, r_0=2.0)
        s.bonded_inter.add(h)
        s.part.add_bonds(h, np.column_stack([np.arange(0, 124), np.arange(1, 125)]))
        p0 = s.analysis.linear_momentum()
        s.integrator.run(2000)
        # round-off: 125 particles of |p| ~ 1 over 2000 steps
        np.testing.assert_allclose(s.analysis.linear_momentum(), p0, atol=1e-11)


class ParticleBadInput(unittest.TestCase):
    def setUp(self):
        self.system = lbmd.System(box_l=[10.0, 10.0, 10.0])

    def assertRaisesNaming(self, exc, word, fn, *args, **kwargs):
        with self.assertRaises(exc) as cm:
            fn(*args, **kwargs)
        self.assertIn(word, str(cm.exception))

    def test_add(self):
        add = self.system.part.add
        self.assertRaisesNaming(TypeError, "pos", add, type=1)
        self.assertRaisesNaming(TypeError, "'colour'", add, pos=[1, 1, 1], colour=3)
        self.assertRaisesNaming(ValueError, "pos", add, pos=[1, 1])
        self.assertRaisesNaming(ValueError, "finite", add, pos=[1, np.nan, 1])
        self.assertRaisesNaming(ValueError, "mass", add, pos=[1, 1, 1], mass=-1)
        self.assertRaisesNaming(ValueError, "type", add, pos=[1, 1, 1], type=-2)
        self.assertRaisesNaming(TypeError, "type", add, pos=[1, 1, 1], type=1.5)
        self.assertRaisesNaming(ValueError, "v", add, pos=[[1, 1, 1], [2, 2, 2]], v=[[1, 1, 1]])
        add(pos=[1, 1, 1], id=4)
        self.assertRaisesNaming(ValueError, "already exists", add, pos=[1, 1, 1], id=4)
        self.assertRaisesNaming(ValueError, "id", add, pos=[1, 1, 1], id=-1)

    def test_properties(self):
        p = self.system.part.add(pos=[1, 1, 1])
        self.assertRaisesNaming(AttributeError, "velocity", setattr, p, "velocity", [1, 1, 1])
        self.assertRaisesNaming(ValueError, "v", setattr, p, "v", [1, 1])
        self.assertRaisesNaming(ValueError, "mass", setattr, p, "mass", 0.0)
        self.assertRaisesNaming(AttributeError, "read-only", setattr, p, "pos_folded", [1, 1, 1])
        with self.assertRaises(IndexError):
            self.system.part.by_id(17)

    def test_bonds(self):
        s = self.system
        s.part.add(pos=[[1, 1, 1], [2, 2, 2]])
        h = HarmonicBond(k=1.0, r_0=1.0)
        self.assertRaisesNaming(ValueError, "bonded_inter.add", s.part.by_id(0).add_bond, (h, 1))
        s.bonded_inter.add(h)
        self.assertRaisesNaming(ValueError, "does not exist", s.part.by_id(0).add_bond, (h, 5))
        self.assertRaisesNaming(ValueError, "twice", s.part.by_id(0).add_bond, (h, 0))
        self.assertRaisesNaming(ValueError, "2 particles", s.part.add_bonds, h, [[0, 1, 1]])
        self.assertRaisesNaming(TypeError, "tuple", s.part.by_id(0).add_bond, [h, 1])
        self.assertRaisesNaming(ValueError, "'k'", HarmonicBond, k=-1.0, r_0=1.0)
        self.assertRaisesNaming(TypeError, "'r_0'", HarmonicBond, k=1.0)
        self.assertRaisesNaming(TypeError, "'r0'", HarmonicBond, k=1.0, r_0=1.0, r0=2.0)

    def test_broken_bond_stops_the_run(self):
        s = self.system
        s.time_step = 0.01
        s.part.add(pos=[[1, 1, 1], [2, 1, 1]], v=[[-5, 0, 0], [5, 0, 0]])
        h = HarmonicBond(k=0.0, r_0=1.0, r_cut=1.5)
        s.bonded_inter.add(h)
        s.part.by_id(0).add_bond((h, 1))
        with self.assertRaises(lbmd.SimulationInstability) as cm:
            s.integrator.run(100)
        self.assertIn("broke", str(cm.exception))
        self.assertIn("0 1", str(cm.exception))

    def test_integers_out_of_range_are_refused_not_wrapped(self):
        """ids, types and mol_ids are C++ ints: 2**40 must not become 0 and
        1.7 must not become 1 (before: silently wrapped or truncated)."""
        s = self.system
        add = s.part.add
        self.assertRaisesNaming(ValueError, "'type'", add, pos=[1, 1, 1], type=2**40)
        self.assertRaisesNaming(ValueError, "'mol_id'", add, pos=[1, 1, 1], mol_id=2**33)
        self.assertRaisesNaming(ValueError, "'id'", add, pos=[1, 1, 1], id=2**31 - 1)
        self.assertEqual(len(s.part), 0)  # nothing half added
        p = add(pos=[1, 1, 1], type=2)
        self.assertRaisesNaming(TypeError, "'type'", setattr, p, "type", 1.7)
        self.assertRaisesNaming(TypeError, "'type'", setattr, p, "type", float("nan"))
        self.assertRaisesNaming(ValueError, "'type'", setattr, p, "type", 2**40)
        self.assertRaisesNaming(TypeError, "'mol_id'", setattr, p, "mol_id", 2.5)
        self.assertEqual((p.type, p.mol_id), (2, 0))
        p.mol_id = np.float64(3.0)  # a whole number stored as a float is fine
        self.assertEqual(p.mol_id, 3)
        # whole numbers of any numeric kind are ids (as int(pid) took them before)
        for pid in (np.int64(0), np.array(0), np.float64(0.0), 0.0):
            self.assertEqual(s.part.by_id(pid).id, 0)
            self.assertTrue(s.part.exists(pid))
        self.assertRaisesNaming(TypeError, "pid", s.part.by_id, 0.7)
        self.assertRaisesNaming(ValueError, "pid", s.part.by_id, 2**40)
        q = add(pos=[2, 2, 2])
        h = HarmonicBond(k=1.0, r_0=1.0)
        s.bonded_inter.add(h)
        self.assertRaisesNaming(ValueError, "partner", p.add_bond, (h, 2**32 + 1))
        self.assertRaisesNaming(TypeError, "partner", p.add_bond, (h, 0.9))
        self.assertEqual(p.bonds, ())
        # bulk bonds: 0.5 -> 0 and 2**32 + 1 -> 1 made wrong bonds (before)
        for ids, exc in (([[0.5, 1.7]], TypeError), ([[0, 2**32 + 1]], ValueError),
                         ([[True, False]], TypeError), ([["0", "1"]], TypeError), ([[0, -1]], ValueError)):
            self.assertRaisesNaming(exc, "'ids'", s.part.add_bonds, h, ids)
        self.assertEqual(len(s._core.get_bonds(s.bonded_inter._id_of(h))), 0)
        self.assertRaisesNaming(TypeError, "tuple", p.delete_bond, ())
        self.assertRaisesNaming(ValueError, "partner", p.delete_bond, (h, -3))
        self.assertRaisesNaming(TypeError, "pid", s.part.exists, "a")
        # a slice refused as a whole: no particle changed
        sl = s.part.by_ids([p.id, q.id])
        self.assertRaisesNaming(ValueError, "mass", setattr, sl, "mass", [2.0, -1.0])
        np.testing.assert_array_equal(sl.mass, [1.0, 1.0])

    def test_exclusion_partner_must_exist(self):
        """A negative or missing partner crashed the next run (before)."""
        s = self.system
        s.time_step = 0.01
        p = s.part.add(pos=[1, 1, 1])
        s.part.add(pos=[2, 1, 1])
        self.assertRaisesNaming(ValueError, "partner", p.add_exclusion, -1)
        self.assertRaisesNaming(ValueError, "does not exist", p.add_exclusion, 17)
        self.assertRaisesNaming(TypeError, "partner", p.add_exclusion, 1.7)
        self.assertRaisesNaming(ValueError, "itself", p.add_exclusion, p.id)
        with self.assertRaises(ValueError):  # the engine checks too
            s._core.add_exclusion(0, 2000000000)
        p.add_exclusion(1)
        s.integrator.run(5)

    def test_position_too_far_to_fold(self):
        """Beyond 1e9 box lengths the image counter would overflow: refused
        (before: read back as garbage after run(0))."""
        s = self.system
        self.assertRaisesNaming(ValueError, "1e9 box lengths", s.part.add, pos=[1e12, 1, 1])
        p = s.part.add(pos=[1, 1, 1])
        self.assertRaisesNaming(ValueError, "1e9 box lengths", setattr, p, "pos", [1, -1e11, 1])
        np.testing.assert_array_equal(p.pos, [1, 1, 1])
        # one row of many refused: none of them added (before: the rows before it stayed)
        self.assertRaisesNaming(ValueError, "1e9 box lengths", s.part.add, pos=[[2, 2, 2], [1e20, 0, 0]])
        self.assertEqual(len(s.part), 1)
        self.assertFalse(s.part.exists(-1))  # as in ESPResSo, not an error
        self.assertEqual(len(s.part.by_ids(np.array([p.id], dtype=object))), 1)

    def test_blow_up_stops_with_the_particle_named(self):
        """k dt^2 / m = 250: the bond makes the pair explode. Stopped when a
        particle moves half the box in one step (before: ran on to energies
        of 1e12 without a word)."""
        s = self.system
        s.time_step = 0.5
        s.part.add(pos=[[4, 5, 5], [6, 5, 5]])
        s.part.add(pos=[1, 1, 1], v=[1e6, 0, 0], fix=[True, False, False])  # fast, but fixed in x
        h = HarmonicBond(k=1000.0, r_0=1.0)
        s.bonded_inter.add(h)
        s.part.by_id(0).add_bond((h, 1))
        with self.assertRaises(lbmd.SimulationInstability) as cm:
            s.integrator.run(100)
        msg = str(cm.exception)
        self.assertIn("in one time step", msg)
        self.assertIn("particle 0", msg)
        self.assertTrue(np.all(np.isfinite(s.part.all().pos)))


if __name__ == "__main__":
    unittest.main()
