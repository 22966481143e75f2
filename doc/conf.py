"""Sphinx configuration of the PyOIF user guide.

Build it with ``cmake --build build --target doc`` (HTML in build/doc/html);
the target puts the built ``lbmd`` and ``oif`` packages on the path so that
the API reference is generated from their docstrings. Warnings are errors.
"""
import os
import sys

project = "PyOIF"
author = "The PyOIF developers"
copyright = "2026, The PyOIF developers (GPL-3.0-or-later)"

# the packages as built (lbmd needs its compiled extension)
_python_dir = os.environ.get("PYOIF_PYTHON_DIR")
if _python_dir:
    sys.path.insert(0, _python_dir)

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.mathjax", "sphinx.ext.viewcode"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "figures/**/README.md", "tutorials/*.ipynb"]

myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "none"

html_theme = "sphinx_rtd_theme"
html_title = "PyOIF user guide"
html_static_path = []
# pages rendered outside Sphinx (the executed tutorial notebook)
html_extra_path = [p for p in [os.environ.get("PYOIF_GUIDE_EXTRA")] if p and os.path.isdir(p)]
