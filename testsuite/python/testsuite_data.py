"""Where the testsuite's own input files are: testsuite/data/ (ESPResSo's PyOIF
meshes and their provenance in testsuite/data/meshes/README.md). CTest sets
PYOIF_TEST_DATA; a test run by hand finds the folder beside this file.
Also where the sources and the build are (PYOIF_SOURCE_DIR, PYOIF_BUILD_DIR)
and `run_sample` and `read_csv`, which the tests of the samples share."""
import csv
import os
import subprocess

TEST_DATA = os.environ.get("PYOIF_TEST_DATA", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data"))
TEST_MESHES = os.path.join(TEST_DATA, "meshes")

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
BUILD = os.environ.get("PYOIF_BUILD_DIR", os.path.join(SOURCE, "build"))
LAUNCHER = os.path.join(BUILD, "pyoif")


def run_sample(name, *args, cwd, timeout=600):
    """stdout of `pyoif samples/<name> args` on one thread; the test fails
    with the sample's own output if it exits with an error."""
    proc = subprocess.run([LAUNCHER, os.path.join(SOURCE, "samples", name), *args],
                          cwd=cwd, capture_output=True, text=True, timeout=timeout,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    if proc.returncode != 0:
        raise AssertionError(f"{name} {' '.join(args)} exited with {proc.returncode}:\n"
                             f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    # the shipped samples are within every measured limit: system.check_settings()
    # has nothing to warn of (each of its warnings names a setting that fails).
    # Not yet the validation scans (samples/validation): capsule_shear's and
    # cell_drag's large frictions still draw the coupling's warning (gamma N
    # tau / (rho S agrid) 1.9 and 2.8 against the measured 1.4) while they
    # run stably: that limit is not yet measured per scene as the membrane's is
    if "SettingsWarning" in proc.stderr and not name.startswith("validation/"):
        raise AssertionError(f"{name} {' '.join(args)} warned of its settings:\n{proc.stderr[-3000:]}")
    return proc.stdout


def read_csv(path):
    """The rows of a CSV file as dicts (header line first; lines starting
    with '#', a data file's provenance, skipped)."""
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))
