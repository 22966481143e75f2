"""System-level API: construction, parameters read back as set, ESPResSo
porting helpers, and every documented bad input raising a clear exception."""
import unittest

import numpy as np

import lbmd


class SystemApi(unittest.TestCase):
    def test_submodules_available_after_import(self):
        for name in ("lb", "shapes", "constraints", "interactions", "lbboundaries"):
            self.assertTrue(hasattr(lbmd, name), name)

    def test_parameters_read_back(self):
        s = lbmd.System(box_l=[4, 5, 6], periodicity=[True, False, True])
        s.time_step = 0.025
        s.cell_system.skin = 0.3
        np.testing.assert_array_equal(s.box_l, [4, 5, 6])
        self.assertEqual(s.periodicity, [True, False, True])
        self.assertEqual(s.time_step, 0.025)
        self.assertEqual(s.cell_system.skin, 0.3)
        s.non_bonded_inter[0, 1].soft_sphere.set_params(a=2.0, n=3.0, cutoff=1.5, offset=0.1)
        self.assertEqual(s.non_bonded_inter[1, 0].soft_sphere.get_params(),
                         {"a": 2.0, "n": 3.0, "cutoff": 1.5, "offset": 0.1})
        s.non_bonded_inter[0, 1].soft_sphere.deactivate()
        self.assertFalse(s.non_bonded_inter[0, 1].soft_sphere.is_active())

    def test_two_systems_are_independent(self):
        a = lbmd.System(box_l=[10, 10, 10])
        b = lbmd.System(box_l=[5, 5, 5])
        a.time_step = b.time_step = 0.01
        a.part.add(pos=[1, 1, 1], v=[1, 0, 0])
        b.part.add(pos=[[1, 1, 1], [2, 2, 2]])
        a.integrator.run(10)
        self.assertEqual(len(a.part), 1)
        self.assertEqual(len(b.part), 2)
        np.testing.assert_allclose(a.part.by_id(0).pos, [1.1, 1, 1])
        np.testing.assert_array_equal(b.part.by_id(0).pos, [1, 1, 1])

    def test_ctrl_c_ends_a_run_between_steps(self):
        """SIGINT (sent by another process, as Ctrl-C is) ends a long run
        within 16 steps, the system as after a run of that many steps: going
        on gives bit for bit the uninterrupted trajectory, also with a
        coupled fluid (tau = 4 time steps). Before, the signal waited for the
        run's end. A Python handler runs between steps only; one that
        returns lets the run go on to its end."""
        import faulthandler
        import os
        import signal
        import subprocess
        import time

        def make():
            s = lbmd.System(box_l=[8, 8, 8])
            s.time_step = 0.01
            s.part.add(pos=[[1, 1, 1], [1.9, 1.2, 1]], v=[[0.3, 0.1, 0], [-0.2, 0, 0.1]])
            s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=1.5)
            lbf = s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.04))
            s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
            return s

        def send_sigint_soon():
            return subprocess.Popen(["sh", "-c", f"sleep 0.5; kill -INT {os.getpid()}"])

        s = make()
        killer = send_sigint_soon()
        # should the interrupt be lost, the process ends a minute later with
        # the tracebacks (faulthandler's thread, which also ends a process
        # stuck in C++), instead of running into CTest's timeout
        faulthandler.dump_traceback_later(60, exit=True)
        try:
            with self.assertRaises(KeyboardInterrupt):
                s.integrator.run(2**31 - 1)  # days at this speed
        finally:
            faulthandler.cancel_dump_traceback_later()
        killer.wait()
        steps = round(s.time / s.time_step)
        self.assertGreater(steps, 0)
        self.assertEqual(steps % 16, 0)
        s.integrator.run(48)  # and it goes on
        ref = make()
        ref.integrator.run(steps + 48)
        np.testing.assert_array_equal(s.part.all().pos, ref.part.all().pos)
        np.testing.assert_array_equal(s.part.all().v, ref.part.all().v)

        # runs shorter than 16 steps (no interruption point in them): the
        # signal is handled when one ends (it was lost)
        # (a fluid large enough that the signal lands in a run, not in the
        # Python code between runs, where Python handles it anyway)
        s = lbmd.System(box_l=[24, 24, 24])
        s.time_step = 0.01
        s.actors.add(lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.01))
        killer = send_sigint_soon()
        deadline = time.monotonic() + 60.0
        with self.assertRaises(KeyboardInterrupt):
            while time.monotonic() < deadline:
                s.integrator.run(15)
        killer.wait()
        self.assertEqual(round(s.time / s.time_step) % 15, 0)

        # a handler that returns: the run is not cut short
        calls = []
        old = signal.signal(signal.SIGINT, lambda signum, frame: calls.append(len(s.part)))
        try:
            s = make()
            killer = send_sigint_soon()
            n = 0
            # runs of a few ms until the signal came (a minute at most: a
            # count of runs was too few on a busy machine, where the sending
            # process may take seconds to start)
            deadline = time.monotonic() + 60.0
            while not calls and time.monotonic() < deadline:
                s.integrator.run(1000)
                n += 1
            killer.wait()
        finally:
            signal.signal(signal.SIGINT, old)
        self.assertEqual(calls, [2])
        self.assertEqual(round(s.time / s.time_step), 1000 * n)

    def test_parameter_objects_refuse_changes_they_would_ignore(self):
        """sphere.radius = 5 changed the Python object only (before)."""
        sphere = lbmd.shapes.Sphere(center=[1, 1, 1], radius=1.0)
        with self.assertRaisesRegex(AttributeError, "create a new Sphere"):
            sphere.radius = 5.0
        self.assertEqual(sphere.get_params()["radius"], 1.0)
        bond = lbmd.interactions.HarmonicBond(k=1.0, r_0=1.0)
        with self.assertRaisesRegex(AttributeError, "'k' cannot be changed"):
            bond.k = 100.0
        with self.assertRaisesRegex(TypeError, "keywords"):
            lbmd.interactions.HarmonicBond(1.0, 1.0)
        s = lbmd.System(box_l=[4, 4, 4])
        with self.assertRaisesRegex(TypeError, "keywords"):
            s.non_bonded_inter[0, 0].soft_sphere.set_params(1.0, 2.0, 1.0)
        with self.assertRaisesRegex(TypeError, "box_l"):
            lbmd.System(box_l=["8", "8", "8"])
        with self.assertRaisesRegex(TypeError, "min_global_cut"):
            s.min_global_cut = "abc"
        s.time_step = np.array(0.01)  # a 0-d array is a number
        self.assertEqual(s.time_step, 0.01)

    def test_constraint_added_twice_and_empty_type(self):
        s = lbmd.System(box_l=[4, 4, 4])
        c = s.constraints.add(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=0.0), particle_type=1)
        with self.assertRaisesRegex(ValueError, "already added"):
            s.constraints.add(c)
        with self.assertRaisesRegex(ValueError, "no particle of type 3"):
            s.analysis.center_of_mass(p_type=3)

    def test_non_bonded_types_bounded(self):
        """Type pairs are a dense table: a type of 9000 asked for 7 GB, even
        to read (before)."""
        s = lbmd.System(box_l=[4, 4, 4])
        with self.assertRaisesRegex(ValueError, "0..1023"):
            s.non_bonded_inter[9000, 0].soft_sphere.is_active()
        self.assertFalse(s.non_bonded_inter[1023, 1023].soft_sphere.is_active())
        with self.assertRaisesRegex(ValueError, "0..1023"):
            s._core.get_soft_sphere(0, 5000)  # the engine checks too

    def test_time_advances(self):
        s = lbmd.System(box_l=[10, 10, 10])
        s.time_step = 0.5
        s.integrator.run(4)
        self.assertAlmostEqual(s.time, 2.0)

    def test_run_after_setting_a_position_starts_from_new_forces(self):
        # a bond stretched between two runs: the next run's first half kick
        # must use the stretched bond's force, as a system built stretched
        def system_with_bond(x1):
            s = lbmd.System(box_l=[10.0, 10.0, 10.0])
            s.time_step = 0.01
            bond = lbmd.interactions.HarmonicBond(k=10.0, r_0=1.0)
            s.bonded_inter.add(bond)
            a = s.part.add(pos=[2.0, 5.0, 5.0])
            b = s.part.add(pos=[x1, 5.0, 5.0])
            a.add_bond((bond, b))
            return s, b
        moved, b = system_with_bond(3.0)
        moved.integrator.run(1)
        b.pos = [4.5, 5.0, 5.0]
        b.v = [0.0, 0.0, 0.0]
        moved.part.by_id(0).pos = [2.0, 5.0, 5.0]
        moved.part.by_id(0).v = [0.0, 0.0, 0.0]
        moved.integrator.run(1)
        fresh, b_fresh = system_with_bond(4.5)
        fresh.integrator.run(1)
        np.testing.assert_allclose(b.pos, b_fresh.pos, rtol=0, atol=1e-14)
        np.testing.assert_allclose(b.v, b_fresh.v, rtol=0, atol=1e-14)

    def test_run_after_switching_a_thermostat_starts_from_new_forces(self):
        # Langevin friction (kT 0) switched on between two runs: the second
        # run's first half kick already feels -gamma v (velocity Verlet with
        # the force recomputed at its start)
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s.time_step = dt = 0.01
        p = s.part.add(pos=[5.0, 5.0, 5.0], v=[1.0, 0.0, 0.0], mass=2.0)
        s.integrator.run(1)
        gamma, m, v1 = 3.0, 2.0, 1.0
        s.thermostat.set_langevin(kT=0.0, gamma=gamma)
        s.integrator.run(1)
        v_half = v1 + 0.5 * dt * (-gamma * v1) / m
        v2 = v_half + 0.5 * dt * (-gamma * v_half) / m
        self.assertAlmostEqual(p.v[0], v2, delta=1e-14)

    def test_run_timings_add_up(self):
        # every phase of a step is exercised (bond, pair contact, wall, fluid
        # coupling, lattice update): each is timed, they and 'other' sum to
        # the total, and only runs count
        s = lbmd.System(box_l=[8.0, 8.0, 8.0])
        s.time_step = 0.05
        s.cell_system.skin = 0.2
        h = lbmd.interactions.HarmonicBond(k=1.0, r_0=1.0)
        s.bonded_inter.add(h)
        s.part.add(pos=[[3.0, 4.0, 4.0], [4.2, 4.0, 4.0]], type=[0, 0])
        s.part.by_id(0).add_bond((h, 1))
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.01, n=1.0, cutoff=1.5, offset=0.0)
        s.constraints.add(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0), particle_type=1)
        s.non_bonded_inter[0, 1].soft_sphere.set_params(a=0.01, n=1.0, cutoff=4.0, offset=0.0)
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.05)
        s.actors.add(lbf)
        s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
        phases = ("bonded", "non_bonded", "constraints", "coupling", "lb_fluid")
        # the force computation a run starts with (stale forces) is not a step's
        s.integrator.run(0, recalc_forces=True)
        t = s.integrator.timings()
        self.assertEqual(t["steps"], 0)
        for key in phases + ("membrane",):  # (no cells here: the membrane phase does nothing)
            self.assertEqual(t[key], 0.0, key)
        s.integrator.run(30)
        t = s.integrator.timings()
        self.assertEqual(t["steps"], 30)
        for key in phases + ("other",):  # 'other': the Verlet passes at least
            self.assertGreater(t[key], 0.0, key)
        self.assertGreater(t["total"], sum(t[k] for k in phases))
        # force computations outside runs are not counted
        s.analysis.energy()
        s.cell_system.get_pairs(1.0)
        s.integrator.run(0, recalc_forces=True)
        for key in ("steps",) + phases:
            self.assertEqual(s.integrator.timings()[key], t[key], key)
        self.assertIn("total (30 steps)", s.integrator.timing_report())
        s.integrator.run(10)
        self.assertEqual(s.integrator.timings()["steps"], 40)
        self.assertGreater(s.integrator.timings()["total"], t["total"])
        s.integrator.reset_timings()
        self.assertEqual(s.integrator.timings(),
                         dict.fromkeys(("steps", "total", "other", "membrane", "communication") + phases, 0))
        # one rank: no exchanges with other ranks (the periodic halo copies
        # within the rank are not communication)
        s.integrator.run(5)
        self.assertEqual(s.integrator.timings()["communication"], 0.0)

    def test_features(self):
        lbmd.assert_features(["MASS", "EXTERNAL_FORCES", "SOFT_SPHERE"])
        self.assertTrue(lbmd.has_features("LB_BOUNDARIES"))
        self.assertFalse(lbmd.has_features("ELECTROSTATICS"))
        with self.assertRaises(lbmd.FeaturesError) as cm:
            lbmd.assert_features(["MASS", "ELECTROSTATICS", "DIPOLES"])
        self.assertIn("ELECTROSTATICS, DIPOLES", str(cm.exception))

    def test_energy_dict(self):
        s = lbmd.System(box_l=[10, 10, 10])
        s.part.add(pos=[[1, 1, 1], [2, 1, 1]], v=[[1, 0, 0], [0, 2, 0]], mass=[1.0, 0.5])
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=2.0)
        e = s.analysis.energy()
        self.assertAlmostEqual(e["kinetic"], 0.5 + 1.0)
        self.assertAlmostEqual(e["non_bonded"], 1.0)
        self.assertAlmostEqual(e["total"], 2.5)
        self.assertEqual(e["bonded"], 0.0)

    def test_langevin_equipartition(self):
        """kT from the mean kinetic energy of free particles, within 3 %
        (5000 particles x 20 decorrelated samples: statistical error ~0.3 %)."""
        s = lbmd.System(box_l=[20, 20, 20])
        s.time_step = 0.01
        s.part.add(pos=np.random.default_rng(0).random((5000, 3)) * 20, mass=2.0)
        s.thermostat.set_langevin(kT=1.5, gamma=2.0, seed=42)
        s.integrator.run(500)
        samples = []
        for _ in range(20):
            s.integrator.run(50)
            samples.append(np.mean(2.0 * np.sum(s.part.all().v ** 2, axis=1)) / 3)
        self.assertAlmostEqual(np.mean(samples) / 1.5, 1.0, delta=0.03)

    def test_langevin_damping_rate(self):
        """kT = 0: velocity decays as exp(-gamma t / m) (relaxation runs)."""
        s = lbmd.System(box_l=[10, 10, 10])
        s.time_step = 0.001
        p = s.part.add(pos=[5, 5, 5], v=[1, 0, 0], mass=2.0)
        s.thermostat.set_langevin(kT=0.0, gamma=1.0)
        s.integrator.run(1000)
        self.assertAlmostEqual(p.v[0], np.exp(-0.5), delta=1e-3)


