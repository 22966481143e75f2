"""oif.scene_parameters: the numbers of a scene from SI inputs. The PyOIF
paper's inputs give the samples' numbers; the rules (lattice spacing from
the cell and the channel, relaxation time, speed-up held by the membrane
limit and by the Reynolds number, friction, node mass) each hold; a scene
built from the plan passes system.check_settings() with no warning; SI
mistakes are named."""
import math
import unittest

import numpy as np

import lbmd
import lbmd.lb
import oif
from lbmd.units import UnitSystem, oif_moduli_from_si
from oif.scene_plan import RBC_MEMBRANE


class SceneParameters(unittest.TestCase):
    def test_the_papers_scene(self):
        # the paper's channel (20 um high) at its mean speed, 1.3 mm/s on the centre line
        plan = oif.scene_parameters(narrowest=20e-6, mean_speed=1.3e-3 / 1.5)
        self.assertEqual((plan.agrid, plan.tau, plan.time_step, plan.visc, plan.dens), (1.0, 0.1, 0.1, 1.5, 1.0))
        self.assertEqual(plan.speedup, 27.0)  # the membrane limit, not the Reynolds number (0.5 / 0.0116)
        paper = oif_moduli_from_si(UnitSystem(), **RBC_MEMBRANE)
        for key in ("ks", "kb", "kal", "kag", "kv"):
            self.assertAlmostEqual(plan.moduli[key], 27.0 * paper[key], delta=1e-12 * plan.moduli[key])
        self.assertAlmostEqual(paper["ks"], 0.005, delta=1e-5)  # the paper's ks
        self.assertAlmostEqual(plan.moduli["kvisc"], 1.0, delta=1e-4)  # unscaled
        system = lbmd.System(box_l=[20.0] * 3)
        rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.91,) * 3, normal=True)
        self.assertEqual(plan.resize, (3.91, 3.91, 3.91))
        self.assertAlmostEqual(plan.gamma, rbc.suggest_LBgamma(visc=1.5, dens=1.0), delta=1e-12)
        self.assertAlmostEqual(plan.gamma * plan.time_step / plan.node_mass, 0.3, delta=1e-12)
        self.assertEqual(plan.contact_scale, 27.0)
        self.assertAlmostEqual(plan.speed, 27.0 * 1.3e-3 / 1.5, delta=1e-12)  # um/us = m/s
        text = str(plan)
        for name in ("lattice spacing", "lattice update", "speed-up", "membrane coefficients", "coupling gamma",
                     "node mass", "contacts", "Mach"):
            self.assertIn(name, text)
        self.assertEqual(plan.box([90e-6, 30.2e-6, 14e-6]), [90.0, 31.0, 14.0])

    def test_rules(self):
        # a fast real flow: the speed-up stops at Re 0.5
        fast = oif.scene_parameters(narrowest=12e-6, mean_speed=35e-3)
        self.assertAlmostEqual(fast.reynolds, 0.5, delta=1e-12)
        self.assertAlmostEqual(fast.speedup, 0.5 / (35e-3 * 12e-6 / 1.5e-6), delta=1e-12)
        # faster still: no speed-up at all
        self.assertEqual(oif.scene_parameters(narrowest=20e-6, mean_speed=0.1).speedup, 1.0)
        # asked for: real time, the paper's moduli
        real = oif.scene_parameters(narrowest=20e-6, mean_speed=1e-3, speedup=1)
        self.assertAlmostEqual(real.moduli["ks"], 0.005, delta=1e-5)
        # a small cell: 3.9 nodes on its radius need 0.25 um
        small = oif.scene_parameters(narrowest=10e-6, mean_speed=1e-3, cell_radius=1.5e-6, mesh="sphere162")
        self.assertEqual(small.agrid, 0.25)
        self.assertAlmostEqual(3 * small.visc * small.tau / small.agrid ** 2 + 0.5, 0.95, delta=1e-9)
        self.assertLess(small.mach, 0.1)

    def test_mistakes_named(self):
        with self.assertRaisesRegex(ValueError, "narrowest.*metres"):
            oif.scene_parameters(narrowest=12, mean_speed=1e-3)
        with self.assertRaisesRegex(ValueError, "does not pass a channel"):
            oif.scene_parameters(narrowest=4e-6, mean_speed=1e-3)
        with self.assertRaisesRegex(ValueError, "speedup"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, speedup=0.5)
        with self.assertRaisesRegex(ValueError, "mean_speed"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=-1.0)
        with self.assertRaises(TypeError):
            oif.scene_parameters(narrowest="12 um", mean_speed=1e-3)

    def test_scene_from_the_plan_passes_the_checks(self):
        """A channel between walls with two red cells, every number from the
        plan: system.check_settings() finds nothing past a measured limit."""
        plan = oif.scene_parameters(narrowest=14e-6, mean_speed=1e-3)
        s = lbmd.System(box_l=plan.box([40e-6, 20e-6, 16e-6]))
        s.time_step = plan.time_step
        s.cell_system.skin = 0.3
        lbf = lbmd.lb.LBFluid(**plan.fluid, ext_force_density=[1e-4, 0, 0])
        s.actors.add(lbf)
        walls = [lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0), lbmd.shapes.Wall(normal=[0, 0, -1], dist=-15.0)]
        for w in walls:
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=w))
            s.constraints.add(shape=w, particle_type=10)
        rbc = oif.OifCellType(*oif.mesh_files(plan.mesh), system=s, resize=plan.resize, normal=True, **plan.moduli)
        cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=[x, 10.0, 8.0], particle_mass=plan.node_mass)
                 for x in (10.0, 30.0)]
        s.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)
        oif.set_contacts(s, rbc, particle_types=0, wall_types=10, scale=plan.contact_scale)
        report = s.check_settings()
        self.assertEqual(report.warnings(), [], str(report))
        s.integrator.run(200)
        self.assertTrue(np.all(np.isfinite(s.part.all().pos)))
        for c in cells:
            self.assertAlmostEqual(c.volume() / rbc.volume0, 1.0, delta=0.01)
        self.assertTrue(math.isfinite(plan.capillary))


if __name__ == "__main__":
    unittest.main()
