"""lbmd.visualization: the pictures hold the data they claim (the image is
the fluid plane's speed, one outline per cell that cuts the plane, ids as
text), files are written, bad arguments are refused, the 3D snapshot renders
or says what is missing, and LiveView stops on an interrupt with the state
of a plain run of the steps it did (a SIGINT in the middle of a run:
test_visualization_interrupt.py, one rank only)."""
import os
import tempfile
import warnings
import unittest

import matplotlib
import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes
from lbmd import visualization as vis
from lbmd.settings_check import SettingsWarning
from lbmd.units import UnitSystem
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.quiver import Quiver

matplotlib.use("Agg")
BOX = [20.0, 10.0, 8.0]
CENTRES = [[5.0, 5.0, 4.0], [14.0, 3.5, 4.0], [14.0, 6.5, 4.0]]  # two of them side by side at x = 14


def scene(with_cells=True):
    # a small, coarse test scene (here, not at import: unittest's runner resets the filters)
    warnings.simplefilter("ignore", SettingsWarning)
    system = lbmd.System(box_l=BOX)
    system.time_step = 0.05
    system.cell_system.skin = 0.2
    fluid = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.05, ext_force_density=[0.002, 0.0, 0.0])
    system.actors.add(fluid)
    walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-7.0),
             shapes.Cylinder(center=[10.0, 5.0, 4.0], axis=[0, 0, 1], radius=1.5, length=8.0)]
    for w in walls:
        system.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
    cells = []
    if with_cells:
        kind = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(1.2, 1.2, 1.2), ks=0.05,
                               kb=0.01, kal=0.01, kag=0.5, kv=0.5, normal=True)
        cells = [oif.OifCell(cell_type=kind, origin=c, particle_type=0, particle_mass=1.0) for c in CENTRES]
        system.thermostat.set_lb(LB_fluid=fluid, gamma=1.0)
    return system, fluid, cells


