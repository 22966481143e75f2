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


class SpeedWatch(unittest.TestCase):
    """The fluid's fastest node, looked for every speed_watch_every lattice
    updates during a run: its Mach number against plane Poiseuille flow, a
    warning that names it once per level passed, and none when off."""

    def channel(self, force, every=100):
        # walls halfway between the node planes y 0.5|1.5 and 8.5|9.5: h = 8
        s = lbmd.System(box_l=[8.0, 10.0, 4.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, ext_force_density=[force, 0, 0],
                              speed_watch_every=every)
        s.actors.add(lbf)
        for w in (lbmd.shapes.Wall(normal=[0, 1, 0], dist=1), lbmd.shapes.Wall(normal=[0, -1, 0], dist=-9)):
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=w))
        return s, lbf

    def test_poiseuille_mach(self):
        force = 0.101
        s, lbf = self.channel(force)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            for _ in range(30):  # 3000 updates: 4.7 diffusion times h^2 / nu
                s.integrator.run(100)
        # the fastest nodes are at y 4.5 and 5.5: u = f / (2 rho nu) (y - 1) (9 - y)
        c_s = 1.0 / 0.1 / 3 ** 0.5
        expected = force / 2.0 * 3.5 * 4.5 / c_s  # Mach 0.1378
        seen = [x for x in s.check_settings() if x.name.startswith("Mach number (fastest node seen")]
        self.assertEqual(len(seen), 1)
        self.assertAlmostEqual(float(seen[0].value), expected, delta=0.01 * expected)
        self.assertFalse(seen[0].ok)  # past the advice (0.1): never "ok"
        self.assertIn("WARN", seen[0].line())
        mine = [str(w.message) for w in caught if issubclass(w.category, SettingsWarning)]
        # once for passing the advice, though every run after that passed it too
        self.assertEqual(len([m for m in mine if "reached Mach" in m]), 1, mine)
        self.assertRegex(mine[-1], r"lattice node \(\d+, [45], \d+\)")

    def test_slow_flow_and_watch_off(self):
        s, lbf = self.channel(0.02)  # Mach 0.027: within the advice
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(1000)
        self.assertEqual([w for w in caught if issubclass(w.category, SettingsWarning)], [])
        self.assertLess(s.__dict__["_mach_highest"][0], 0.1)
        s, lbf = self.channel(0.5, every=0)  # Mach about 0.7, unseen with the watch off
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(200)
        self.assertEqual([w for w in caught if "reached Mach" in str(w.message)], [])
        self.assertIsNone(lbf._core.take_speed_watch())

    def test_past_advice_is_a_note_not_ok(self):
        # a cell of radius 3 lattice spacings: within the measured limit (2),
        # past the advice (4): printed "note", not "ok", and not a warning
        s2 = lbmd.System(box_l=[40.0, 20.0, 20.0])
        s2.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
        s2.actors.add(lbf)
        ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s2, resize=(3.0, 3.0, 3.0), normal=True,
                             ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0, 10.0, 10.0])
        s2.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
        report = s2.check_settings()
        radius = [x for x in report if x.name.endswith("radius / agrid")][0]
        self.assertTrue(radius.ok)
        self.assertFalse(radius.advised)
        self.assertTrue(radius.line().startswith("[note]"), radius.line())
        self.assertNotIn(radius, report.warnings())
        for line in str(report).splitlines():
            self.assertFalse(line.startswith("[ok") and "3 nodes" in line, line)
        del cell


class WallsAndCoupling(unittest.TestCase):
    """The wall and coupling lines: what a scene leaves out or mixes up is
    named; the complete scene passes."""

    def channel(self, constraints=True, boundaries=True, coupled=True, contact=True, wall_type=5, cell_type=0,
                wall_shapes=None):
        s = lbmd.System(box_l=[30.0, 20.0, 20.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
        s.actors.add(lbf)
        lo, hi = lbmd.shapes.Wall(normal=[0, 1, 0], dist=2), lbmd.shapes.Wall(normal=[0, -1, 0], dist=-18)
        for w in (lo, hi):
            if constraints:
                s.constraints.add(shape=w, particle_type=wall_type)
        if boundaries:
            # the same walls as one union and other objects: compared by the
            # nodes they cover, not by identity
            u = lbmd.shapes.Union()
            u.add(lbmd.shapes.Wall(normal=[0, 1, 0], dist=2))
            u.add(lbmd.shapes.Wall(normal=[0, -1, 0], dist=-18))
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=u))
        ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(4.0,) * 3, normal=True,
                             ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)
        cells = [oif.OifCell(cell_type=ct, particle_type=cell_type, origin=[15.0, 10.0, 10.0])]
        if contact and wall_type != cell_type:
            oif.set_contacts(s, ct, particle_types=cell_type, wall_types=[wall_type])
        if coupled:
            s.thermostat.set_lb(LB_fluid=lbf, gamma=1.5)
        return s, cells

    def test_complete_scene_passes(self):
        s, kept = self.channel()
        report = s.check_settings()
        self.assertEqual(report.warnings(), [], str(report))
        names = " ".join(x.name for x in report)
        for what in ("cells coupled to the fluid", "constraint 0 (Wall) against the lattice boundaries",
                     "cells of particle type 0 against constraint 1 (Wall, particle type 5)"):
            self.assertIn(what, names)

    def test_each_mistake_named(self):
        for kw, expected in ((dict(coupled=False), ["cells coupled to the fluid"]),
                             (dict(boundaries=False), ["constraint 0 (Wall) against the lattice boundaries",
                                                       "constraint 1 (Wall) against the lattice boundaries"]),
                             (dict(constraints=False), ["lattice boundary 0 (Union) against the constraints"]),
                             (dict(contact=False), [f"cells of particle type 0 against constraint {i} (Wall, "
                                                    f"particle type 5)" for i in (0, 1)]),
                             (dict(wall_type=0), [f"cells of particle type 0 against constraint {i} (Wall, "
                                                  f"particle type 0)" for i in (0, 1)])):
            with self.subTest(**kw):
                s, kept = self.channel(**kw)
                self.assertEqual(sorted(x.name for x in s.check_settings().warnings()), expected)

    def test_walls_without_particles(self):
        # a fluid between lattice walls with no particles is no mistake;
        # constraints without lattice walls are (the fluid passes them)
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s.time_step = 0.1
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
        s.actors.add(lbf)
        s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 1, 0], dist=2)))
        self.assertEqual(s.check_settings().warnings(), [])
        s.constraints.add(shape=lbmd.shapes.Sphere(center=[5, 6, 5], radius=2, direction=1), particle_type=3)
        self.assertEqual([x.name for x in s.check_settings().warnings()],
                         ["constraint 0 (Sphere) against the lattice boundaries"])


if __name__ == "__main__":
    unittest.main()
