"""A short run of the reader fuzzer (maintainer/fuzz/fuzz_readers.py, fixed
seed): randomly damaged nodes.dat/triangles.dat pairs and meshio files
(.off, .obj, .ply, .stl, .vtk, .msh, .vtu) give either a mesh or a
ValueError/TypeError/OSError naming the file -- no other exception, no
crash, no hang. The checkpoint loader's run is an expected failure until
lbmd.checkpoint turns the errors the fuzzer finds into CheckpointError
(doc/sanitizers.md, "Findings")."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
FUZZER = os.path.join(SOURCE, "maintainer", "fuzz", "fuzz_readers.py")


def fuzz(targets, n, seed):
    """(exit status, counts per target, printed report) of a fuzzer run."""
    with tempfile.TemporaryDirectory() as out:
        r = subprocess.run([sys.executable, FUZZER, "-n", str(n), "--seed", str(seed), "--timeout", "60",
                            "--out", out, "--target"] + targets,
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                           env=dict(os.environ, OMP_NUM_THREADS="1"))
        with open(os.path.join(out, "summary.json")) as f:
            counts = json.load(f)["counts"]
    return r.returncode, counts, r.stdout


class FuzzReaders(unittest.TestCase):
    def test_mesh_readers(self):
        status, counts, report = fuzz(["dat", "meshio"], 200, 2026)
        for target in ("dat", "meshio"):
            c = counts[target]
            self.assertEqual(sum(c.values()), 200, report)
            for bad in ("bad", "crash", "hang"):
                self.assertEqual(c.get(bad, 0), 0, f"{target}: {bad} outcomes\n{report}")
            # the mutations must reach both outcomes, or the run tests nothing
            self.assertGreater(c.get("clean", 0), 100, report)
            self.assertGreater(c.get("accepted", 0), 0, report)
        self.assertEqual(status, 0, report)

    def test_checkpoint_loader(self):
        # damaged files are refused by the checksum before HDF5 reads them
        # (the library itself crashed on some); edited ones (ckpt_h5, resealed
        # or not) by the loader's checks: CheckpointError, never another error
        status, counts, report = fuzz(["ckpt_bytes", "ckpt_h5"], 50, 2026)
        for target in ("ckpt_bytes", "ckpt_h5"):
            self.assertEqual(sum(counts[target].values()), 50, report)
        self.assertEqual(status, 0, report)


if __name__ == "__main__":
    unittest.main()
