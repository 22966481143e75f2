"""lbmd.io.H5mdWriter under mpirun: the file written by 2 ranks (rank 0
writes what the collective queries gathered) equals the 1-rank file: the
same tree, attributes, steps, times, ids, types, mol ids and images, and
the floating-point values equal to round-off (rtol 1e-12, as
test_mpi_equality: the cell's volume and surface are sums over ranks).

This process starts mpirun: it imports neither mpi4py nor lbmd.
"""
import os
import sys
import tempfile
import unittest

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from test_checkpoint_mpi import MPIRUN, mpirun  # noqa: E402

SCENE = os.path.join(HERE, "h5md_scene.py")


def contents(path):
    """{name: (attributes, data or None)} of every object in the file."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            attrs = {k: np.asarray(v).tolist() for k, v in obj.attrs.items()}
            out[name] = (attrs, obj[()] if isinstance(obj, h5py.Dataset) else None)
        f.visititems(visit)
    return out


@unittest.skipIf(MPIRUN is None, "no mpirun")
class H5mdRanks(unittest.TestCase):
    def test_two_ranks_equal_one(self):
        with tempfile.TemporaryDirectory() as tmp:
            files = {}
            for ranks in (1, 2):
                files[ranks] = os.path.join(tmp, f"t{ranks}.h5")
                mpirun(ranks, SCENE, files[ranks])
            one, two = contents(files[1]), contents(files[2])
            self.assertEqual(sorted(one), sorted(two))
            self.assertIn("particles/atoms/position/value", one)
            self.assertIn("observables/cells/volume/value", one)
            for name, (attrs, data) in one.items():
                self.assertEqual(attrs, two[name][0], name)
                if data is None:
                    continue
                other = two[name][1]
                self.assertEqual(data.shape, other.shape, name)
                if data.dtype.kind == "f":
                    np.testing.assert_allclose(other, data, rtol=1e-12, atol=1e-15, err_msg=name)
                else:
                    np.testing.assert_array_equal(other, data, err_msg=name)
            # the frames are the system's, not empty: three steps, things moved
            np.testing.assert_array_equal(one["particles/atoms/position/step"][1], [0, 15, 30])
            pos = one["particles/atoms/position/value"][1]
            self.assertGreater(np.abs(pos[2] - pos[0]).max(), 1e-4)


if __name__ == "__main__":
    unittest.main()
