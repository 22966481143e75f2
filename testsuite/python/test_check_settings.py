"""system.check_settings(): each choice against its measured limit
(doc/accuracy.md). Scenes past each limit get the warning, the same scene
within the limits does not; the first integrator.run warns once."""
import unittest
import warnings

import lbmd
import lbmd.lb
import oif
from lbmd.settings_check import SettingsWarning


def scene(visc=1.5, tau=0.1, dt=0.1, gamma=1.5, kb=0.02, contact=(0.1, 1.0), cells=2):
    s = lbmd.System(box_l=[40.0, 20.0, 20.0])
    s.time_step = dt
    lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=visc, tau=tau)
    s.actors.add(lbf)
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(4.0, 4.0, 4.0), normal=True,
                         ks=0.005, kb=kb, kal=0.007, kag=0.7, kv=0.9)
    # the script keeps its cells (check_settings sees the living OifCells)
    cell_list = [oif.OifCell(cell_type=ct, particle_type=0, origin=[10.0 + 15 * k, 10.0, 10.0])
                 for k in range(cells)]
    if contact:
        a, cutoff = contact
        s.non_bonded_inter[0, 0].membrane_collision.set_params(a=a, n=1.2, cutoff=cutoff)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
    return s, lbf, cell_list


def warned(report):
    return sorted(s.name.split(": ")[-1] for s in report.warnings())


class CheckSettings(unittest.TestCase):

    def test_within_limits_quiet(self):
        s, _, kept = scene()
        report = s.check_settings()
        self.assertEqual(report.warnings(), [], str(report))
        names = " ".join(x.name for x in report)
        for what in ("relaxation time", "Mach", "precision", "radius / agrid", "mean edge / agrid",
                     "mesh resolution", "time step against the membrane (kb, kal)",
                     "gamma * time_step / mass", "gamma N tau / (dens S agrid)",
                     "contact between cell types 0 and 0"):
            self.assertIn(what, names)
        self.assertIn("expect", str(report))

    def test_each_limit(self):
        # tau* = 3 visc tau / agrid^2 + 1/2 = 0.53 < 0.55
        s, _, kept = scene(visc=0.1, tau=0.1, dt=0.1)
        self.assertIn("relaxation time tau* = 3 visc tau / agrid^2 + 1/2", warned(s.check_settings()))
        # Mach 0.35 > 0.2
        s, lbf, kept = scene()
        c_s = 1.0 / 0.1 / 3 ** 0.5
        lbf[5, 5, 5].velocity = [0.35 * c_s, 0.0, 0.0]
        self.assertIn("Mach number (fastest node now)", warned(s.check_settings()))
        # kb 1000 times the paper's: measured stable only below dt 0.05 / 1000
        s, _, kept = scene(kb=20.0)
        self.assertIn("time step against the membrane (kb, kal)", warned(s.check_settings()))
        # the coupling: gamma N tau / (rho S agrid) = 10 * 374 * 0.1 / 134 = 2.8 > 1
        s, _, kept = scene(gamma=10.0)
        self.assertIn("coupling gamma N tau / (dens S agrid)", warned(s.check_settings()))
        # the paper's contact (a 1e-4, cutoff 0.5 < the longest edge 0.85): cells cross
        s, _, kept = scene(contact=(1e-4, 0.5))
        self.assertIn("contact between cell types 0 and 0", warned(s.check_settings()))
        # gamma dt / m = 1.5 * 1.0 = 1.5 > 1
        s, _, kept = scene(gamma=1.5, dt=1.0, tau=1.0, visc=0.15)
        self.assertIn("coupling gamma * time_step / mass", warned(s.check_settings()))
        # two cells, no contact between their type
        s, _, kept = scene(contact=None)
        self.assertIn("contact between cell types 0 and 0", warned(s.check_settings()))

    def test_membrane_limit_tells_the_truth(self):
        # the membrane check runs one cell alone at the scene's dt, mass and
        # friction: kb 1000 x the paper's at dt 0.1 is flagged, and the scene
        # itself does blow up
        s, _, kept = scene(kb=20.0, contact=None, cells=1)
        self.assertIn("time step against the membrane (kb, kal)", warned(s.check_settings()))
        with self.assertRaises(lbmd.SimulationInstability):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                s.integrator.run(400)
        # ESPResSo 4.2.2's oif_volume_conservation scene (sphere393 of radius
        # 12, kb = kal = 1, Langevin friction 0.7, dt 0.4, stretched 1.5 x):
        # it runs stably, and nothing is flagged
        import os
        data = os.path.join(os.environ.get("PYOIF_TEST_DATA", os.path.join(os.path.dirname(
            os.path.abspath(__file__)), "..", "data")), "meshes")
        s = lbmd.System(box_l=[50.0] * 3)
        s.time_step = 0.4
        s.cell_system.skin = 0.5
        ct = oif.OifCellType(os.path.join(data, "sphere393nodes.dat"), os.path.join(data, "sphere393triangles.dat"),
                             system=s, kslin=1.0, kb=1.0, kal=1.0, kag=0.1, kv=0.1, check_orientation=False,
                             resize=(3.0, 3.0, 3.0))
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[25.0] * 3)
        parts = s.part.all()
        parts.pos = (parts.pos - 25.0) * 1.5 * [0.96, 1.05, 1.02] + 25.0
        s.thermostat.set_langevin(kT=0, gamma=0.7, seed=42)
        self.assertEqual(s.check_settings().warnings(), [], str(s.check_settings()))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(450)
        self.assertEqual([str(w.message) for w in caught if issubclass(w.category, SettingsWarning)], [])
        self.assertAlmostEqual(cell.diameter(), 24.0, delta=0.1)

    def test_first_run_warns_once(self):
        s, _, kept = scene(contact=None)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(2)  # shorter than SETTINGS_CHECK_MIN_STEPS: not yet checked
            self.assertEqual([w for w in caught if issubclass(w.category, SettingsWarning)], [])
            s.integrator.run(10)
            s.integrator.run(10)
        mine = [w for w in caught if issubclass(w.category, SettingsWarning)]
        self.assertEqual(len(mine), 1, [str(w.message) for w in caught])
        self.assertIn("pass through each other", str(mine[0].message))


if __name__ == "__main__":
    unittest.main()
