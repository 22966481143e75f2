"""Runs one test_*.py file for CTest so that a skipped test shows as skipped.

CTest knows one status per registered test (a file here); unittest exits 0
whether its tests ran or were skipped, so a file whose tests all skipped
used to count as passed. This runner executes the file as ``__main__`` with
``unittest.main`` wrapped: when every test passed it exits 0; when some were
skipped (and none failed) it prints one ``SKIPPED: <test id>: <reason>``
line per skip and exits 77, which the CMakeLists registers as
SKIP_RETURN_CODE, so CTest reports the file as skipped. Which skips are
expected on a machine is decided after the run by maintainer/check_skips.py
against testsuite/expected_skips.txt (the README's test command runs it).

Usage (CTest does this): pyoif unittest_runner.py test_something.py [args]
"""
import os
import runpy
import sys
import unittest

SKIP_RETURN_CODE = 77


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: pyoif unittest_runner.py test_file.py [unittest arguments]")
    path = os.path.abspath(sys.argv[1])
    sys.argv = [path] + sys.argv[2:]
    sys.path.insert(0, os.path.dirname(path))
    original_main = unittest.main
    outcome = {}

    class Main(original_main):
        """unittest.main that never exits itself: the runner decides."""

        def __init__(self, *args, **kwargs):
            kwargs["exit"] = False
            super().__init__(*args, **kwargs)
            outcome["result"] = self.result

    unittest.main = Main
    try:
        runpy.run_path(path, run_name="__main__")
    except SystemExit:
        # a file that exits by itself (sys.exit(unittest.main())) has run
        # its tests: the result decides; one that exits before them keeps
        # its own exit status
        if "result" not in outcome:
            raise
    finally:
        unittest.main = original_main
    result = outcome.get("result")
    if result is None:
        sys.exit(f"unittest_runner: {path} did not call unittest.main()")
    if not result.wasSuccessful():
        sys.exit(1)
    if result.skipped:
        sys.stdout.flush()
        for test, reason in result.skipped:
            print(f"SKIPPED: {test.id()}: {reason}", flush=True)
        sys.exit(SKIP_RETURN_CODE)
    sys.exit(0)


if __name__ == "__main__":
    main()
