"""Checkpoints (lbmd.checkpoint) on one rank: a run continued from a
checkpoint is bit for bit the uninterrupted run (Langevin thermostat with
bonds, contacts, walls and fixed coordinates; a single-precision fluid with
two MD steps per lattice update, saved between a lattice update's
deposits); the named objects come back as one graph; damaged, foreign,
truncated and other-version files give a CheckpointError naming the file;
a failed save leaves the previous checkpoint as it was; a walltime signal
ends a run with a checkpoint and status 75, and the resumed run ends where
the uninterrupted one does. (At 2 ranks and across rank counts:
test_checkpoint_mpi.)"""
import os
import pickle
import subprocess
import tempfile
import textwrap
import unittest
from unittest import mock

import h5py
import numpy as np

import lbmd
import oif
from lbmd import checkpoint, lb, lbboundaries, shapes

BUILD = os.environ.get("PYOIF_BUILD_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "build"))


def langevin_scene():
    """Particles under a Langevin thermostat: harmonic bonds, soft-sphere
    pairs, walls (a Union) as constraints, an excluded pair, fixed
    coordinates and external forces."""
    s = lbmd.System(box_l=[10.0, 10.0, 10.0])
    s.time_step = 0.01
    s.cell_system.skin = 0.3
    rng = np.random.default_rng(5)
    pos = np.stack([rng.uniform(0, 10, 40), rng.uniform(0, 10, 40), rng.uniform(2, 8, 40)], axis=1)
    s.part.add(pos=pos, type=[0] * 20 + [1] * 20)
    s.part.by_id(3).fix = [True, False, False]
    s.part.by_id(4).ext_force = [0.1, 0.0, -0.2]
    s.part.by_id(5).add_exclusion(6)
    bond = lbmd.interactions.HarmonicBond(k=5.0, r_0=1.0)
    s.bonded_inter.add(bond)
    for i in range(0, 20, 2):
        s.part.by_id(i).add_bond((bond, i + 1))
    for t1, t2 in ((0, 0), (0, 1), (1, 1)):
        s.non_bonded_inter[t1, t2].soft_sphere.set_params(a=0.05, n=2.0, cutoff=1.2)
    s.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.1, n=1.5, cutoff=1.0)
    s.non_bonded_inter[1, 10].soft_sphere.set_params(a=0.1, n=1.5, cutoff=1.0)
    walls = shapes.Union(shapes=[shapes.Wall(normal=[0, 0, 1], dist=1.0),
                                 shapes.Wall(normal=[0, 0, -1], dist=-9.0)])
    s.constraints.add(shape=walls, particle_type=10, penetrable=False)
    s.thermostat.set_langevin(kT=1.0, gamma=1.0, seed=42)
    return s


def fluid_scene():
    """Single-precision fluid, tau = 2 time steps, particles coupled with
    noise (kT > 0), a sphere of fluid boundary."""
    s = lbmd.System(box_l=[12.0, 8.0, 8.0])
    s.time_step = 0.05
    s.cell_system.skin = 0.2
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, kT=1e-4, seed=7, single_precision=True,
                     ext_force_density=[2e-3, 0.0, 0.0])
    s.actors.add(lbf)
    s.lbboundaries.add(lbboundaries.LBBoundary(shape=shapes.Sphere(center=[6.0, 4.0, 4.0], radius=2.0)))
    rng = np.random.default_rng(3)
    s.part.add(pos=rng.uniform(0, 1, (30, 3)) * [12, 8, 8] * [1, 1, 0.25], type=[0] * 30)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=2.0, seed=11)
    return s, lbf


def file_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def particle_arrays(s):
    p = s.part.all()
    return {"pos": p.pos, "v": p.v, "f": p.f}


