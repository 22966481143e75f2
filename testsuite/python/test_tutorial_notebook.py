"""doc/tutorials/bifurcation.ipynb: stored with its pictures, and it runs
headless from start to end (nbclient, on the "PyOIF" kernel of the build
tree) without an error, making its pictures again."""
import base64
import os
import tempfile
import unittest

import nbformat

BUILD = os.environ.get("PYOIF_BUILD_DIR")
SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
NOTEBOOK = os.path.join(SOURCE, "doc", "tutorials", "bifurcation.ipynb")
PNG = b"\x89PNG\r\n\x1a\n"


def pictures(nb):
    return [base64.b64decode(o["data"]["image/png"]) for c in nb.cells if c.cell_type == "code"
            for o in c.outputs if "image/png" in o.get("data", {})]


def errors(nb):
    return [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o["output_type"] == "error"]


class Tutorial(unittest.TestCase):
    def test_stored_with_outputs(self):
        nb = nbformat.read(NOTEBOOK, as_version=4)
        nbformat.validate(nb)
        self.assertEqual(nb.metadata["kernelspec"]["name"], "pyoif")
        self.assertEqual(errors(nb), [])
        shown = pictures(nb)
        self.assertGreaterEqual(len(shown), 6)
        self.assertTrue(all(p.startswith(PNG) and len(p) > 5000 for p in shown))
        code = [c for c in nb.cells if c.cell_type == "code"]
        self.assertTrue(all(c.execution_count is not None for c in code), "the notebook was not executed")

    @unittest.skipUnless(BUILD, "PYOIF_BUILD_DIR not set (run through CTest)")
    def test_executes(self):
        from nbclient import NotebookClient
        nb = nbformat.read(NOTEBOOK, as_version=4)
        for c in nb.cells:
            if c.cell_type == "code":
                c.outputs = []
        from unittest import mock
        # the kernel "pyoif" is in the build tree's share/jupyter; the environment is restored afterwards
        with mock.patch.dict(os.environ, {"JUPYTER_PATH": os.path.join(BUILD, "share", "jupyter")}), \
                tempfile.TemporaryDirectory() as tmp:
            os.environ.pop("PYTHONPATH", None)  # the kernel spec brings it
            NotebookClient(nb, kernel_name="pyoif", timeout=300, resources={"metadata": {"path": tmp}}).execute()
        self.assertEqual(errors(nb), [])
        self.assertGreaterEqual(len(pictures(nb)), 6)
        run = [c for c in nb.cells if c.cell_type == "code" and "view.run(" in c.source][0]
        self.assertEqual(run.outputs[-1]["data"]["text/plain"], "15000")  # LiveView ran every step


if __name__ == "__main__":
    unittest.main()
