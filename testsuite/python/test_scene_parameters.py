"""oif.scene_parameters: the numbers of a scene from SI inputs. The PyOIF
paper's inputs give the samples' numbers; the rules (lattice spacing from
the cell and the channel, relaxation time, speed-up held by the membrane
limit and by the Reynolds number, friction, node mass) each hold; a scene
built from the plan passes system.check_settings() with no warning; the
accuracy wanted picks the mesh and the time step, a time budget the finest
accuracy that fits; SI mistakes are named."""
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

    def test_accuracy_picks_mesh_and_time_step(self):
        """The accuracy wanted picks the coarsest mesh whose measured shape
        error (check_settings' MESH_ERROR table) is within it, a lattice
        update whose time-step error is, and a speed-up one cell of the plan
        survives at the time step and 1.5x it (check_settings' trial)."""
        from oif.settings_check import MESH_ERROR, TRIAL_MARGIN, membrane_trial
        error = dict(MESH_ERROR)
        coarse = oif.scene_parameters(narrowest=10e-6, mean_speed=1.3e-3, accuracy=0.05)
        self.assertEqual(coarse.mesh, "rbc162")
        self.assertLessEqual(coarse.shape_error, 0.05)
        medium = oif.scene_parameters(narrowest=10e-6, mean_speed=1.3e-3, accuracy=0.02)
        self.assertEqual(medium.mesh, "rbc642")  # rbc374's 4.5 % is too much
        self.assertEqual(medium.shape_error, error[642])
        for plan in (coarse, medium):
            self.assertLessEqual(plan.time_error, plan.accuracy)
            self.assertEqual(plan.time_step, 0.1)
            s = lbmd.System(box_l=[40.0] * 3)
            cell_type = oif.OifCellType(*oif.mesh_files(plan.mesh), system=s, resize=plan.resize, normal=True,
                                        **plan.moduli)
            for dt in (plan.time_step, TRIAL_MARGIN * plan.time_step):
                self.assertEqual(membrane_trial(cell_type, dt, plan.node_mass, plan.gamma), "stable", plan)
        self.assertEqual(coarse.speedup, 27.0)
        self.assertLess(medium.speedup, 27.0)  # rbc642 at 27x fails the trial at 1.5x the time step
        self.assertIn("lowered until one cell passes", str(medium))
        # a finer time step: halved until its error (0.56 % at 0.1 us, as tau^1.4) is within
        fine = oif.scene_parameters(narrowest=10e-6, mean_speed=1.3e-3, accuracy=0.002, mesh="rbc374")
        self.assertEqual(fine.mesh, "rbc374")  # asked: kept
        self.assertAlmostEqual(fine.time_step, 0.025, delta=1e-12)  # 0.05 us gives 0.21 %
        self.assertAlmostEqual(fine.time_error, 0.0056 * 0.25 ** 1.4, delta=1e-12)
        self.assertAlmostEqual(fine.node_mass, fine.gamma * 0.025 / 0.3, delta=1e-12)
        self.assertFalse(fine.accuracy_met)  # rbc374's 4.5 % shape error: said, not hidden
        self.assertIn("NOT met", str(fine))
        self.assertTrue(medium.accuracy_met)
        # the time-step error at tau*'s floor: a large cell on a coarse lattice cannot reach 0.1 %
        coarse_lattice = oif.scene_parameters(narrowest=20e-6, mean_speed=1e-3, cell_radius=8e-6, accuracy=0.001,
                                              mesh="rbc2562")
        self.assertIn("time-step error", coarse_lattice.accuracy_shortfall)

    def test_run_time_and_budget(self):
        """The estimated run time is the measured costs times the work (lattice
        node updates and cell node steps), and a time budget picks the finest
        accuracy whose estimate fits, or says that none does."""
        from oif.scene_plan import RANK_EFFICIENCY, SECONDS_PER_CELL_NODE_STEP, SECONDS_PER_NODE_UPDATE
        work = dict(narrowest=10e-6, mean_speed=1.3e-3, duration=0.05, box=[100e-6, 40e-6, 16e-6], cells=20)
        plan = oif.scene_parameters(**work)
        self.assertEqual(plan.steps, round(0.05 / 27 / 1e-7))
        one_core = plan.steps * (100 * 40 * 16 * SECONDS_PER_NODE_UPDATE + 20 * 374 * SECONDS_PER_CELL_NODE_STEP)
        self.assertAlmostEqual(plan.estimated_seconds, one_core, delta=1e-9 * one_core)
        two = oif.scene_parameters(cores=2, **work)
        self.assertAlmostEqual(two.estimated_seconds, one_core / (1 + RANK_EFFICIENCY), delta=1e-9 * one_core)
        self.assertIn("estimated run time", str(plan))
        estimate = {a: oif.scene_parameters(accuracy=a, **work).estimated_seconds for a in (0.01, 0.02, 0.05)}
        self.assertGreater(estimate[0.01], estimate[0.02])
        self.assertGreater(estimate[0.02], estimate[0.05])
        budget = 0.5 * (estimate[0.02] + estimate[0.01])
        chosen = oif.scene_parameters(time_budget=budget, **work)
        self.assertEqual((chosen.accuracy, chosen.mesh), (0.02, "rbc642"))
        self.assertLessEqual(chosen.estimated_seconds, budget)
        self.assertIn("time budget", str(chosen))
        with self.assertRaisesRegex(ValueError, "time_budget.*coarser accuracy"):
            oif.scene_parameters(time_budget=0.5 * estimate[0.05], **work)
        with self.assertRaisesRegex(ValueError, "time_budget.*coarser accuracy"):  # accuracy asked: checked
            oif.scene_parameters(time_budget=budget, accuracy=0.01, **work)

    def test_mistakes_named(self):
        with self.assertRaisesRegex(ValueError, "narrowest.*metres"):
            oif.scene_parameters(narrowest=12, mean_speed=1e-3)
        with self.assertRaisesRegex(ValueError, "does not pass a channel"):
            oif.scene_parameters(narrowest=4e-6, mean_speed=1e-3)
        with self.assertRaisesRegex(ValueError, "speedup"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, speedup=0)
        with self.assertRaisesRegex(ValueError, "mean_speed"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=-1.0)
        with self.assertRaises(TypeError):
            oif.scene_parameters(narrowest="12 um", mean_speed=1e-3)
        with self.assertRaisesRegex(ValueError, "'accuracy' is the error wanted as a fraction"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, accuracy=2)
        with self.assertRaisesRegex(ValueError, r"'box\[0\]' is 100: SI, in metres"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, duration=0.01, box=[100, 40, 16])
        with self.assertRaisesRegex(ValueError, "'time_budget' needs the 'duration'"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, time_budget=3600)
        with self.assertRaisesRegex(ValueError, "'cells' must be a whole number"):
            oif.scene_parameters(narrowest=12e-6, mean_speed=1e-3, cells=2.5)

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
