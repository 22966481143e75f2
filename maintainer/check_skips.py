#!/usr/bin/python3
"""Fails when CTest skipped a test that testsuite/expected_skips.txt does not list.

CTest shows a skipped test as skipped (the Python tests exit 77 through
testsuite/python/unittest_runner.py, a GoogleTest skip matches the tests'
SKIP_REGULAR_EXPRESSION) but still exits 0, so a test that silently stopped
running (no mpirun found, a feature probe gone wrong, a file renamed) would
pass CI. The README's test command runs this after ctest with the JUnit file
ctest wrote (--output-junit):

    /usr/bin/python3 maintainer/check_skips.py build/ctest-junit.xml

Each skip is described as "<ctest name>: <test id>: <reason>" (one per
skipped unittest or GoogleTest case); it is expected when it matches one of
the shell-style patterns in testsuite/expected_skips.txt. Exit 0 when every
skip is expected (they are printed), 1 otherwise (the unexpected ones are
named), 2 when the file cannot be read.
"""
import fnmatch
import os
import re
import sys
import xml.etree.ElementTree as ElementTree

HERE = os.path.dirname(os.path.abspath(__file__))
EXPECTED = os.path.join(HERE, "..", "testsuite", "expected_skips.txt")


def expected_patterns(path=EXPECTED):
    """The patterns of testsuite/expected_skips.txt (comments and blank lines dropped)."""
    patterns = []
    with open(path, encoding="utf-8") as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                patterns.append(line)
    return patterns


def skips(junit_path):
    """One description per skipped case of every skipped ctest test."""
    root = ElementTree.parse(junit_path).getroot()
    found = []
    for case in root.iter("testcase"):
        if case.find("skipped") is None:
            continue
        name = case.get("name")
        out = case.findtext("system-out") or ""
        cases = [f"{name}: {m.group(1).strip()}" for m in re.finditer(r"^SKIPPED: (.*)$", out, re.M)]
        cases += [f"{name}: {m.group(1).strip()}: GTEST_SKIP"
                  for m in re.finditer(r"^\[  SKIPPED \] (\S+)\s*$", out, re.M)]
        found += cases or [f"{name}: (no reason printed)"]
    return found


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        found = skips(argv[1])
        patterns = expected_patterns()
    except (OSError, ElementTree.ParseError) as error:
        print(f"check_skips: cannot read {error}", file=sys.stderr)
        return 2
    unexpected = [s for s in found if not any(fnmatch.fnmatchcase(s, p) for p in patterns)]
    for s in found:
        print(f"check_skips: {'UNEXPECTED ' if s in unexpected else ''}skip: {s}")
    if unexpected:
        print(f"check_skips: {len(unexpected)} skip(s) not listed in testsuite/expected_skips.txt: "
              "make the test run here, or list the skip there with the reason it is "
              "expected on this kind of machine", file=sys.stderr)
        return 1
    print(f"check_skips: {len(found)} skip(s), all expected")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
