"""ESPResSo 4.2.2's own object-in-fluid test and sample, run unchanged except
for the porting rule (doc/porting.md): 'espressomd' -> 'lbmd' and
'object_in_fluid' -> 'oif' in their text. The originals are kept verbatim in
espresso_4_2_2/ (provenance and licence in its README.md):

- testsuite/oif_volume_conservation.py: ESPResSo's unit test (relaxation of a
  stretched sphere, exponential decay rate, elastic_forces of a cell cut to
  20 triangles);
- samples/object_in_fluid/motivation.py, run by ESPResSo's own sample test
  testsuite/test_object_in_fluid__motivation.py (4 cycles of 500 steps
  instead of 50, command-line argument 0, as ESPResSo's CTest runs it; that
  harness imports neither package and runs unchanged).

ESPResSo's test helpers (unittest_decorators, tests_common,
importlib_wrapper) are this project's stand-ins in espresso_4_2_2/support/.
The sample's input meshes are ESPResSo's rbc374 files, byte-identical in
testsuite/data/meshes/."""
import os
import shutil
import subprocess
import tempfile
import unittest

from testsuite_data import LAUNCHER, TEST_MESHES

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "espresso_4_2_2")
SUPPORT = os.path.join(HERE, "support")


def port(text):
    """The porting rule, nothing else."""
    return text.replace("espressomd", "lbmd").replace("object_in_fluid", "oif")


def read(*path):
    with open(os.path.join(HERE, *path)) as f:
        return f.read()


class TestEspresso422(unittest.TestCase):

    def run_unittest_file(self, path, cwd):
        env = dict(os.environ, OMP_NUM_THREADS="1",
                   PYTHONPATH=os.pathsep.join(filter(None, [SUPPORT, os.environ.get("PYTHONPATH")])))
        proc = subprocess.run([LAUNCHER, path], cwd=cwd, capture_output=True, text=True, timeout=800, env=env)
        output = proc.stdout + proc.stderr
        self.assertEqual(proc.returncode, 0, output[-6000:])
        # unittest's summary: every test ran, none skipped
        self.assertRegex(output, r"\nOK\s*$")
        self.assertNotIn("skipped", output)
        return output

    def test_rule_is_the_only_change(self):
        original = read("testsuite", "oif_volume_conservation.py")
        ported = port(original)
        changed = [(a, b) for a, b in zip(original.splitlines(), ported.splitlines()) if a != b]
        self.assertEqual([b for _, b in changed],
                         ["import lbmd", "import oif as oif",
                          "    system = lbmd.System(box_l=(50., 50., 50.))",
                          "        Load a soft elastic sphere via ``oif``, stretch it and"])

    def test_oif_volume_conservation(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "oif_volume_conservation.py")
            with open(path, "w") as f:
                f.write(port(read("testsuite", "oif_volume_conservation.py")))
            output = self.run_unittest_file(path, tmp)
        self.assertIn("Ran 2 tests", output)

    def test_sample_motivation(self):
        with tempfile.TemporaryDirectory() as tmp:
            sample_dir = os.path.join(tmp, "samples", "object_in_fluid")
            os.makedirs(os.path.join(sample_dir, "input"))
            for name in ("rbc374nodes.dat", "rbc374triangles.dat"):
                shutil.copy(os.path.join(TEST_MESHES, name), os.path.join(sample_dir, "input", name))
            with open(os.path.join(sample_dir, "motivation.py"), "w") as f:
                f.write(port(read("samples", "object_in_fluid", "motivation.py")))
            # ESPResSo's sample test is a CMake template, @SAMPLES_DIR@ its only
            # placeholder; it imports neither package, and the rule would also
            # rename the folder name object_in_fluid in its paths: not ported
            test = read("testsuite", "test_object_in_fluid__motivation.py")
            self.assertNotIn("espressomd", test)
            self.assertNotIn("import object_in_fluid", test)
            path = os.path.join(tmp, "test_object_in_fluid__motivation.py")
            with open(path, "w") as f:
                f.write(test.replace("@SAMPLES_DIR@", os.path.join(tmp, "samples")))
            output = self.run_unittest_file(path, tmp)
            self.assertIn("Ran 1 test", output)
            self.assertIn("Simulation completed.", output)
            out = sorted(os.listdir(os.path.join(sample_dir, "output", "sim0")))
        self.assertIn("cell1_3.vtk", out)
        self.assertNotIn("cell1_4.vtk", out)  # maxCycle = 4: cycles 0..3


if __name__ == "__main__":
    unittest.main()
