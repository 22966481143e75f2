"""The user guide (doc/, Sphinx): it builds without a warning, and every
Python example in it runs.

Each page's ```python blocks, with its hidden setups, make one script
(guide_examples.py), run with the launcher in an empty folder that links the
repository's samples/ (so paths such as samples/data/... read as from the
repository's root). A page passes when its script exits with status 0 and
prints no traceback; the number of blocks found must equal the page's
```python fences, so that a block the extractor misses fails the test."""
import glob
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from guide_examples import page_script  # noqa: E402

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
BUILD = os.environ.get("PYOIF_BUILD_DIR", os.path.join(SOURCE, "build"))
LAUNCHER = os.path.join(BUILD, "pyoif")


def guide_pages():
    """The guide's Markdown pages and the README (the first script)."""
    pages = sorted(glob.glob(os.path.join(SOURCE, "doc", "*.md")) + glob.glob(os.path.join(SOURCE, "doc", "*", "*.md")))
    return [p for p in pages if "/figures/" not in p] + [os.path.join(SOURCE, "README.md")]


class GuideExamples(unittest.TestCase):
    def test_study_cited_alike(self):
        """The bifurcation study the flagship reproduces is the PyOIF
        paper's (doc/model.md's citation, doi 10.1371/journal.pcbi.1008249):
        every page that introduces it names that paper, none another."""
        with open(os.path.join(SOURCE, "doc", "model.md")) as f:
            self.assertIn("doi:10.1371/journal.pcbi.1008249", f.read())
        for rel in ("doc/tutorial.md", "doc/study.md", "samples/cell_flow_in_bifurcation.py", "README.md"):
            with open(os.path.join(SOURCE, rel)) as f:
                text = " ".join(f.read().split())
            if "bifurcation" not in text:
                continue
            with self.subTest(page=rel):
                self.assertTrue("PyOIF paper" in text or "e1008249" in text,
                                f"{rel} speaks of the bifurcation study without naming the PyOIF paper")
                # the coupling's calibration is Busik et al.'s, the study is not
                for other in ("Bušík, Slavík, Cimrák, 2020", "Busik, Slavik, Cimrak, 2020"):
                    self.assertNotIn(other, text, f"{rel} credits the study to another paper")

    def test_every_example_runs(self):
        ran = 0
        for page in guide_pages():
            with open(page, encoding="utf-8") as f:
                text = f.read()
            script, n_blocks = page_script(text)
            fences = sum(1 for line in text.splitlines() if line.startswith("```python"))
            name = os.path.relpath(page, SOURCE)
            self.assertEqual(n_blocks, fences, f"{name}: {fences} python fences, {n_blocks} blocks extracted")
            if not n_blocks:
                continue
            with self.subTest(page=name), tempfile.TemporaryDirectory() as work:
                os.symlink(os.path.join(SOURCE, "samples"), os.path.join(work, "samples"))
                with open(os.path.join(work, "page.py"), "w", encoding="utf-8") as f:
                    f.write(script)
                env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1")
                run = subprocess.run([LAUNCHER, "page.py"], cwd=work, env=env, capture_output=True, text=True,
                                     timeout=300)
                output = run.stdout + run.stderr
                self.assertEqual(run.returncode, 0, f"{name}: its examples failed:\n{output[-3000:]}")
                self.assertNotIn("Traceback", output, f"{name}:\n{output[-3000:]}")
                ran += n_blocks
        # the guide's pages with examples: engine, lb, oif, interactions, checkpoints, concepts, tutorial, ...
        self.assertGreaterEqual(ran, 35, "fewer examples than the guide has")


class DocstringExamples(unittest.TestCase):
    """The API reference is made from the docstrings: their >>> examples run
    (doctest), in every module the reference documents."""

    def test_docstring_examples(self):
        import doctest
        import importlib
        import re
        modules = []
        for page in ("lbmd.md", "oif.md"):
            with open(os.path.join(SOURCE, "doc", "api", page), encoding="utf-8") as f:
                modules += re.findall(r"^\.\. automodule:: (\S+)", f.read(), re.M)
        self.assertGreaterEqual(len(modules), 20)
        attempted = 0
        for name in modules:
            result = doctest.testmod(importlib.import_module(name), verbose=False, report=True)
            self.assertEqual(result.failed, 0, f"{name}: {result.failed} docstring examples failed")
            attempted += result.attempted
        self.assertGreaterEqual(attempted, 3, "the docstrings' examples were not found")


class GuideBuild(unittest.TestCase):
    def test_builds_without_warnings(self):
        import importlib.util
        missing = [m for m in ("sphinx", "myst_parser", "sphinx_rtd_theme") if importlib.util.find_spec(m) is None]
        self.assertEqual(missing, [], "the guide needs Debian's python3-sphinx, python3-myst-parser and "
                                      "python3-sphinx-rtd-theme (maintainer/install-deps.sh)")
        with tempfile.TemporaryDirectory() as out:
            html = os.path.join(out, "html")
            run = subprocess.run([sys.executable, os.path.join(SOURCE, "maintainer", "build_guide.py"), BUILD, html],
                                 capture_output=True, text=True, timeout=600)
            self.assertEqual(run.returncode, 0, f"the guide has warnings or errors:\n{run.stdout}{run.stderr}")
            self.assertEqual(run.stderr.strip(), "", run.stderr)
            with open(os.path.join(html, "api", "lbmd.html"), encoding="utf-8") as f:
                api = f.read()
            for name in ("lbmd.System", "lbmd.lb.LBFluid", "lbmd.units.UnitSystem", "lbmd.checkpoint.save"):
                self.assertIn(f'id="{name}"', api, f"the API reference lacks {name}")
            with open(os.path.join(html, "api", "oif.html"), encoding="utf-8") as f:
                api = f.read()
            for name in ("oif.OifCellType", "oif.OifCell", "oif.seed_cells"):
                self.assertIn(f'id="{name}"', api, f"the API reference lacks {name}")
            self.assertGreater(os.path.getsize(os.path.join(html, "tutorials", "bifurcation.html")), 100_000,
                               "the tutorial notebook, rendered with its pictures")
            for page in ("installation", "concepts", "tutorial", "porting", "io-and-interactive", "visualization",
                         "bad-input", "performance"):
                self.assertTrue(os.path.isfile(os.path.join(html, page + ".html")), page)


if __name__ == "__main__":
    unittest.main()
