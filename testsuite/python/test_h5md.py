"""lbmd.io.H5mdWriter: the H5MD 1.1 structure and attributes the
specification requires, the values equal the system's at each written step
(positions folded + images, velocities, forces, types, ids, mol ids, step,
time, box; the cells' centre, volume and surface against the OifCell's
methods), a subset of fields, appending on resume (frames after the
resumed step dropped, a different particle count refused), a changing
particle number (refused, or rows filled with id -1), bad input."""
import os
import tempfile
import unittest

import h5py
import numpy as np

import lbmd
from lbmd.io import H5mdWriter
from h5md_scene import scene


class H5mdWriterTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.tmp.name, "traj.h5")
        self.system, self.cell, self.free = scene()

    def tearDown(self):
        self.tmp.cleanup()

    def snapshot(self):
        part = self.system.part.all()
        c = self.cell
        return dict(step=self.system.step_count, time=self.system.time, pos=part.pos, folded=part.pos_folded,
                    image=part.image_box, v=part.v, f=part.f, type=part.type, id=part.id, mol_id=part.mol_id,
                    centre=c.get_origin(), volume=c.volume(), surface=c.surface())

    def write_frames(self, writer, n=3, steps=15):
        shots = []
        for k in range(n):
            if k:
                self.system.integrator.run(steps)
            writer.write()
            shots.append(self.snapshot())
        return shots

    def test_structure_and_values(self):
        with H5mdWriter(self.path, self.system, cells=[self.cell], author="tester") as w:
            shots = self.write_frames(w)
            self.assertIn("3 frame(s)", repr(w))
        with h5py.File(self.path, "r") as f:
            # h5md group: version [1, 1], author name, creator name and version
            np.testing.assert_array_equal(f["h5md"].attrs["version"], [1, 1])
            self.assertEqual(f["h5md/author"].attrs["name"], "tester")
            self.assertEqual(f["h5md/creator"].attrs["name"], "PyOIF (lbmd)")
            self.assertEqual(f["h5md/creator"].attrs["version"], lbmd.__version__)
            g = f["particles/atoms"]
            box = g["box"]
            self.assertEqual(int(box.attrs["dimension"]), 3)
            self.assertEqual([b.decode() if isinstance(b, bytes) else b for b in box.attrs["boundary"]],
                             ["periodic"] * 3)
            for name in [f"particles/atoms/{k}" for k in ("box/edges", "position", "velocity", "force", "image",
                                                          "species", "id", "mol_id")] + \
                    [f"observables/cells/{k}" for k in ("centre", "volume", "surface")]:
                el = f[name]
                self.assertEqual(set(el.keys()), {"step", "time", "value"}, name)
                self.assertEqual(el["step"].dtype.kind, "i", name)
                self.assertEqual(el["value"].maxshape[0], None, name)  # extensible along the frames
                self.assertIsNotNone(el["value"].chunks, name)
                np.testing.assert_array_equal(el["step"][()], [s["step"] for s in shots], name)
                np.testing.assert_array_equal(el["time"][()], [s["time"] for s in shots], name)
            self.assertNotIn("mass", g)  # not asked for
            n = len(shots[0]["id"])
            self.assertEqual(g["position/value"].shape, (3, n, 3))
            self.assertEqual(g["species/value"].shape, (3, n))
            self.assertEqual(g["image/value"].dtype.kind, "i")
            for k, s in enumerate(shots):
                np.testing.assert_array_equal(g["box/edges/value"][k], self.system.box_l)
                np.testing.assert_array_equal(g["position/value"][k], s["folded"])
                np.testing.assert_array_equal(g["image/value"][k], s["image"])
                np.testing.assert_array_equal(g["velocity/value"][k], s["v"])
                np.testing.assert_array_equal(g["force/value"][k], s["f"])
                np.testing.assert_array_equal(g["species/value"][k], s["type"])
                np.testing.assert_array_equal(g["id/value"][k], s["id"])
                np.testing.assert_array_equal(g["mol_id/value"][k], s["mol_id"])
                # position + image * edges: the unfolded position
                unfolded = g["position/value"][k] + g["image/value"][k] * g["box/edges/value"][k]
                np.testing.assert_allclose(unfolded, s["pos"], rtol=0, atol=1e-12)
                obs = f["observables/cells"]
                np.testing.assert_array_equal(obs["cell_id"][()], [self.cell.cell_id])
                np.testing.assert_array_equal(obs["centre/value"][k], [s["centre"]])
                np.testing.assert_array_equal(obs["volume/value"][k], [s["volume"]])
                np.testing.assert_array_equal(obs["surface/value"][k], [s["surface"]])
            # not trivially equal: things moved, the cell crosses the boundary
            self.assertGreater(np.abs(g["position/value"][2] - g["position/value"][0]).max(), 1e-4)
            self.assertGreater(np.abs(g["image/value"][()]).max(), 0)
            self.assertGreater(np.abs(g["force/value"][2]).max(), 0.0)
            self.assertEqual(sorted(set(g["mol_id/value"][0].tolist())), [-5, self.cell.cell_id])

    def test_subset_of_fields_and_mass(self):
        with H5mdWriter(self.path, self.system, fields=("position", "mass")) as w:
            w.write()
        with h5py.File(self.path, "r") as f:
            g = f["particles/atoms"]
            self.assertEqual(sorted(k for k in g.keys()), ["box", "mass", "position"])
            self.assertNotIn("observables", f)
            np.testing.assert_array_equal(g["mass/value"][0], self.system.part.all().mass)

    def test_append_on_resume(self):
        checkpoint = os.path.join(self.tmp.name, "run.checkpoint")
        w = H5mdWriter(self.path, self.system, cells=[self.cell])
        self.write_frames(w, n=2, steps=10)  # steps 0, 10
        lbmd.checkpoint.save(checkpoint, self.system, cells=[self.cell])
        self.system.integrator.run(5)
        w.write()  # step 15: after the checkpoint
        w.close()
        w.close()  # a second close does nothing
        with self.assertRaisesRegex(ValueError, "closed"):
            w.write()
        with h5py.File(self.path, "r") as f:
            original = f["particles/atoms/position/value"][2], f["observables/cells/volume/value"][2]
        # the run resumed from the checkpoint (step 10): the frame at step 15 goes,
        # and comes back, bit for bit, when the resumed run writes it again
        ns = lbmd.checkpoint.load(checkpoint)
        self.system, self.cell = ns.system, ns.cells[0]
        self.assertEqual(self.system.step_count, 10)
        with H5mdWriter(self.path, self.system, cells=[self.cell], append=True) as w:
            self.assertEqual(w.frames, 2)
            self.system.integrator.run(5)
            w.write()
        with h5py.File(self.path, "r") as f:
            np.testing.assert_array_equal(f["particles/atoms/position/step"][()], [0, 10, 15])
            np.testing.assert_array_equal(f["observables/cells/volume/step"][()], [0, 10, 15])
            self.assertEqual(f["observables/cells/volume/value"].shape, (3, 1))
            np.testing.assert_array_equal(f["particles/atoms/position/value"][2], original[0])
            np.testing.assert_array_equal(f["observables/cells/volume/value"][2], original[1])
        # another particle count: refused, naming both counts
        self.system.part.add(pos=[3.0, 3.0, 3.0])
        with self.assertRaisesRegex(ValueError, r"cannot append .* holds? .*\b%d particles, the system has %d"
                                    % (len(self.system.part) - 1, len(self.system.part))):
            H5mdWriter(self.path, self.system, cells=[self.cell], append=True)
        # other fields: refused
        with self.assertRaisesRegex(ValueError, "fields"):
            H5mdWriter(self.path, self.system, fields=("position",), append=True)
        # append to a file that is not there: a new file
        other = os.path.join(self.tmp.name, "new.h5")
        with H5mdWriter(other, self.system, append=True) as w:
            w.write()
        with h5py.File(other, "r") as f:
            self.assertEqual(f["particles/atoms/id/value"].shape[0], 1)

    def test_particle_number_changes(self):
        with H5mdWriter(self.path, self.system) as w:
            w.write()
            self.system.part.add(pos=[3.0, 3.0, 3.0], type=2)
            with self.assertRaisesRegex(ValueError, "variable_particles=True"):
                w.write()
        n = len(self.system.part)
        with H5mdWriter(self.path, self.system, variable_particles=True) as w:
            w.write()  # n particles
            self.free[0].remove()
            w.write()  # n - 1
            self.system.part.add(pos=[[4.0, 4.0, 4.0], [5.0, 5.0, 5.0]])
            w.write()  # n + 1
            ids = self.system.part.all().id
        with h5py.File(self.path, "r") as f:
            g = f["particles/atoms"]
            self.assertEqual(g["id/value"].shape, (3, n + 1))
            self.assertEqual(int(np.count_nonzero(g["id/value"][0] >= 0)), n)
            np.testing.assert_array_equal(g["id/value"][1][n - 1:], [-1, -1])  # absent rows
            self.assertTrue(np.all(np.isnan(g["position/value"][1][n - 1:])))
            np.testing.assert_array_equal(g["id/value"][2], ids)

    def test_bad_input(self):
        with self.assertRaisesRegex(TypeError, "'system'"):
            H5mdWriter(self.path, None)
        with self.assertRaisesRegex(ValueError, r"'fields' has unknown name\(s\) \['pos'\]"):
            H5mdWriter(self.path, self.system, fields=("pos",))
        with self.assertRaisesRegex(TypeError, "'cells'"):
            H5mdWriter(self.path, self.system, cells=[1, 2])
        with self.assertRaisesRegex(ValueError, "'cell_fields'"):
            H5mdWriter(self.path, self.system, cells=[self.cell], cell_fields=("area",))
        with self.assertRaisesRegex(ValueError, "needs the field 'id'"):
            H5mdWriter(self.path, self.system, fields=("position",), variable_particles=True)
        with self.assertRaisesRegex(ValueError, "'group'"):
            H5mdWriter(self.path, self.system, group="a/b")
        os.makedirs(os.path.join(self.tmp.name, "folder.h5"))
        with self.assertRaisesRegex(ValueError, "is a directory"):
            H5mdWriter(os.path.join(self.tmp.name, "folder.h5"), self.system)
        not_h5md = os.path.join(self.tmp.name, "plain.h5")
        with h5py.File(not_h5md, "w") as f:
            f["x"] = 1
        with self.assertRaisesRegex(ValueError, "not an H5MD 1.1 file"):
            H5mdWriter(not_h5md, self.system, append=True)
        garbage = os.path.join(self.tmp.name, "garbage.h5")
        with open(garbage, "w") as f:
            f.write("not hdf5")
        with self.assertRaisesRegex(OSError, "cannot append to"):
            H5mdWriter(garbage, self.system, append=True)


if __name__ == "__main__":
    unittest.main()
