"""CI's guard against silent skips: unittest_runner.py turns a file with
skipped tests into exit status 77 with one SKIPPED line per test (CTest's
SKIP_RETURN_CODE), and maintainer/check_skips.py fails on a skip that
testsuite/expected_skips.txt does not list."""
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
RUNNER = os.path.join(SOURCE, "testsuite", "python", "unittest_runner.py")
CHECK = os.path.join(SOURCE, "maintainer", "check_skips.py")

JUNIT = """<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="t" tests="3" failures="0" disabled="0" skipped="2">
  <testcase name="python_test_launcher" status="notrun"><skipped message="SKIP_RETURN_CODE=77"/>
    <system-out>SKIPPED: __main__.K.test_lab: Jupyter Lab is installed
</system-out></testcase>
  <testcase name="{name}" status="notrun"><skipped message="SKIP_REGULAR_EXPRESSION_MATCHED"/>
    <system-out>{out}
</system-out></testcase>
  <testcase name="cpp_test_ok" status="run"><system-out></system-out></testcase>
</testsuite>
"""


class CheckSkips(unittest.TestCase):
    def run_file(self, body):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "test_demo.py")
            with open(path, "w") as f:
                f.write(textwrap.dedent(body))
            return subprocess.run([sys.executable, RUNNER, path], capture_output=True, text=True, timeout=120)

    def check(self, name, out):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "junit.xml")
            with open(path, "w") as f:
                f.write(JUNIT.format(name=name, out=out))
            return subprocess.run([sys.executable, CHECK, path], capture_output=True, text=True, timeout=120)

    def test_runner_exit_status(self):
        head = "import unittest\nclass K(unittest.TestCase):\n"
        tail = "if __name__ == '__main__':\n    unittest.main()\n"
        ok = self.run_file(head + "    def test_a(self): pass\n" + tail)
        self.assertEqual(ok.returncode, 0, ok.stderr)
        skipped = self.run_file(head + "    def test_a(self): pass\n    def test_b(self): self.skipTest('no x here')\n"
                                + tail)
        self.assertEqual(skipped.returncode, 77, skipped.stderr)
        self.assertIn("SKIPPED: __main__.K.test_b: no x here", skipped.stdout)
        failed = self.run_file(head + "    def test_a(self): self.fail('no')\n    def test_b(self): self.skipTest('x')\n"
                               + tail)
        self.assertEqual(failed.returncode, 1)
        exits = self.run_file("import sys, unittest\nclass K(unittest.TestCase):\n    def test_a(self): pass\n"
                              "if __name__ == '__main__':\n    sys.exit(unittest.main())\n")
        self.assertEqual(exits.returncode, 0, exits.stderr)

    def test_expected_and_unexpected(self):
        expected = self.check("cpp_test_ok2", "")  # a skip without a reason line is unexpected too
        self.assertEqual(expected.returncode, 1)
        self.assertIn("UNEXPECTED skip: cpp_test_ok2: (no reason printed)", expected.stdout)
        gtest = self.check("cpp_test_x", "[  SKIPPED ] Suite.Case")
        self.assertEqual(gtest.returncode, 1)
        self.assertIn("UNEXPECTED skip: cpp_test_x: Suite.Case: GTEST_SKIP", gtest.stdout)
        self.assertIn("skip: python_test_launcher: __main__.K.test_lab: Jupyter Lab is installed", gtest.stdout)
        listed = self.check("python_test_lb_api", "SKIPPED: __main__.A.test_full: no /dev/full")
        self.assertEqual(listed.returncode, 0, listed.stdout + listed.stderr)
        self.assertIn("2 skip(s), all expected", listed.stdout)


if __name__ == "__main__":
    unittest.main()
