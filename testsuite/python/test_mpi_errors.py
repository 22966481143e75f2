"""What a user sees under `mpirun -np 2 pyoif script.py`: an uncaught error on
one rank ends every rank within seconds (no hang in a collective, no rank left
behind) and says which rank failed; only rank 0 prints unless --all-ranks or
PYOIF_ALL_RANKS=1; lbmd.rank, lbmd.size and lbmd.comm are mpi4py's. Each test
starts mpirun itself, so this file runs serially under CTest."""
import os
import re
import shutil
import signal
import subprocess
import tempfile
import textwrap
import time
import unittest

BUILD = os.environ.get("PYOIF_BUILD_DIR")
MPIRUN = shutil.which("mpirun") or shutil.which("mpiexec")
TIMEOUT = 60  # seconds; a hang is what the abort-on-error hook prevents

# "#PID" in a script: each rank writes its pid to the folder given as its
# argument, so that the test can check that no rank outlives mpirun. The
# barrier: no rank fails (and ends the job) before all pids are written.
PID_LINE = """with open(os.path.join(sys.argv[1], f'pid_{lbmd.rank}'), 'w') as f:
    f.write(str(os.getpid()))
lbmd.comm.barrier()
"""


def alive(pid):
    """True while pid runs (a zombie, dead but not reaped, counts as alive:
    it is a rank left behind)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


@unittest.skipUnless(BUILD and os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class Base(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def script(self, text):
        path = os.path.join(self.tmp.name, "script.py")
        with open(path, "w") as f:
            f.write(textwrap.dedent(text).replace("#PID\n", PID_LINE))
        return path

    def run_cmd(self, cmd, env=None):
        """(returncode, stdout, stderr, seconds). The command runs in its own
        process group so that a hung job can be killed whole: killing mpirun
        alone would leave its ranks running."""
        # a PYOIF_ALL_RANKS of the caller's shell must not change what is tested
        env = dict({k: v for k, v in os.environ.items() if k != "PYOIF_ALL_RANKS"}, OMP_NUM_THREADS="1",
                   OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", **(env or {}))
        start = time.monotonic()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                cwd=self.tmp.name, start_new_session=True)
        try:
            out, err = proc.communicate(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            self.fail(f"{' '.join(cmd)} still ran after {TIMEOUT} s (killed):\n{out[-2000:]}\n{err[-2000:]}")
        return proc.returncode, out, err, time.monotonic() - start

    def pyoif(self, *args, env=None):
        return self.run_cmd([os.path.join(BUILD, "pyoif"), *args], env=env)

    def mpirun(self, *args, env=None):
        return self.run_cmd([MPIRUN, "--oversubscribe", "-np", "2", os.path.join(BUILD, "pyoif"), *args], env=env)

    def assert_ranks_gone(self):
        """Every rank that wrote its pid file has ended within a few seconds
        of mpirun's return."""
        pids = []
        for r in (0, 1):
            with open(os.path.join(self.tmp.name, f"pid_{r}")) as f:
                pids.append(int(f.read()))
        deadline = time.monotonic() + 5.0
        while any(alive(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertEqual([p for p in pids if alive(p)], [], "ranks left running after mpirun returned")


@unittest.skipUnless(MPIRUN, "no mpirun or mpiexec")
class ErrorOnOneRank(Base):
    def test_error_on_rank_1_ends_all_ranks(self):
        """Rank 1 raises while rank 0 runs the integrator and then waits in a
        barrier for it: without the hook rank 0 would wait forever."""
        path = self.script("""
            import os, sys
            import lbmd
            #PID
            s = lbmd.System(box_l=[4.0, 4.0, 4.0], time_step=0.01)
            s.part.add(pos=[1.0, 1.0, 1.0], v=[0.1, 0.0, 0.0])
            if lbmd.rank == 1:
                raise ValueError("boom on rank 1")
            s.integrator.run(100)
            lbmd.comm.barrier()
            print("rank 0 passed the barrier")
            """)
        rc, out, err, seconds = self.mpirun(path, self.tmp.name)
        self.assertNotEqual(rc, 0, err)
        self.assertIn("boom on rank 1", err)
        self.assertIn("[rank 1] Traceback (most recent call last):", err)
        self.assertIn("[rank 1] ValueError: boom on rank 1", err)
        self.assertNotIn("[rank 0]", err)
        self.assertNotIn("passed the barrier", out)
        self.assertLess(seconds, 30.0)
        self.assert_ranks_gone()

    def test_engine_error_on_one_rank_raised_on_every_rank(self):
        """With a fluid the particles are spread over the ranks: a particle
        that rank 1 integrates is pushed into a wall. Only rank 1 sees it,
        yet every rank raises the same SimulationInstability (the script
        catches it and goes on: no rank is left waiting), and likewise for
        a fluid node that becomes unstable in rank 1's subdomain."""
        path = self.script("""
            import os, sys
            import lbmd
            #PID
            def scene():
                s = lbmd.System(box_l=[16.0, 8.0, 8.0])
                s.time_step = 0.1
                s.cell_system.node_grid = [2, 1, 1]
                lbf = lbmd.lb.LBFluid(agrid=1.0, tau=0.1, dens=1.0, visc=1.0)
                s.actors.add(lbf)
                s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0)
                return s, lbf
            s, lbf = scene()
            s.constraints.add(shape=lbmd.shapes.Wall(normal=[0, 0, 1], dist=1.0), particle_type=1)
            s.non_bonded_inter[0, 1].soft_sphere.set_params(a=1e-4, n=1.0, cutoff=1.0)
            # x = 12: rank 1's half; driven through the wall at z = 1
            s.part.add(pos=[[12.0, 4.0, 1.5], [3.0, 4.0, 4.0]], v=[[0, 0, -2.0], [0, 0, 0]])
            try:
                s.integrator.run(20)
                print(f"@rank {lbmd.rank}: no error@", file=sys.stderr, flush=True)
            except lbmd.SimulationInstability as e:
                print(f"@rank {lbmd.rank} caught: {e} [{e.cause} {e.step} {e.particle} {e.value}]@",
                      file=sys.stderr, flush=True)
            s2, lbf2 = scene()
            lbf2[12, 4, 4].velocity = [8.0, 0.0, 0.0]  # 0.8 lattice units, beyond the sound speed; rank 1
            try:
                s2.integrator.run(5)
                print(f"@rank {lbmd.rank}: no fluid error@", file=sys.stderr, flush=True)
            except lbmd.SimulationInstability as e:
                print(f"@rank {lbmd.rank} fluid: {e} [{e.cause} {e.step} {e.node}]@", file=sys.stderr,
                      flush=True)
            lbmd.comm.barrier()
            print("all ranks went on")
            """)
        rc, out, err, seconds = self.mpirun(path, self.tmp.name)
        self.assertEqual(rc, 0, err)
        self.assertIn("all ranks went on", out)
        # (the ranks' lines may interleave on stderr: markers delimit them)
        caught = dict(re.findall(r"@rank (\d) caught: (.*?)@", err, re.S))
        self.assertEqual(sorted(caught), ["0", "1"], err)
        self.assertTrue(caught["0"].startswith("particle 0 "), caught)
        self.assertIn("penetrated", caught["0"])
        # the attributes travel with the message (lbmd.SimulationInstability)
        self.assertRegex(caught["0"], r"\[wall_penetration \d+ 0 [-0-9.e]+\]$")
        self.assertEqual(caught["0"], caught["1"])
        fluid = dict(re.findall(r"@rank (\d) fluid: (.*?)@", err, re.S))
        self.assertEqual(sorted(fluid), ["0", "1"], err)
        self.assertIn("unstable at node (12, 4, 4)", fluid["0"])
        self.assertTrue(fluid["0"].endswith("[mach 1 (12, 4, 4)]"), fluid["0"])
        self.assertEqual(fluid["0"], fluid["1"])
        self.assertLess(seconds, 30.0)
        self.assert_ranks_gone()

    def test_query_on_one_rank_says_why_it_waits(self):
        """A query made on rank 0 alone (inside `if lbmd.rank == 0:`) cannot
        return until the other ranks make it too: rank 0 says so on stderr
        (after PYOIF_COLLECTIVE_WARN_S seconds, 10 by default) instead of
        hanging without a word. Here rank 1 makes the query later, so the
        job ends normally."""
        path = self.script("""
            import os, sys, time
            import lbmd
            #PID
            s = lbmd.System(box_l=[16.0, 8.0, 8.0]); s.time_step = 0.1
            lbf = lbmd.lb.LBFluid(agrid=1.0, tau=0.1, dens=1.0, visc=1.0)
            s.actors.add(lbf)
            s.part.add(pos=[[3.0, 3.0, 3.0]])
            if lbmd.rank == 1:
                time.sleep(4.0)
            print("position", s.part.all().pos[0])
            """)
        rc, out, err, seconds = self.mpirun(path, self.tmp.name, env={"PYOIF_COLLECTIVE_WARN_S": "1"})
        self.assertEqual(rc, 0, err)
        self.assertIn("position [3. 3. 3.]", out)
        self.assertIn("[rank 0] a particle property query has waited 1 s for the other ranks", err)
        self.assertIn("inside `if lbmd.rank == 0:`", err)
        self.assertNotIn("[rank 1] a particle property query", err)
        self.assert_ranks_gone()

    def test_error_on_rank_0_keeps_its_printed_lines(self):
        """What the failing rank printed before the error (buffered, stdout is
        a pipe) still comes out: the hook flushes before MPI_Abort."""
        path = self.script("""
            import os, sys
            import lbmd
            #PID
            print("rank 0 printed this before failing")
            if lbmd.rank == 0:
                raise KeyError("lost key on rank 0")
            lbmd.comm.barrier()
            """)
        rc, out, err, _ = self.mpirun(path, self.tmp.name)
        self.assertNotEqual(rc, 0, err)
        self.assertIn("rank 0 printed this before failing", out)
        self.assertIn("[rank 0] KeyError: 'lost key on rank 0'", err)
        self.assertNotIn("[rank 1]", err)
        self.assert_ranks_gone()

    def test_one_rank_keeps_python_behaviour(self):
        """Without mpirun: Python's own traceback and exit status 1."""
        path = self.script("""
            import sys
            import lbmd
            assert sys.excepthook is sys.__excepthook__
            raise ValueError("boom alone")
            """)
        rc, out, err, _ = self.pyoif(path)
        self.assertEqual(rc, 1, err)
        self.assertIn("\nValueError: boom alone", err)
        self.assertNotIn("[rank", err)


HELLO = """
    import sys
    from mpi4py import MPI
    import lbmd
    print(f"hello from {lbmd.rank}")
    print(f"ids {lbmd.rank} {MPI.COMM_WORLD.Get_rank()} {lbmd.size} {MPI.COMM_WORLD.Get_size()} "
          f"{type(lbmd.rank).__name__} {type(lbmd.size).__name__} {lbmd.comm is MPI.COMM_WORLD}")
    print(f"note from {lbmd.rank}", file=sys.stderr)
    """


@unittest.skipUnless(MPIRUN, "no mpirun or mpiexec")
class Printing(Base):
    def test_only_rank_0_prints(self):
        rc, out, err, _ = self.mpirun(self.script(HELLO))
        self.assertEqual(rc, 0, err)
        self.assertIn("hello from 0", out)
        self.assertNotIn("hello from 1", out)
        # stderr stays on every rank
        self.assertIn("note from 0", err)
        self.assertIn("note from 1", err)

    def test_all_ranks_option(self):
        rc, out, err, _ = self.mpirun("--all-ranks", self.script(HELLO))
        self.assertEqual(rc, 0, err)
        self.assertIn("hello from 0", out)
        self.assertIn("hello from 1", out)

    def test_rank_size_comm_are_mpi4py_s(self):
        """lbmd.rank/size/comm agree with mpi4py on each rank (printed by
        both ranks through PYOIF_ALL_RANKS=1)."""
        rc, out, err, _ = self.mpirun(self.script(HELLO), env={"PYOIF_ALL_RANKS": "1"})
        self.assertEqual(rc, 0, err)
        ids = sorted(line for line in out.splitlines() if line.startswith("ids "))
        self.assertEqual(ids, ["ids 0 0 2 2 int int True", "ids 1 1 2 2 int int True"])

    def test_one_rank(self):
        rc, out, err, _ = self.pyoif(self.script(HELLO))
        self.assertEqual(rc, 0, err)
        self.assertIn("ids 0 0 1 1 int int True", out)


if __name__ == "__main__":
    unittest.main()