class Pictures(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.system, cls.fluid, cls.cells = scene()
        cls.system.integrator.run(40)

    def image(self, fig):
        images = [a for ax in fig.axes for a in ax.get_images()]
        self.assertEqual(len(images), 1)
        return images[0]

    def test_geometry(self):
        fig = vis.geometry(self.system, "z", 4.0)
        flags, z = vis.boundary_slice(self.system, "z", 4.0)
        self.assertEqual(z, 3.5)  # the node plane at or below 4.0
        data = self.image(fig).get_array()
        np.testing.assert_array_equal(data.mask, flags.T == 0)
        np.testing.assert_array_equal(data.data[~data.mask], flags.T[flags.T != 0])
        self.assertEqual(set(np.unique(flags)), {0, 3})  # only the cylinder (boundary 2) cuts z = 3.5
        self.assertEqual(sorted(vis.shape_outlines(fig)), [2])
        # an x plane cuts the walls too: three shapes' outlines
        fig = vis.geometry(self.system, "x", 10.0)
        self.assertEqual(sorted(vis.shape_outlines(fig)), [0, 1, 2])
        self.assertFalse(vis.shape_outlines(vis.geometry(self.system, "x", 10.0, outlines=False)))
        self.assertIn("3 LBBoundaries", fig.axes[0].get_title())

    def test_fluid_image_is_the_speed(self):
        fig = vis.fluid(self.system, "z", 4.0, arrows="quiver")
        u = self.fluid[:, :, 3].velocity
        flags = self.fluid[:, :, 3].boundary
        data = self.image(fig).get_array()
        speed = np.linalg.norm(u, axis=-1).T
        np.testing.assert_array_equal(data.mask, flags.T != 0)
        np.testing.assert_allclose(data.data[~data.mask], speed[flags.T == 0], rtol=1e-12)
        self.assertGreater(speed.max(), 0.0)
        self.assertEqual(len(fig.axes), 2)  # the plot and its colour bar
        self.assertTrue(any(isinstance(c, Quiver) for c in fig.axes[0].get_children()))
        # SI: the same numbers in mm/s, axes in um
        units = UnitSystem(length=1e-6, time=1e-6, mass=1e-15)
        fig = vis.fluid(self.system, "z", 4.0, units=units, component="x")
        data = self.image(fig).get_array()
        np.testing.assert_allclose(data.data[~data.mask], (u[..., 0].T * 1e3)[flags.T == 0], rtol=1e-12)
        self.assertIn("mm/s", fig.axes[1].get_ylabel())
        self.assertIn("µm", fig.axes[0].get_xlabel())
        self.assertGreater(len([c for c in fig.axes[0].collections if isinstance(c, LineCollection)]), 0)  # streams

    def test_cells_cut_by_the_plane(self):
        for x in (5.0, 14.0, 10.0):
            fig = vis.cells(self.system, self.cells, "x", x)
            coordinate = vis.boundary_slice(self.system, "x", x)[1]
            cut = {c.cell_id for c in self.cells
                   if c.mesh.positions()[:, 0].min() < coordinate < c.mesh.positions()[:, 0].max()}
            outlines = vis.cell_outlines(fig)
            self.assertEqual(set(outlines), cut, f"plane x = {coordinate}")
            texts = {t.get_text() for t in fig.axes[0].texts}
            self.assertEqual(texts, {str(i) for i in cut})
        self.assertEqual(len(cut), 0)  # x = 10: between the cells
        fig = vis.cells(self.system, self.cells, "x", 14.0)
        self.assertEqual(len(vis.cell_outlines(fig)), 2)

    def test_cells_projected_and_coloured(self):
        values = [1.0, 2.0, 3.0]
        fig = vis.cells(self.system, self.cells, "z", mode="projected", color_by=values)
        outlines = vis.cell_outlines(fig)
        self.assertEqual(len(outlines), 3)
        self.assertTrue(all(isinstance(a, PolyCollection) for a in outlines.values()))
        colours = [tuple(outlines[c.cell_id].get_facecolor()[0]) for c in self.cells]
        self.assertEqual(len(set(colours)), 3)
        self.assertEqual(len(fig.axes), 2)  # colour bar
        self.assertEqual(fig.axes[1].get_ylim(), (1.0, 3.0))
        fig = vis.cells(self.system, self.cells, "z", 4.0, color_by="deformation")
        d, label = vis.cell_values(self.cells, "deformation")
        self.assertEqual(label, "D / D0")
        self.assertTrue(np.all((d > 0.8) & (d < 1.2)), d)
        v, _ = vis.cell_values(self.cells, "velocity")
        np.testing.assert_allclose(v, [np.linalg.norm(c.get_velocity()) for c in self.cells])

    def test_save(self):
        with tempfile.TemporaryDirectory() as tmp:
            for name, make in (("g.png", lambda p: vis.geometry(self.system, save=p)),
                               ("f.png", lambda p: vis.fluid(self.system, save=p)),
                               ("c.png", lambda p: vis.cells(self.system, self.cells, save=p))):
                path = os.path.join(tmp, name)
                make(path)
                self.assertEqual(os.path.exists(path), lbmd.rank == 0)  # written by rank 0 only
                if lbmd.rank != 0:
                    continue
                with open(path, "rb") as f:
                    head = f.read(8)
                self.assertEqual(head, b"\x89PNG\r\n\x1a\n")
                self.assertGreater(os.path.getsize(path), 5000)

    def test_snapshot_3d(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "s.png")
            try:
                vis.check_3d()
            except RuntimeError as e:  # no X server and no Xvfb: the message says what to install
                self.assertIn("xvfb", str(e))
                with self.assertRaisesRegex(RuntimeError, "xvfb"):
                    vis.snapshot_3d(self.system, self.cells, path)
                return
            vis.snapshot_3d(self.system, self.cells, path, color_by="velocity", size=(320, 200))
            if lbmd.rank != 0:
                self.assertFalse(os.path.exists(path))
                return
            from PIL import Image
            with Image.open(path) as im:
                self.assertEqual(im.size, (320, 200))
                pixels = np.asarray(im.convert("RGB"), dtype=float)
            self.assertGreater(pixels.std(), 5.0)  # not a blank image
            self.assertTrue(np.any((pixels[..., 0] - pixels[..., 2]) > 60))  # red cells, or a colour scale

    def test_bad_arguments(self):
        s, cells = self.system, self.cells
        for call, error, words in (
                (lambda: vis.geometry(s, "w"), ValueError, "'axis'"),
                (lambda: vis.geometry(s, "z", 9.0), ValueError, r"'position' must be in \[0, 8\]"),
                (lambda: vis.geometry(s, "z", "middle"), TypeError, "'position'"),
                (lambda: vis.geometry("system"), TypeError, "lbmd.System"),
                (lambda: vis.fluid(s, component="speed"), ValueError, "'component'"),
                (lambda: vis.fluid(s, arrows="lines"), ValueError, "'arrows'"),
                (lambda: vis.fluid(s, units="SI"), TypeError, "UnitSystem"),
                (lambda: vis.cells(s, [1, 2]), TypeError, r"item 0 must be a cell \(an oif.OifCell\)"),
                (lambda: vis.cells(s, cells, color_by=[1.0]), ValueError, "one number per cell \\(3\\)"),
                (lambda: vis.cells(s, cells, color_by="size"), ValueError, "'deformation', 'velocity'"),
                (lambda: vis.cells(s, cells, mode="side"), ValueError, "'mode'"),
                (lambda: vis.fluid(s, save="/nonexistent/folder/f.png"), OSError, "does not exist"),
                (lambda: vis.snapshot_3d(s, cells, "s.jpg"), ValueError, "ending in .png"),
                (lambda: vis.snapshot_3d(s, cells, "s.png", size=(0, 10)), ValueError, "'size'"),
                (lambda: vis.LiveView(s, every=0), ValueError, "'every'"),
                (lambda: vis.LiveView(s, plot="fluid"), TypeError, "'plot'"),
                (lambda: vis.LiveView(s).run(-1), ValueError, "'n_steps'")):
            with self.subTest(words=words), self.assertRaisesRegex(error, words):
                call()
        system, _, _ = scene(with_cells=False)
        system.actors.clear()
        with self.assertRaisesRegex(ValueError, "no lattice-Boltzmann fluid"):
            vis.fluid(system)


def state(system, fluid):
    return (np.asarray(system.part.all().pos), np.asarray(system.part.all().v), fluid[:, :, :].velocity,
            system.step_count)


class Live(unittest.TestCase):
    def assert_same_state(self, a, b):
        self.assertEqual(a[3], b[3])
        for x, y in zip(a[:3], b[:3]):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-13)

    def test_runs_and_draws(self):
        system, fluid, cells = scene()
        with tempfile.TemporaryDirectory() as tmp:
            frame = os.path.join(tmp, "frame.png")
            view = vis.LiveView(system, plot=lambda s, ax: vis.cells(s, cells, ax=ax, axis="z"), every=10,
                                save=frame, display="none")
            self.assertEqual(view.run(25), 25)
            self.assertFalse(view.interrupted)
            self.assertEqual(os.path.exists(frame), lbmd.rank == 0)  # written by rank 0 only
            if lbmd.rank == 0:
                self.assertGreater(os.path.getsize(frame), 0)
            self.assertIn("step 25", view.figure._suptitle.get_text())
            self.assertIn("steps/s", view.figure._suptitle.get_text())
        reference, ref_fluid, _ = scene()
        reference.integrator.run(25)
        self.assert_same_state(state(system, fluid), state(reference, ref_fluid))

    def test_interrupt_from_a_callback(self):
        system, fluid, cells = scene()
        calls = []

        def stop_after_two(view):
            calls.append(system.step_count)
            if len(calls) == 2:
                raise KeyboardInterrupt

        view = vis.LiveView(system, every=15, callback=stop_after_two, display="none")
        done = view.run(100)
        self.assertEqual(done, 30)
        self.assertTrue(view.interrupted)
        self.assertEqual(calls, [15, 30])
        self.assertIn("interrupted", view.figure._suptitle.get_text())
        reference, ref_fluid, _ = scene()
        reference.integrator.run(30)
        self.assert_same_state(state(system, fluid), state(reference, ref_fluid))
        # the system goes on from there
        view.callback = None
        self.assertEqual(view.run(5), 5)
        self.assertEqual(system.step_count, 35)


if __name__ == "__main__":
    unittest.main()