class BitExact(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix="test_checkpoint_")
        self.path = os.path.join(self.folder, "run.h5")

    def assert_equal_arrays(self, a, b):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)

    def test_langevin_particles(self):
        s = langevin_scene()
        s.integrator.run(123)
        checkpoint.save(self.path, s)
        s.integrator.run(200)
        reference = particle_arrays(s)
        ns = checkpoint.load(self.path)
        self.assertEqual(ns.system.step_count, 123)
        ns.system.integrator.run(200)
        self.assert_equal_arrays(reference, particle_arrays(ns.system))
        self.assertEqual(ns.system.time, s.time)
        self.assertEqual(ns.system.analysis.energy()["total"], s.analysis.energy()["total"])
        # not trivially equal: the particles moved
        self.assertGreater(np.abs(reference["pos"] - langevin_scene().part.all().pos).max(), 0.1)

    def test_saved_before_the_first_run(self):
        """A checkpoint written before any force calculation (a stop signal
        that arrives before the first step) holds no forces: the resumed run
        computes them as the uninterrupted one did. Before 29 Nov 2026 the
        load marked the stored zero forces valid, and the first half kick of
        the resumed run used them (test_checkpoint_mpi's signal test then
        failed whenever the signal came before the first step)."""
        s, lbf = fluid_scene()
        checkpoint.save(self.path, s, lbf=lbf)
        s.integrator.run(30)
        reference = particle_arrays(s)
        reference["population"] = lbf[:, :, :].population
        ns = checkpoint.load(self.path)
        ns.system.integrator.run(30)
        result = particle_arrays(ns.system)
        result["population"] = ns.lbf[:, :, :].population
        self.assert_equal_arrays(reference, result)

    def test_fluid_between_lattice_updates(self):
        s, lbf = fluid_scene()
        s.integrator.run(41)  # odd: between the two MD steps of a lattice update
        checkpoint.save(self.path, s, lbf=lbf)
        s.integrator.run(60)
        reference = particle_arrays(s)
        reference["population"] = lbf[:, :, :].population
        ns = checkpoint.load(self.path)
        self.assertIs(ns.lbf, ns.system.actors[0])
        self.assertTrue(ns.lbf.single_precision)
        ns.system.integrator.run(60)
        result = particle_arrays(ns.system)
        result["population"] = ns.lbf[:, :, :].population
        self.assert_equal_arrays(reference, result)
        # momentum bookkeeping (coupling ledger) came back too
        np.testing.assert_allclose(ns.system.analysis.linear_momentum(), s.analysis.linear_momentum(),
                                   rtol=0, atol=1e-12)

    def test_cells_and_named_objects(self):
        s = lbmd.System(box_l=[20.0, 12.0, 12.0])
        s.time_step = 0.1
        lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[1e-3, 0, 0])
        s.actors.add(lbf)
        rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(2.5, 2.5, 2.5), ks=0.02, kb=0.02,
                              kal=0.02, kag=0.7, kv=0.9, normal=True)
        cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=[6.0, 6.0, 6.0]),
                 oif.OifCell(cell_type=rbc, particle_type=0, origin=[14.0, 6.0, 6.0])]
        s.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=1.5, dens=1.0))
        s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.1, n=1.2, cutoff=1.0)
        s.integrator.run(50)
        checkpoint.save(self.path, s, cells=cells, rbc=rbc, note={"outputs": 3})
        s.integrator.run(50)
        volumes = [c.volume() for c in cells]
        ns = checkpoint.load(self.path)
        self.assertEqual(ns.note, {"outputs": 3})
        self.assertIs(ns.cells[0].cell_type, ns.rbc)
        self.assertIs(ns.cells[0].system, ns.system)
        self.assertEqual(len(ns.system.bonded_inter), len(s.bonded_inter))
        ns.system.integrator.run(50)
        self.assertEqual([c.volume() for c in ns.cells], volumes)
        # the loaded cells are live: seeding sees them, a new cell can be added
        self.assertEqual(len(oif.oif_classes.live_cells(ns.system)), 2)
        oif.OifCell(cell_type=ns.rbc, particle_type=0, origin=[10.0, 6.0, 2.9 + 0.0])
        ns.system.integrator.run(5)
        self.assertTrue(np.all(np.isfinite(ns.system.part.all().pos)))