class SystemBadInput(unittest.TestCase):
    def raises(self, exc, word, fn, *args, **kwargs):
        with self.assertRaises(exc) as cm:
            fn(*args, **kwargs)
        self.assertIn(word, str(cm.exception), msg=str(cm.exception))

    def test_construction(self):
        self.raises(TypeError, "box_l", lbmd.System)
        self.raises(ValueError, "box_l", lbmd.System, box_l=[1, 2])
        self.raises(ValueError, "box_l", lbmd.System, box_l=[1, -2, 3])
        self.raises(ValueError, "box_l", lbmd.System, box_l=[1, np.inf, 3])
        self.raises(TypeError, "'box_L'", lbmd.System, box_L=[1, 2, 3])
        self.raises(ValueError, "periodicity", lbmd.System, box_l=[1, 1, 1], periodicity=[1, 0])

    def test_attributes(self):
        s = lbmd.System(box_l=[10, 10, 10])
        self.raises(ValueError, "time_step", setattr, s, "time_step", 0.0)
        self.raises(ValueError, "time_step", setattr, s, "time_step", -0.1)
        self.raises(TypeError, "time_step", setattr, s, "time_step", "0.1")
        self.raises(AttributeError, "timestep", setattr, s, "timestep", 0.1)
        self.raises(ValueError, "skin", setattr, s.cell_system, "skin", -1.0)
        self.raises(RuntimeError, "time_step", s.integrator.run, 10)
        s.time_step = 0.1
        self.raises(ValueError, "steps", s.integrator.run, -1)
        self.raises(TypeError, "steps", s.integrator.run, 1.5)

    def test_interactions(self):
        s = lbmd.System(box_l=[10, 10, 10])
        ss = s.non_bonded_inter[0, 0].soft_sphere
        self.raises(TypeError, "'cutoff'", ss.set_params, a=1.0, n=2.0)
        self.raises(ValueError, "'a'", ss.set_params, a=-1.0, n=2.0, cutoff=1.0)
        self.raises(TypeError, "'cut'", ss.set_params, a=1.0, n=2.0, cutoff=1.0, cut=1.0)
        self.raises(ValueError, "types", s.non_bonded_inter.__getitem__, (-1, 0))
        self.raises(AttributeError, "lennard_jones", getattr, s.non_bonded_inter[0, 0], "lennard_jones")
        self.raises(TypeError, "set_langevin", s.thermostat.set_langevin, kT=1.0)
        self.raises(ValueError, "seed", s.thermostat.set_langevin, kT=1.0, gamma=1.0)
        self.raises(ValueError, "'gamma'", s.thermostat.set_langevin, kT=1.0, gamma=-1.0, seed=1)

    def test_range_larger_than_box(self):
        s = lbmd.System(box_l=[2, 10, 10])
        s.time_step = 0.01
        s.part.add(pos=[1, 1, 1])
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=3.0)
        self.raises(ValueError, "exceeds the box", s.integrator.run, 1)

    def test_explosion_reports_particle_and_time(self):
        s = lbmd.System(box_l=[10, 10, 10])
        s.time_step = 0.1
        s.part.add(pos=[[5, 5, 5], [5.01, 5, 5]])
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1e30, n=12.0, cutoff=1.0)
        with self.assertRaises(lbmd.SimulationInstability) as cm:
            s.integrator.run(100)
        self.assertIn("particle", str(cm.exception))
        self.assertIn("time", str(cm.exception))


if __name__ == "__main__":
    unittest.main()
