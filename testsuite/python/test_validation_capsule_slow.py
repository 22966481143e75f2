"""Validation against theory: a spherical neo-Hookean capsule in simple
shear flow, Taylor deformation D against the small-deformation theory of
D. Barthes-Biesel & J. M. Rallison, J. Fluid Mech. 113, 251-267 (1981):
D = (5/4) (2 + nu_s)/(1 + nu_s) Ca = 25/12 Ca for a neo-Hookean membrane
(nu_s = 1/2, area dilation modulus K = 3 Gs), Ca = eta gamma_dot a / Gs.
(The "D = 25/4 Ca" of the literature is the same law with Ca based on the
neo-Hookean surface modulus Es = 3 Gs.)

The sample samples/validation/capsule_shear.py runs the capsule (sphere642,
radius 6 lattice nodes, channel height H = 10 a, Reynolds number
gamma_dot a^2 / nu = 0.19; doc/validation.md) at Ca 0.0125, 0.025 and 0.05,
each at three coupling frictions: 1, 4 and 8 times suggest_LBgamma. The
friction coupling lets the membrane slip against the fluid; the theory has
no slip, so the sample extrapolates 1/D linearly in 1/gamma to 1/gamma = 0
from the two largest frictions.

Tolerance: the no-slip limit of D within 10 % of the theory at every Ca
(the issue's criterion). Measured (26 Nov 2026): D/theory 1.051, 1.054,
1.046 at Ca 0.0125, 0.025, 0.05 (5 % above the theory: confinement a/H =
0.1 and the immersed boundary's thickness, doc/validation.md). Also
asserted: D linear in Ca (D/Ca equal within 3 % over the three Ca, at each
friction), D growing with the friction, the inclination angle near 45 deg
(small-deformation theory: pi/4 at Ca -> 0; within 5 deg), the volume held
within 1 %, and the documented bias of the default coupling
(suggest_LBgamma alone): D 0.60-0.80 of the theory (measured 0.69).
About 65 CPU s: hence _slow (ctest label slow)."""
import os
import sys
import tempfile
import unittest

from testsuite_data import BUILD, SOURCE, run_sample, read_csv

SAMPLE = "validation/capsule_shear.py"  # under samples/
TOLERANCE = 0.10  # relative, on the no-slip limit of D (the 10 %)
CAPILLARY_NUMBERS = (0.0125, 0.025, 0.05)



@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class CapsuleShear(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with tempfile.TemporaryDirectory() as tmp:
            stdout = run_sample(SAMPLE, "--output", tmp, "--ca", *map(str, CAPILLARY_NUMBERS), cwd=tmp,
                                timeout=900)
            cls.png_size = os.path.getsize(os.path.join(tmp, "capsule_shear.png"))
            cls.rows = read_csv(os.path.join(tmp, "capsule_shear.csv"))
        cls.stdout = stdout
        cls.runs = [r for r in cls.rows if r["kind"] == "run"]
        cls.limits = {float(r["Ca"]): r for r in cls.rows if r["kind"] == "no_slip_limit"}

    def test_outputs(self):
        self.assertGreater(self.png_size, 0)
        self.assertIn("no-slip limit, worst |D/theory - 1|", self.stdout)
        self.assertEqual(sorted(self.limits), sorted(CAPILLARY_NUMBERS))
        self.assertEqual(len(self.runs), 3 * len(CAPILLARY_NUMBERS))

    def test_theory_column(self):
        # the sample's theory is Barthes-Biesel & Rallison's 25/12 Ca, not made up
        for r in self.rows:
            self.assertAlmostEqual(float(r["D_theory"]), 25.0 / 12.0 * float(r["Ca"]), places=12)

    def test_no_slip_limit_against_theory(self):
        for ca, r in self.limits.items():
            with self.subTest(Ca=ca):
                d = float(r["D"])
                self.assertLess(abs(d / (25.0 / 12.0 * ca) - 1.0), TOLERANCE, f"Ca {ca}: D {d}")

    def test_linear_in_ca(self):
        for k in {r["coupling"] for r in self.runs}:
            slopes = [float(r["D"]) / float(r["Ca"]) for r in self.runs if r["coupling"] == k]
            with self.subTest(coupling=k):
                self.assertLess(max(slopes) / min(slopes) - 1.0, 0.03, slopes)

    def test_slip_lowers_the_deformation(self):
        for ca in CAPILLARY_NUMBERS:
            sel = sorted((r for r in self.runs if float(r["Ca"]) == ca), key=lambda r: float(r["gamma"]))
            d = [float(r["D"]) for r in sel]
            with self.subTest(Ca=ca):
                self.assertTrue(all(b > a for a, b in zip(d, d[1:])), d)
                self.assertGreater(float(self.limits[ca]["D"]), d[-1])

    def test_default_coupling_bias(self):
        # documented in doc/validation.md: suggest_LBgamma alone gives about 0.69 of the theory
        for r in self.runs:
            if float(r["coupling"]) == 1.0:
                with self.subTest(Ca=r["Ca"]):
                    self.assertGreater(float(r["ratio"]), 0.60)
                    self.assertLess(float(r["ratio"]), 0.80)

    def test_shape_and_volume(self):
        for r in self.runs:
            with self.subTest(Ca=r["Ca"], coupling=r["coupling"]):
                self.assertLess(abs(float(r["angle_deg"]) - 45.0), 5.0)
                self.assertLess(abs(float(r["volume_rel"]) - 1.0), 0.01)
                self.assertLess(abs(float(r["surface_rel"]) - 1.0), 0.01)
                # steady: D varies by less than 5 % over the last third of the run
                self.assertLess(float(r["D_spread"]), 0.05 * float(r["D"]))


class CapsuleShearUnits(unittest.TestCase):
    """The measurement itself, without a simulation: the equivalent
    ellipsoid of a triangulated ellipsoid returns its axes and tilt."""

    def test_taylor_deformation_of_an_ellipsoid(self):
        import math

        import numpy as np

        import oif
        sys.path.insert(0, os.path.join(SOURCE, "samples", "validation"))
        try:
            import capsule_shear
        finally:
            sys.path.pop(0)
        nodes_file, triangles_file = oif.mesh_files("sphere642")
        p = np.loadtxt(nodes_file)
        t = np.loadtxt(triangles_file, dtype=int)
        p = p / np.linalg.norm(p, axis=1)[:, None]
        tilt = math.radians(30.0)
        rot = np.array([[math.cos(tilt), 0, -math.sin(tilt)], [0, 1, 0], [math.sin(tilt), 0, math.cos(tilt)]])
        q = (p * [6.0, 5.0, 4.0]) @ rot.T + [10.0, 3.0, 7.0]
        d, angle = capsule_shear.taylor_deformation(q, t)
        # the polyhedron inscribed in the ellipsoid: its axes are short by
        # the same factor, so D is exact to the mesh's symmetry
        self.assertAlmostEqual(d, (6.0 - 4.0) / (6.0 + 4.0), delta=1e-3)
        self.assertAlmostEqual(angle, 30.0, delta=0.1)
        d, angle = capsule_shear.taylor_deformation(p * 5.0, t)
        self.assertLess(d, 1e-3)
        self.assertAlmostEqual(capsule_shear.theory_d(0.03), 25.0 / 12.0 * 0.03, places=12)


if __name__ == "__main__":
    unittest.main()
