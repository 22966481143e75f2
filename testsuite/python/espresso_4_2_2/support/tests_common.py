"""Stand-in for ESPResSo's testsuite/python/tests_common.py, written for this
project: ``data_path`` finds ESPResSo's test meshes in this project's
testsuite/data/meshes (copied unchanged from ESPResSo 4.2.2's
testsuite/python/data, see its README.md). Only what the OIF tests use."""
import os
import pathlib

_DATA = os.environ.get("PYOIF_TEST_DATA",
                       os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "data"))


def data_path(filename):
    """Absolute path of one of ESPResSo's test data files."""
    path = pathlib.Path(_DATA).resolve() / "meshes" / filename
    if not path.is_file():
        raise FileNotFoundError(f"tests_common.data_path: {filename} is not in {path.parent}")
    return path
