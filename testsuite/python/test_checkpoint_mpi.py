"""Checkpoints under mpirun: a run continued from a checkpoint equals the
uninterrupted run bit for bit at the same rank count (1 and 2 ranks: fluid
with kT > 0, cells straddling the subdomain cuts and the periodic boundary,
walls, contacts, the coupling's noise; two MD steps per lattice update,
saved between them); a checkpoint loads at another rank count (2 -> 1,
1 -> 3) with the state as saved and the continued run equal to the
uninterrupted one, sums over ranks to round-off (rtol 1e-12, as
test_mpi_equality). The flagship sample, signalled (SIGUSR1 to mpirun) at 2
ranks, exits with status 75 and its checkpoint; --resume finishes the run
with the tables of an uninterrupted run, byte for byte.

This process starts mpirun: it imports neither mpi4py nor lbmd.
"""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from test_mpi_equality import LAUNCHER, MPIRUN, SOURCE, compare_states  # noqa: E402

SCENES = os.path.join(HERE, "checkpoint_scenes.py")
SAMPLE = os.path.join(SOURCE, "samples", "cell_flow_in_bifurcation.py")
N1, N2 = 41, 40          # MD steps before and after the checkpoint (41: between two lattice updates)
EXIT_CHECKPOINTED = 75   # lbmd.checkpoint.EXIT_CHECKPOINTED
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def mpirun(ranks, *args, timeout=300):
    cmd = [MPIRUN, "--oversubscribe", "-np", str(ranks), LAUNCHER, *args]
    done = subprocess.run(cmd, capture_output=True, text=True, env=ENV, timeout=timeout)
    if done.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return done


def load(path):
    with np.load(path) as f:
        return {k: f[k] for k in f.files}


@unittest.skipIf(MPIRUN is None, "no mpirun")
class CheckpointRanks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.mkdtemp(prefix="test_checkpoint_mpi_")
        for ranks in (1, 2):
            mpirun(ranks, SCENES, "full", str(N1), str(N2), cls.f(f"c{ranks}.h5"), cls.f(f"full{ranks}.npz"))

    @classmethod
    def f(cls, name):
        return os.path.join(cls.folder, name)

    def resume(self, saved_at, ranks):
        out, loaded = self.f(f"r{saved_at}{ranks}.npz"), self.f(f"l{saved_at}{ranks}.npz")
        mpirun(ranks, SCENES, "resume", self.f(f"c{saved_at}.h5"), str(N2), out, loaded)
        return load(out), load(loaded)

    def assert_identical(self, a, b, label):
        differ = [k for k in a if k != "ranks" and not np.array_equal(a[k], b[k])]
        self.assertEqual(differ, [], f"{label}: these quantities differ")

    def test_same_rank_count_bit_for_bit(self):
        for ranks in (1, 2):
            result, _ = self.resume(ranks, ranks)
            self.assert_identical(load(self.f(f"full{ranks}.npz")), result, f"{ranks} -> {ranks} ranks")
        # not trivially equal: the cells moved and the fluid changed
        full = load(self.f("full1.npz"))
        self.assertGreater(np.abs(full["part_v"]).max(), 0.0)

    def test_other_rank_count(self):
        for saved_at, ranks in ((2, 1), (1, 3)):
            result, loaded = self.resume(saved_at, ranks)
            compare_states(load(self.f(f"full{saved_at}.npz")), result, f"saved at {saved_at}, run on {ranks}")
            self.assertAlmostEqual(float(loaded["time"]), N1 * 0.05, places=12)


@unittest.skipIf(MPIRUN is None, "no mpirun")
class SignalOnOneRank(unittest.TestCase):
    def test_ranks_agree_on_the_step(self):
        """Rank 1 alone gets the signal: both ranks stop after the same step
        (one checkpoint, status 75), and the resumed run ends in the state
        of the uninterrupted one, bit for bit."""
        folder = tempfile.mkdtemp(prefix="test_checkpoint_one_rank_")
        n = 1500
        mpirun(2, SCENES, "walltime", os.path.join(folder, "none.h5"), str(n), os.path.join(folder, "whole.npz"))
        ckpt = os.path.join(folder, "ckpt.h5")
        cmd = [MPIRUN, "--oversubscribe", "-np", "2", LAUNCHER, SCENES, "walltime", ckpt, str(n),
               os.path.join(folder, "never.npz"), "1"]
        stopped = subprocess.run(cmd, capture_output=True, text=True, env=ENV, timeout=300)
        self.assertEqual(stopped.returncode, EXIT_CHECKPOINTED, stopped.stderr[-3000:])
        self.assertEqual(stopped.stderr.count("checkpoint of step"), 1, stopped.stderr[-3000:])
        self.assertFalse(os.path.exists(os.path.join(folder, "never.npz")))
        mpirun(2, SCENES, "walltime", ckpt, str(n), os.path.join(folder, "resumed.npz"))
        whole, resumed = load(os.path.join(folder, "whole.npz")), load(os.path.join(folder, "resumed.npz"))
        differ = [k for k in whole if not np.array_equal(whole[k], resumed[k])]
        self.assertEqual(differ, [])


@unittest.skipIf(MPIRUN is None, "no mpirun")
class SampleSignalled(unittest.TestCase):
    def test_walltime_signal_and_resume(self):
        folder = tempfile.mkdtemp(prefix="test_checkpoint_sample_")
        options = ["--cells", "6", "--force", "3e-3", "--duration", "0.6", "--no-plots", "--progress", "off"]
        mpirun(1, SAMPLE, *options, "--output", os.path.join(folder, "whole"))
        out = os.path.join(folder, "split")
        cmd = [MPIRUN, "--oversubscribe", "-np", "2", LAUNCHER, SAMPLE, *options, "--output", out]
        job = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
        # signal once the cells run (the tables exist): a walltime warning
        deadline = time.monotonic() + 120
        while not os.path.exists(os.path.join(out, "cells.csv")) and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(1.0)
        job.send_signal(signal.SIGUSR1)
        stdout, stderr = job.communicate(timeout=300)
        self.assertEqual(job.returncode, EXIT_CHECKPOINTED, stderr[-3000:])
        self.assertIn("checkpoint of step", stderr)
        mpirun(2, SAMPLE, "--resume", "--output", out, "--no-plots", "--progress", "off")
        for table in ("cells.csv", "branches.csv", "crossings.csv", "haematocrit.csv"):
            with open(os.path.join(folder, "whole", table)) as a, open(os.path.join(out, table)) as b:
                self.assertEqual(a.read(), b.read(), table)


if __name__ == "__main__":
    unittest.main()