class Errors(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix="test_checkpoint_errors_")
        self.path = os.path.join(self.folder, "good.h5")
        self.system = langevin_scene()
        self.system.integrator.run(10)
        checkpoint.save(self.path, self.system)

    def assert_refused(self, path, *words):
        with self.assertRaises(checkpoint.CheckpointError) as cm:
            checkpoint.load(path)
        message = str(cm.exception)
        self.assertIn(os.fspath(path), message)
        for w in words:
            self.assertIn(w, message)

    def test_missing(self):
        self.assert_refused(os.path.join(self.folder, "nothing.h5"), "no such file")

    def test_not_hdf5(self):
        text = os.path.join(self.folder, "notes.h5")
        with open(text, "w") as f:
            f.write("step 100\n")
        self.assert_refused(text, "not a readable HDF5 file")

    def test_truncated(self):
        cut = os.path.join(self.folder, "cut.h5")
        with open(self.path, "rb") as f:
            data = f.read()
        with open(cut, "wb") as f:
            f.write(data[:len(data) // 2])
        self.assert_refused(cut)

    def test_foreign_hdf5(self):
        foreign = os.path.join(self.folder, "foreign.h5")
        with h5py.File(foreign, "w") as f:
            f.create_dataset("particles/position", data=np.zeros((3, 3)))
        self.assert_refused(foreign, "not a PyOIF checkpoint")

    def test_other_version(self):
        with h5py.File(self.path, "r+") as f:
            f.attrs["version"] = checkpoint.FORMAT_VERSION + 1
        self.assert_refused(self.path, "checksum")  # edited: the checksum no longer matches
        checkpoint.seal(self.path)  # as another version would have written it
        self.assert_refused(self.path, "format version", str(checkpoint.FORMAT_VERSION + 1))

    def test_damaged_objects(self):
        with h5py.File(self.path, "r+") as f:
            del f["objects"]
            f.create_dataset("objects", data=np.frombuffer(b"\x80\x05garbage", dtype=np.uint8))
        checkpoint.seal(self.path)
        self.assert_refused(self.path, "cannot be read back")

    def test_one_byte_changed(self):
        data = bytearray(file_bytes(self.path))
        data[len(data) // 2] ^= 0x10
        damaged = os.path.join(self.folder, "flipped.h5")
        with open(damaged, "wb") as f:
            f.write(bytes(data))
        self.assert_refused(damaged, "checksum")

    def test_missing_dataset(self):
        with h5py.File(self.path, "r+") as f:
            del f["system0/particles/folded_pos"]
        checkpoint.seal(self.path)
        self.assert_refused(self.path, "system0/particles/folded_pos", "missing")

    def test_unpicklable_object_keeps_previous(self):
        before = file_bytes(self.path)
        with self.assertRaises(TypeError) as cm:
            checkpoint.save(self.path, self.system, callback=lambda: None)
        self.assertIn("picklable", str(cm.exception))
        self.assertEqual(file_bytes(self.path), before)

    def test_failed_write_keeps_previous(self):
        before = file_bytes(self.path)
        self.system.integrator.run(5)
        with mock.patch.object(h5py.File, "create_dataset", side_effect=OSError(28, "No space left on device")):
            with self.assertRaises(OSError) as cm:
                checkpoint.save(self.path, self.system)
        self.assertIn(self.path, str(cm.exception))
        self.assertEqual(file_bytes(self.path), before)
        self.assertEqual(sorted(os.listdir(self.folder)), ["good.h5"])  # no temporary file left
        self.assertEqual(checkpoint.load(self.path).system.step_count, 10)

    def test_bad_arguments(self):
        with self.assertRaises(TypeError):
            checkpoint.save(self.path, "system")
        with self.assertRaises(TypeError):
            checkpoint.save(42, self.system)
        with self.assertRaises(ValueError):
            checkpoint.save(self.folder, self.system)  # a folder, not a file name
        with self.assertRaises(TypeError):
            pickle.dumps(self.system)  # only through checkpoint.save


WALLTIME_SCRIPT = textwrap.dedent("""
    import signal, sys
    import numpy as np
    import lbmd
    sys.path.insert(0, {here!r})
    from test_checkpoint import langevin_scene
    path, mode, out = sys.argv[1], sys.argv[2], sys.argv[3]
    N = 100000
    if mode == "resume":
        s = lbmd.checkpoint.load(path).system
    else:
        s = langevin_scene()
    if mode == "signal":
        lbmd.checkpoint.stop_on_signal(path, s, signals=[signal.SIGALRM])
        signal.setitimer(signal.ITIMER_REAL, 0.1)  # during the run
    while s.step_count < N:
        s.integrator.run(N - s.step_count)
    np.save(out, s.part.all().pos)
""")


class Walltime(unittest.TestCase):
    def test_signal_checkpoint_and_resume(self):
        folder = tempfile.mkdtemp(prefix="test_walltime_")
        script = os.path.join(folder, "run.py")
        with open(script, "w") as f:
            f.write(WALLTIME_SCRIPT.format(here=os.path.dirname(os.path.abspath(__file__))))
        ckpt = os.path.join(folder, "ckpt.h5")

        def run(mode, out):
            return subprocess.run([os.path.join(BUILD, "pyoif"), script, ckpt, mode, os.path.join(folder, out)],
                                  capture_output=True, text=True, timeout=300)

        full = run("plain", "full.npy")
        self.assertEqual(full.returncode, 0, full.stderr)
        stopped = run("signal", "never.npy")
        self.assertEqual(stopped.returncode, checkpoint.EXIT_CHECKPOINTED, stopped.stderr)
        self.assertIn("checkpoint of step", stopped.stderr)
        self.assertFalse(os.path.exists(os.path.join(folder, "never.npy")))
        step = checkpoint.load(ckpt).system.step_count
        self.assertTrue(0 < step < 100000, step)
        resumed = run("resume", "resumed.npy")
        self.assertEqual(resumed.returncode, 0, resumed.stderr)
        np.testing.assert_array_equal(np.load(os.path.join(folder, "full.npy")),
                                      np.load(os.path.join(folder, "resumed.npy")))


if __name__ == "__main__":
    unittest.main()
