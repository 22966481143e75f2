"""The project stands alone: no tracked file (code, build files, tests,
samples, benchmarks, documentation) reads or links to anything outside the
repository. A user clones this repository and nothing else, so a path into a
folder beside the checkout, a developer machine's absolute path, a relative
path that climbs above the repository root, or a documentation link that
leads outside it (or nowhere) would break their build, tests or reading.

The files are those git tracks (`git ls-files`); without git (an unpacked
source archive) every file under the source tree except build folders."""
import os
import re
import subprocess
import unittest

ROOT = os.path.realpath(os.environ.get("PYOIF_SOURCE_DIR",
                                       os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")))
THIS = os.path.realpath(os.path.abspath(__file__))

# A folder beside the checkout that only developers have. (This file itself
# is skipped: its rule test below writes such references on purpose.)
SIBLING_FOLDER = re.compile(r"\.\.[/\\]shared\b|\bshared[/\\](data|design|reference|hooks)\b")
# Absolute paths of a developer's machine (the interpreter /usr/bin/python3
# and other system paths are fine: they come from Debian's packages).
MACHINE_PATH = re.compile(r"(?<![\w.~-])/(work|home|root|mnt|scratch|Users)/")
# A run of ../ inside a path: resolved against the file's folder.
PARENT_RUN = re.compile(r"(?<![\w.])((?:\.\./)+)([\w.\-/]*)")
# os.path.join(os.path.dirname(__file__), "..", "..", ...): resolved against the file's folder.
PY_JOIN_UP = re.compile(r"os\.path\.dirname\((?:os\.path\.(?:abspath|realpath)\()?__file__\)?\)\s*,"
                        r"((?:\s*[\"']\.\.[\"']\s*,?)+)")
# CMake paths from the source tree's variables.
CMAKE_PATH = re.compile(r"\$\{(PROJECT_SOURCE_DIR|CMAKE_SOURCE_DIR|CMAKE_CURRENT_SOURCE_DIR|"
                        r"CMAKE_CURRENT_LIST_DIR)\}(/[^\s;\"')}]*)?")
# Markdown links and images: [text](target) with a relative target.
MD_LINK = re.compile(r"\]\(([^)\s]+)\)")


def tracked_files(root):
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True, check=True)
        names = [n for n in out.stdout.decode().split("\0") if n]
        if names:
            return names
    except (OSError, subprocess.CalledProcessError):
        pass
    names = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d != ".git" and not d.startswith("build")]
        names += [os.path.relpath(os.path.join(folder, f), root) for f in files]
    return names


def text_of(path):
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data:
        return None  # binary
    return data.decode("utf-8", errors="replace")


def inside(root, path):
    path = os.path.normpath(path)
    return path == root or path.startswith(root + os.sep)


def problems_in(root, rel, text):
    """(line number, what) for each reference in one file's text that leads
    outside the repository."""
    folder = os.path.dirname(os.path.join(root, rel))
    depth = len(os.path.relpath(folder, root).split(os.sep)) if folder != root else 0
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        if SIBLING_FOLDER.search(line):
            found.append((number, "refers to the developers' folder beside the checkout"))
        m = MACHINE_PATH.search(line)
        if m:
            found.append((number, f"an absolute path on a developer's machine ('/{m.group(1)}/...')"))
        for m in PARENT_RUN.finditer(line):
            if not inside(root, os.path.join(folder, m.group(1) + m.group(2))):
                found.append((number, f"the relative path '{m.group(0)}' climbs above the repository root"))
        for m in PY_JOIN_UP.finditer(line):
            if m.group(1).count("..") > depth:
                found.append((number, f"os.path.join(dirname(__file__), {m.group(1).count('..')} x '..') climbs "
                                      f"above the repository root"))
        if rel.endswith(("CMakeLists.txt", ".cmake")):
            for m in CMAKE_PATH.finditer(line):
                base = root if m.group(1) in ("PROJECT_SOURCE_DIR", "CMAKE_SOURCE_DIR") else folder
                if not inside(root, base + (m.group(2) or "")):
                    found.append((number, f"the CMake path '{m.group(0)}' leads outside the source tree"))
        if rel.endswith(".md"):
            for m in MD_LINK.finditer(line):
                target = m.group(1).split("#")[0]
                if not target or re.match(r"^[a-z][a-z0-9+.-]*:", target):
                    continue  # an anchor on the same page, or a URL (https:, mailto:)
                resolved = os.path.join(folder, target)
                if not inside(root, resolved):
                    found.append((number, f"the link '{m.group(1)}' leads outside the repository"))
                elif not os.path.exists(resolved):
                    found.append((number, f"the link '{m.group(1)}' leads to a file that does not exist"))
    return found


class TestRepositoryStandsAlone(unittest.TestCase):

    def test_no_reference_outside_the_repository(self):
        names = tracked_files(ROOT)
        self.assertGreater(len(names), 50, "the source tree's files were not found")
        report = []
        for rel in names:
            path = os.path.join(ROOT, rel)
            if os.path.realpath(path) == THIS or not os.path.isfile(path):
                continue
            text = text_of(path)
            if text is None:
                continue
            report += [f"{rel}:{n}: {what}" for n, what in problems_in(ROOT, rel, text)]
        self.assertEqual(report, [], "tracked files refer to paths outside the repository:\n" + "\n".join(report))

    def test_the_rules_catch_each_kind(self):
        """Each rule finds what it is for (so that the test above can fail)."""
        cases = {
            "testsuite/python/test_x.py": [
                'DATA = "' + ".." + '/shared/data/meshes"',
                "mesh = '/work" + "/shared/data/x.dat'",
                'os.path.join(os.path.dirname(__file__), "..", "..", "..", "data")',
                'open("../../../outside.txt")',
            ],
            "testsuite/python/CMakeLists.txt": ["set(X ${PROJECT_SOURCE_DIR}/../data)"],
            "doc/page.md": ["see [the roadmap](../../design/roadmap.md)", "see [nothing](missing.md)"],
        }
        for rel, lines in cases.items():
            for line in lines:
                self.assertNotEqual(problems_in(ROOT, rel, line), [], f"{rel}: {line}")
        fine = {
            "testsuite/python/test_x.py": ['os.path.join(os.path.dirname(__file__), "..", "data")',
                                           'interpreter = "/usr/bin/python3"', 'open("../data/meshes/a.dat")'],
            "testsuite/python/CMakeLists.txt": ["set(X ${PROJECT_SOURCE_DIR}/testsuite/data)"],
            "doc/page.md": ["[engine](engine.md), [code](../src/core), [web](https://example.org/a/../b)"],
        }
        for rel, lines in fine.items():
            for line in lines:
                self.assertEqual(problems_in(ROOT, rel, line), [], f"{rel}: {line}")


if __name__ == "__main__":
    unittest.main()
