"""hard_contact, the contact that cannot be crossed (doc/interactions.md):
F(h) = a ((cutoff / h)^n - 1) for the gap h = r - offset in (0, cutoff).
Two particles of different cells at several distances: the force against
the expression and against -dV/dr by finite differences, nothing within one
cell (same mol_id) or beyond the range; a squeeze of a particle onto another
(an external force, Langevin damping) settles at the gap where the contact
balances it (analytic); a squeeze stronger than the time step can follow
stops with SimulationInstability "contact_overrun" naming both particles,
for a pair and for a wall; the guard gap against its formula."""
import unittest

import numpy as np

import lbmd
from lbmd import shapes

A, N, CUTOFF, OFFSET = 0.01, 1.0, 0.5, 0.46


def force(h, a=A, n=N, cutoff=CUTOFF):
    return a * ((cutoff / h) ** n - 1.0) if 0 < h < cutoff else 0.0


class TestHardContact(unittest.TestCase):

    def scene(self, mol_b=1, n=N):
        s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        s.time_step = 0.01
        s.non_bonded_inter[0, 0].hard_contact.set_params(a=A, n=n, cutoff=CUTOFF, offset=OFFSET)
        a = s.part.add(pos=[4.0, 5.0, 6.0], type=0, mol_id=0)
        b = s.part.add(pos=[5.0, 5.0, 6.0], type=0, mol_id=mol_b)
        return s, a, b

    def test_force_and_energy(self):
        direction = np.array([2.0, -1.0, 2.0]) / 3.0
        for n in (1.0, 2.0):
            s, a, b = self.scene(n=n)

            def at(r):
                b.pos = a.pos + r * direction
                s.integrator.run(0, recalc_forces=True)
                return b.f, s.analysis.energy()["non_bonded"]
            for r in (0.5, 0.6, 0.8, 0.95, 0.97, 1.2):
                fb, _ = at(r)
                with self.subTest(n=n, r=r):
                    np.testing.assert_allclose(fb, force(r - OFFSET, n=n) * direction, rtol=1e-12, atol=1e-15)
            for r in (0.55, 0.7, 0.9):  # F = -dV/dr
                fb, _ = at(r)
                h = 1e-6
                finite = -(at(r + h)[1] - at(r - h)[1]) / (2 * h)
                with self.subTest(n=n, r=r):
                    self.assertAlmostEqual(np.dot(fb, direction), finite, delta=1e-6 * abs(finite))
            self.assertEqual(at(OFFSET + CUTOFF + 1e-9)[1], 0.0)  # V(cutoff) = 0 with its force

    def test_same_cell_is_silent(self):
        s, a, b = self.scene(mol_b=0)
        b.pos = a.pos + [0.6, 0.0, 0.0]
        s.integrator.run(0, recalc_forces=True)
        self.assertEqual(np.abs(b.f).max(), 0.0)

    def test_squeeze_settles_at_the_balancing_gap(self):
        # b pushed onto a (fixed) with 0.1 nN: a (c / h - 1) = 0.1 gives h = c / 11
        s, a, b = self.scene()
        a.fix = [True, True, True]
        b.pos = a.pos + [OFFSET + 0.4, 0.0, 0.0]
        b.ext_force = [-0.1, 0.0, 0.0]
        s.thermostat.set_langevin(kT=0.0, gamma=20.0, seed=1)
        s.integrator.run(20000)
        gap = b.pos[0] - a.pos[0] - OFFSET
        self.assertAlmostEqual(gap, CUTOFF / 11.0, delta=1e-6)
        self.assertGreater(s.non_bonded_inter[0, 0].hard_contact.get_params()["guard_gap"], 0.0)

    def test_overrun_is_named(self):
        s, a, b = self.scene()
        s.time_step = 0.1
        a.fix = [True, True, True]
        b.pos = a.pos + [OFFSET + 0.3, 0.0, 0.0]
        # balanced only at h = c / 201, below the guard gap at this time step
        b.ext_force = [-2.0, 0.0, 0.0]
        s.thermostat.set_langevin(kT=0.0, gamma=5.0, seed=1)
        with self.assertRaises(lbmd.SimulationInstability) as cm:
            s.integrator.run(2000)
        err = cm.exception
        self.assertEqual(err.cause, "contact_overrun")
        self.assertIn("packing_clearance", str(err))  # the way out for a scene packed too close
        self.assertIn("particle 1", str(err))
        self.assertIn("particle 0", str(err))
        self.assertLess(err.value, s.non_bonded_inter[0, 0].hard_contact.get_params()["guard_gap"] + 1e-15)
        self.assertGreater(b.pos[0] - a.pos[0], 0.0)  # never through
        # the guard: k(h) dt^2 / m = 1 with k = a n c^n / h^(n + 1), m = 1
        guard = (A * N * CUTOFF ** N * 0.1 ** 2 / 1.0) ** (1.0 / (N + 1.0))
        self.assertAlmostEqual(s.non_bonded_inter[0, 0].hard_contact.get_params()["guard_gap"], guard, places=14)

    def test_packing_clearance_leaves_twice_the_guard_gap(self):
        """oif.contacts.guard_gap is the engine's guard gap of the advised
        contact (set_contacts at a scale), and packing_clearance leaves
        twice it beyond the offset where that exceeds PACKING_MARGIN (the
        flagship's 27x contacts and light nodes)."""
        import oif
        s = lbmd.System(box_l=[20.0, 20.0, 20.0])
        s.time_step = 0.1
        ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.91,) * 3, kv=0.9)
        oif.set_contacts(s, ct, particle_types=0, scale=27.0)
        oif.OifCell(cell_type=ct, particle_type=0, origin=[10.0, 10.0, 10.0], particle_mass=0.05)
        s.integrator.run(1)  # the guards are computed at a run's start
        engine = s.non_bonded_inter[0, 0].hard_contact.get_params()["guard_gap"]
        self.assertAlmostEqual(oif.contacts.guard_gap(oif.contacts.CONTACT_A * 27.0, 0.1, 0.05), engine, places=12)
        offset = oif.contacts.contact_offset(ct)
        stiff = oif.contacts.packing_clearance(ct, scale=27.0, time_step=0.1, node_mass=0.05)
        self.assertGreater(2.0 * engine, oif.contacts.PACKING_MARGIN)
        self.assertAlmostEqual(stiff - offset, 2.0 * engine, places=12)
        self.assertAlmostEqual(oif.contacts.packing_clearance(ct, time_step=0.1, node_mass=1.0) - offset,
                               oif.contacts.PACKING_MARGIN, places=12)

    def test_wall_overrun_is_named(self):
        s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        s.time_step = 0.1
        wall = shapes.Wall(normal=[0, 0, 1], dist=1.0)
        s.constraints.add(shape=wall, particle_type=10)
        s.non_bonded_inter[0, 10].hard_contact.set_params(a=A, n=N, cutoff=CUTOFF, offset=0.0)
        p = s.part.add(pos=[5.0, 5.0, 1.3], type=0, mol_id=3)
        p.ext_force = [0.0, 0.0, -0.05]
        s.thermostat.set_langevin(kT=0.0, gamma=5.0, seed=1)
        s.integrator.run(3000)  # settles: a (c / h - 1) = 0.05
        self.assertAlmostEqual(p.pos[2] - 1.0, CUTOFF / 6.0, delta=1e-6)
        p.ext_force = [0.0, 0.0, -1.0]  # balanced only at h = c / 101, below the guard gap
        s.thermostat.set_langevin(kT=0.0, gamma=5.0, seed=1)
        with self.assertRaises(lbmd.SimulationInstability) as cm:
            s.integrator.run(2000)
        self.assertEqual(cm.exception.cause, "contact_overrun")
        self.assertIn("Wall constraint", str(cm.exception))
        self.assertGreater(p.pos[2], 1.0)

    def test_parameters(self):
        s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        pair = s.non_bonded_inter[0, 1].hard_contact
        self.assertFalse(pair.is_active())
        pair.set_params(a=0.01, cutoff=0.5)
        self.assertEqual(pair.get_params()["n"], 2.0)
        self.assertTrue(pair.is_active())
        for bad, name in ((dict(a=0.0, cutoff=0.5), "a"), (dict(a=0.01, cutoff=-1.0), "cutoff"),
                          (dict(a=0.01, cutoff=0.5, offset=-0.1), "offset"),
                          (dict(a=0.01, cutoff=0.5, n=0.0), "n")):
            with self.subTest(bad=bad), self.assertRaisesRegex(ValueError, f"'{name}'"):
                pair.set_params(**bad)
        pair.deactivate()
        self.assertFalse(pair.is_active())


if __name__ == "__main__":
    unittest.main()
