"""Where the testsuite's own input files are: testsuite/data/ (ESPResSo's PyOIF
meshes and their provenance in testsuite/data/meshes/README.md). CTest sets
PYOIF_TEST_DATA; a test run by hand finds the folder beside this file."""
import os

TEST_DATA = os.environ.get("PYOIF_TEST_DATA", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data"))
TEST_MESHES = os.path.join(TEST_DATA, "meshes")
