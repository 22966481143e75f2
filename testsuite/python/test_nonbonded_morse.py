"""The Morse interaction, ESPResSo's semantics (ESPResSo 4.2 user guide,
"Morse interaction"): for r < cutoff
U(r) = eps (exp(-2 alpha (r - rmin)) - 2 exp(-alpha (r - rmin))) - U_0(cutoff),
zero beyond. Two particles at several distances: the force and the energy
against the expression, the force against -dU/dr by finite differences, the
parameter checks, and a checkpoint round trip."""
import os
import tempfile
import unittest

import numpy as np

import lbmd
from lbmd import checkpoint

EPS, ALPHA, RMIN, CUTOFF = 1.7, 2.3, 1.1, 2.5


def u_morse(r, eps=EPS, alpha=ALPHA, rmin=RMIN, cutoff=CUTOFF):
    def raw(x):
        return eps * (np.exp(-2 * alpha * (x - rmin)) - 2 * np.exp(-alpha * (x - rmin)))
    return raw(r) - raw(cutoff) if r < cutoff else 0.0


def minus_du_morse(r, eps=EPS, alpha=ALPHA, rmin=RMIN, cutoff=CUTOFF):
    if r >= cutoff:
        return 0.0
    e = np.exp(-alpha * (r - rmin))
    return 2 * eps * alpha * (e * e - e)


class TestMorse(unittest.TestCase):

    def setUp(self):
        self.s = lbmd.System(box_l=[12.0, 12.0, 12.0])
        self.s.time_step = 0.01
        self.s.non_bonded_inter[0, 1].morse.set_params(eps=EPS, alpha=ALPHA, rmin=RMIN, cutoff=CUTOFF)
        self.a = self.s.part.add(pos=[4.0, 5.0, 6.0], type=0)
        self.b = self.s.part.add(pos=[5.0, 5.0, 6.0], type=1)
        self.direction = np.array([2.0, -1.0, 2.0]) / 3.0

    def at(self, r):
        """Force on a, force on b and the energy with b at distance r from a."""
        self.b.pos = self.a.pos + r * self.direction
        self.s.integrator.run(0, recalc_forces=True)
        return self.a.f, self.b.f, self.s.analysis.energy()["non_bonded"]

    def test_force_and_energy(self):
        self.assertTrue(lbmd.has_features("MORSE"))
        self.assertEqual(self.s.non_bonded_inter[1, 0].morse.get_params(),
                         {"eps": EPS, "alpha": ALPHA, "rmin": RMIN, "cutoff": CUTOFF})
        # inside (repulsive below rmin, attractive above), at the minimum, beyond the cutoff
        for r in (0.6, 0.9, RMIN, 1.4, 2.0, 2.45, 2.55, 3.5):
            fa, fb, energy = self.at(r)
            with self.subTest(r=r):
                expected = minus_du_morse(r) * self.direction  # on b, along a -> b
                np.testing.assert_allclose(fb, expected, rtol=1e-12, atol=1e-14)
                np.testing.assert_allclose(fa, -expected, rtol=1e-12, atol=1e-14)
                self.assertAlmostEqual(energy, u_morse(r), delta=1e-12 * max(1.0, abs(u_morse(r))))
                if r >= CUTOFF:
                    self.assertEqual(energy, 0.0)
                    self.assertEqual(np.abs(fb).max(), 0.0)
        # repulsive below rmin (b pushed away from a), attractive above
        self.assertGreater(np.dot(self.at(0.9)[1], self.direction), 0.0)
        self.assertLess(np.dot(self.at(2.0)[1], self.direction), 0.0)
        # U(rmin) = -eps before the shift
        shift = EPS * (np.exp(-2 * ALPHA * (CUTOFF - RMIN)) - 2 * np.exp(-ALPHA * (CUTOFF - RMIN)))
        self.assertAlmostEqual(self.at(RMIN)[2], -EPS - shift, places=12)
        # U is continuous at the cutoff: just inside it is ~0
        self.assertAlmostEqual(self.at(CUTOFF - 1e-9)[2], 0.0, places=8)

    def test_force_is_minus_gradient(self):
        h = 1e-6
        for r in (0.7, 1.0, 1.3, 1.9, 2.4):
            _, fb, _ = self.at(r)
            finite = -(self.at(r + h)[2] - self.at(r - h)[2]) / (2 * h)
            with self.subTest(r=r):
                self.assertAlmostEqual(np.dot(fb, self.direction), finite, delta=1e-7 * max(1.0, abs(finite)))

    def test_parameters(self):
        pair = self.s.non_bonded_inter[2, 3].morse
        self.assertFalse(pair.is_active())
        pair.set_params(eps=1.0, alpha=1.0, rmin=1.0)  # cutoff defaults to 0, as in ESPResSo: no interaction
        self.assertFalse(pair.is_active())
        for bad, name in ((dict(eps=-1.0, alpha=1.0, rmin=1.0, cutoff=2.0), "eps"),
                          (dict(eps=1.0, alpha=0.0, rmin=1.0, cutoff=2.0), "alpha"),
                          (dict(eps=1.0, alpha=1.0, rmin=-1.0, cutoff=2.0), "rmin"),
                          (dict(eps=1.0, alpha=1.0, rmin=1.0, cutoff=-2.0), "cutoff"),
                          (dict(eps=float("nan"), alpha=1.0, rmin=1.0, cutoff=2.0), "eps")):
            with self.subTest(bad=bad), self.assertRaisesRegex(ValueError, f"'{name}'"):
                pair.set_params(**bad)
        with self.assertRaisesRegex(TypeError, "alpha"):
            pair.set_params(eps=1.0, rmin=1.0, cutoff=2.0)
        with self.assertRaises(TypeError):
            pair.set_params(eps=1.0, alpha=1.0, rmin=1.0, cutoff=2.0, sigma=1.0)
        self.s.non_bonded_inter[0, 1].morse.deactivate()
        self.assertEqual(self.at(1.0)[2], 0.0)

    def test_checkpoint(self):
        fa, fb, energy = self.at(1.5)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "morse.h5")
            checkpoint.save(path, self.s)
            ns = checkpoint.load(path).system
        self.assertEqual(ns.non_bonded_inter[0, 1].morse.get_params(),
                         {"eps": EPS, "alpha": ALPHA, "rmin": RMIN, "cutoff": CUTOFF})
        ns.integrator.run(0, recalc_forces=True)
        np.testing.assert_allclose(ns.part.by_id(1).f, fb, rtol=1e-14)
        self.assertEqual(ns.analysis.energy()["non_bonded"], energy)


if __name__ == "__main__":
    unittest.main()
