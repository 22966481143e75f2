#!/usr/bin/python3
"""Build the user guide (Sphinx, HTML) from doc/ with the built packages.

    /usr/bin/python3 maintainer/build_guide.py BUILD_DIR [OUTPUT_DIR]

BUILD_DIR is the CMake build folder (its python/ holds lbmd and oif, whose
docstrings make the API reference); OUTPUT_DIR defaults to BUILD_DIR/doc/html.
The tutorial notebooks in doc/tutorials/ are rendered to HTML beside the
guide (nbconvert, with the outputs they were saved with). Warnings are
errors. Used by `cmake --build build --target doc` and by the testsuite.
"""
import glob
import os
import subprocess
import sys

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def render_notebooks(extra_dir):
    """Each doc/tutorials/*.ipynb as extra_dir/tutorials/NAME.html."""
    notebooks = sorted(glob.glob(os.path.join(SOURCE, "doc", "tutorials", "*.ipynb")))
    if not notebooks:
        return
    import nbformat
    from nbconvert import HTMLExporter
    os.makedirs(os.path.join(extra_dir, "tutorials"), exist_ok=True)
    exporter = HTMLExporter()
    for path in notebooks:
        html, _ = exporter.from_notebook_node(nbformat.read(path, as_version=4))
        name = os.path.splitext(os.path.basename(path))[0] + ".html"
        with open(os.path.join(extra_dir, "tutorials", name), "w", encoding="utf-8") as f:
            f.write(html)


def main(argv):
    if len(argv) not in (2, 3):
        sys.exit(__doc__)
    build = os.path.abspath(argv[1])
    output = os.path.abspath(argv[2]) if len(argv) == 3 else os.path.join(build, "doc", "html")
    python_dir = os.path.join(build, "python")
    if not os.path.isdir(os.path.join(python_dir, "lbmd")):
        sys.exit(f"build_guide: no built lbmd in {python_dir}: build the project first")
    extra = output + "_extra"
    render_notebooks(extra)
    env = dict(os.environ, PYOIF_PYTHON_DIR=python_dir, PYOIF_GUIDE_EXTRA=extra,
               PYTHONPATH=python_dir + os.pathsep + os.environ.get("PYTHONPATH", ""))
    doctrees = output + "_doctrees"
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", "-d", doctrees,
               os.path.join(SOURCE, "doc"), output]
    return subprocess.call(command, env=env)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
