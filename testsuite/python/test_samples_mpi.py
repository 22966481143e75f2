"""Every sample runs unchanged under `mpirun -np 2 pyoif sample.py`, with the
short arguments of test_samples.py, and gives the serial run's result: the
same printed table, digit for digit (the physics must not depend on the rank
count), and the same output files, each once (nothing missing, no second
copy or leftover temporary file from another rank). The launcher shows rank
0's stdout only, so the table appears once."""
import os
import shutil
import signal
import subprocess
import tempfile
import unittest

import numpy as np

import test_samples as serial  # the module, so that its tests do not run again here
from testsuite_data import BUILD, LAUNCHER, SOURCE, run_sample

MPIRUN = shutil.which("mpirun") or shutil.which("mpiexec")
TIMEOUT = 300  # seconds; each run takes a few


def run_sample_mpi(name, *args, cwd):
    """stdout of `mpirun -np 2 pyoif samples/<name> args`; the test fails with
    the run's output if it exits with an error or hangs (then the whole job,
    ranks included, is killed)."""
    env = dict({k: v for k, v in os.environ.items() if k != "PYOIF_ALL_RANKS"}, OMP_NUM_THREADS="1",
               OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [MPIRUN, "--oversubscribe", "-np", "2", LAUNCHER,
           os.path.join(SOURCE, "samples", name), *args]
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"mpirun -np 2 {name} {' '.join(args)} still ran after {TIMEOUT} s:\n"
                             f"{out[-3000:]}\n{err[-3000:]}")
    if proc.returncode != 0:
        raise AssertionError(f"mpirun -np 2 {name} {' '.join(args)} exited with {proc.returncode}:\n"
                             f"{out[-3000:]}\n{err[-3000:]}")
    return out


def result_lines(stdout):
    """The lines of a sample's result that are not a numeric table row: the
    bifurcation's scene line, branch entries and the cells' drift."""
    return [line for line in stdout.splitlines()
            if line.startswith(("cycle ", "share ", "small scene", "branch entries", "largest change",
                                "mass flux out", "  outlet "))]


def files_under(folder):
    return sorted(os.path.relpath(os.path.join(d, f), folder) for d, _, files in os.walk(folder) for f in files)


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
@unittest.skipUnless(MPIRUN, "no mpirun or mpiexec")
class SamplesUnderMpirun(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.serial_dir = os.path.join(tmp.name, "serial")
        self.mpi_dir = os.path.join(tmp.name, "mpi")
        os.mkdir(self.serial_dir)
        os.mkdir(self.mpi_dir)

    def check_same_as_serial(self, name, *args, csv_files=()):
        """Runs the sample serially and on two ranks, each in its own folder,
        and compares."""
        out_serial = run_sample(name, *args, cwd=self.serial_dir)
        out_mpi = run_sample_mpi(name, *args, cwd=self.mpi_dir)
        rows_serial, rows_mpi = serial.table_rows(out_serial), serial.table_rows(out_mpi)
        np.testing.assert_array_equal(rows_mpi, rows_serial, err_msg=f"{name}: the printed table differs")
        lines = result_lines(out_serial)
        self.assertGreater(len(rows_serial) + len(lines), 0, f"{name}: no result printed (test out of date?)")
        self.assertEqual(result_lines(out_mpi), lines)
        written = files_under(self.serial_dir)
        self.assertTrue(written, f"{name}: the serial run wrote no file")
        self.assertEqual(files_under(self.mpi_dir), written)
        for path in csv_files:
            with open(os.path.join(self.serial_dir, path)) as a, open(os.path.join(self.mpi_dir, path)) as b:
                self.assertEqual(b.read(), a.read(), path)

    def test_single_cell(self):
        self.check_same_as_serial("oif_single_cell.py", "--cycles", "3", "--steps", "100", "--output", "out")

    def test_two_cells(self):
        self.check_same_as_serial("oif_two_cells.py", "--cycles", "2", "--steps", "100", "--output", "out")

    def test_bifurcation(self):
        self.check_same_as_serial("cell_flow_in_bifurcation.py", "--cells", "4", "--cycles", "2", "--steps", "100",
                                  "--output", "out", csv_files=("out/cells.csv", "out/branches.csv", "out/crossings.csv",
                                             "out/haematocrit.csv", "out/scene.json"))

    def test_device_t_junction(self):
        """The T-junction layout: an inlet on x-, outlets on x+ and on y+ (its
        opposite face closed by the channel's floor); the cells' table and
        their entries and exits (by outlet) bit for bit at 1 and 2 ranks."""
        layout = os.path.join(SOURCE, "samples", "data", "t_junction.svg")
        self.check_same_as_serial("device_from_mask.py", "--layout", layout, "--outlets", "x+", "y+", "--scale", "1.5",
                                  "--speed", "1.3", "--duration", "0.3",
                                  "--output-every", "50", "--haematocrit", "0.1", "--output", "tj", "--no-plots",
                                  csv_files=("tj/cells.csv", "tj/events.csv", "tj/scene.json"))

    def test_bifurcation_rare(self):
        self.check_same_as_serial("cell_flow_in_bifurcation.py", "--cells", "2", "--rare", "--cycles", "1",
                                  "--steps", "20", "--output", "rare", csv_files=("rare/cells.csv",))


if __name__ == "__main__":
    unittest.main()
