"""The samples users start from run as documented and give sane physics in
short runs: cells carried downstream by the flow, volumes held by the
membrane moduli, output files ParaView and plotting scripts read. (Before
this test nothing ran the samples, and a rule change once broke the
flagship's --rare and --full modes unnoticed.)"""
import json
import os
import sys
import tempfile
import unittest

import numpy as np

from testsuite_data import BUILD, SOURCE, run_sample, read_csv


def table_rows(stdout):
    """The rows of a sample's per-cycle table: lines starting with the cycle
    number, brackets dropped, as floats."""
    rows = []
    for line in stdout.splitlines():
        fields = line.replace("[", " ").replace("]", " ").split()
        if fields and fields[0].isdigit():
            try:
                rows.append([float(x) for x in fields])
            except ValueError:  # a sentence that starts with a number ("8 cells entered")
                continue
    return np.array(rows)


def vtk_point_count(path):
    with open(path) as f:
        for line in f:
            if line.startswith("POINTS"):
                return int(line.split()[1])
    raise AssertionError(f"{path}: no POINTS line")


@unittest.skipUnless(os.path.isfile(os.path.join(BUILD, "pyoif")),
                     "no launcher: run through ctest (PYOIF_BUILD_DIR)")
class Samples(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def test_single_cell(self):
        out = run_sample("oif_single_cell.py", "--cycles", "3", "--steps", "100", "--output", "out",
                         cwd=self.tmp.name)
        rows = table_rows(out)  # cycle, time, centre x y z, velocity_x, volume, surface
        self.assertEqual(rows[:, 0].tolist(), [0, 1, 2, 3])
        np.testing.assert_allclose(rows[:, 1], [0.0, 10.0, 20.0, 30.0])  # time step 0.1
        # the body force drives the fluid along x: the cell follows it
        self.assertGreater(rows[-1, 5], 0.0)
        self.assertGreater(rows[-1, 2], rows[0, 2])
        # kv and kag hold volume and surface (within 1 %, as the issue asks)
        np.testing.assert_allclose(rows[:, 6], rows[0, 6], rtol=1e-2)
        np.testing.assert_allclose(rows[:, 7], rows[0, 7], rtol=1e-2)
        for i in range(4):
            self.assertEqual(vtk_point_count(os.path.join(self.tmp.name, "out", f"cell_{i}.vtk")), 374)
        for name in ("wall_bottom.vtk", "wall_top.vtk"):
            self.assertTrue(os.path.isfile(os.path.join(self.tmp.name, "out", name)), name)

    def test_two_cells(self):
        out = run_sample("oif_two_cells.py", "--cycles", "2", "--steps", "100", "--output", "out",
                         cwd=self.tmp.name)
        rows = table_rows(out)  # cycle, time, centre0 xyz, centre1 xyz, min distance, volume0, volume1
        self.assertEqual(len(rows), 3)
        self.assertTrue(np.all(rows[:, 8] > 0.0), "the membranes touched")
        volumes = rows[:, 9:11]
        np.testing.assert_allclose(volumes, np.broadcast_to(volumes[0], volumes.shape), rtol=1e-2)
        self.assertTrue(np.all(rows[-1, [2, 5]] > rows[0, [2, 5]]), "the cells did not move downstream")
        self.assertEqual(vtk_point_count(os.path.join(self.tmp.name, "out", "cell1_2.vtk")), 374)

    def test_device_from_mask(self):
        """The CAD-layout device (samples/data/constriction.dxf): cells enter
        at the inlet and leave at the outlet (a fast flow: 1.3 mm/s run 27x faster, 35 mm/s, so that
        they cross the 90 um in the 2.5 ms), volumes held within 2 %, mass in
        = mass out within 1 %, the tables and the trajectory plot written."""
        out = run_sample("device_from_mask.py", "--speed", "1.3", "--duration", "2.5", "--output-every", "40", "--haematocrit", "0.06",
                         "--output", "device", cwd=self.tmp.name)
        folder = os.path.join(self.tmp.name, "device")
        events = read_csv(os.path.join(folder, "events.csv"))
        self.assertGreater(sum(e["event"] == "in" for e in events), 3)
        self.assertGreater(sum(e["event"] == "out" for e in events), 0, out)
        for e in events:  # cells leave 5 um before the outlet face, enter in the first 18 um
            x = float(e["x_um"])
            self.assertTrue(x < 18.0 if e["event"] == "in" else x > 60.0, e)
        rows = read_csv(os.path.join(folder, "cells.csv"))
        volumes = np.array([float(r["volume_um3"]) for r in rows])
        np.testing.assert_allclose(volumes, np.median(volumes), rtol=0.02)
        balance = float(out.split("over the mass flux in: ")[1].split()[0])
        self.assertAlmostEqual(balance, 1.0, delta=0.01)
        self.assertGreater(os.path.getsize(os.path.join(folder, "device_trajectories.png")), 10000)

    def test_device_bifurcation_two_outlets(self):
        """samples/data/bifurcation.svg: one inlet (x-), two branches of
        widths 15 and 12 um (height 12) ending on one face, so two outlets
        (test_oif_flow_through has cells leaving by both in a small device;
        here 0.4 ms, before any reaches them): mass in = mass out within 1 %,
        and the flow split as the branches' hydraulic resistances give it
        (rectangular ducts of one length at one pressure drop; the manifold
        and the junctions left out: within 3 points of the share; measured
        58.5 % at 0.4 ms, 59.2 % at 3 ms against 59.7 %)."""
        layout = os.path.join(SOURCE, "samples", "data", "bifurcation.svg")
        out = run_sample("device_from_mask.py", "--layout", layout, "--speed", "1.3", "--duration", "0.4",
                         "--output-every", "50", "--haematocrit", "0.1", "--output", "bif", "--no-plots",
                         "--no-vtk", cwd=self.tmp.name)
        balance = float(out.split("over the mass flux in: ")[1].split()[0])
        self.assertAlmostEqual(balance, 1.0, delta=0.01)
        shares = {}
        for line in out.splitlines():
            if line.strip().startswith("outlet "):
                shares[line.split("outlet ")[1].split(":")[0]] = float(line.split(":")[1].split("%")[0])
        self.assertEqual(sorted(shares), ["x+ 1..13 um", "x+ 46..61 um"], out)

        # Q of a w x h duct at one pressure gradient: w h^3 (1 - 192 h / (pi^5 w)
        # sum_odd tanh(n pi w / 2 h) / n^5), h <= w (White, Viscous Fluid Flow)
        def duct(w, h):
            w, h = max(w, h), min(w, h)
            n = np.arange(1, 200, 2)
            return w * h ** 3 * (1 - 192 * h / (np.pi ** 5 * w) * np.sum(np.tanh(n * np.pi * w / (2 * h)) / n ** 5))
        upper = 100 * duct(15, 12) / (duct(15, 12) + duct(12, 12))  # 59.7 %
        self.assertAlmostEqual(shares["x+ 46..61 um"], upper, delta=3.0, msg=out)
        self.assertGreater(len(read_csv(os.path.join(self.tmp.name, "bif", "events.csv"))), 3)

    def test_bifurcation_flat_start(self):
        """--orientation flat: 70 RBCs, more than random orientations fit
        into the 14 um channel (64), seeded as discs parallel to the walls
        over the whole channel; the haematocrit bookkeeping counts every
        cell once (parent and branches, within 0.2 %)."""
        run_sample("cell_flow_in_bifurcation.py", "--cells", "70", "--orientation", "flat", "--cycles", "1",
                   "--steps", "10", "--output", "flat", "--no-plots", cwd=self.tmp.name)
        folder = os.path.join(self.tmp.name, "flat")
        scene = json.load(open(os.path.join(folder, "scene.json")))
        self.assertEqual(scene["rbcs"], 70)
        cells = [r for r in read_csv(os.path.join(folder, "cells.csv")) if float(r["time_ms"]) == 0.0]
        self.assertEqual(len(cells), 70)
        h = read_csv(os.path.join(folder, "haematocrit.csv"))[0]
        counted = sum(float(h[k]) * scene["fluid_volume_um3"][k] for k in ("parent", "lower", "upper"))
        self.assertAlmostEqual(counted / sum(float(r["volume_um3"]) for r in cells), 1.0, delta=2e-3)
        self.assertGreater(float(h["lower"]) + float(h["upper"]), 0.0)  # seeded in the branches too

    def test_bifurcation(self):
        out = run_sample("cell_flow_in_bifurcation.py", "--cells", "4", "--cycles", "2", "--steps", "100",
                         "--output", "out", cwd=self.tmp.name)
        folder = os.path.join(self.tmp.name, "out")
        # the flow is driven to the paper's centre-line speed times 27 (--small)
        # by fluid-only runs before the cells come: within 0.2 % (the sample's
        # own criterion) of 27 x 1.3 mm/s
        head = next(line for line in out.splitlines() if line.startswith("small scene"))
        reached = float(head.split("reached ")[1].split()[0])
        self.assertAlmostEqual(reached, 27 * 1.3, delta=2e-3 * 27 * 1.3)
        cells = read_csv(os.path.join(folder, "cells.csv"))
        self.assertEqual(len(cells), 3 * 4)  # outputs 0..2, four cells
        by_cell = {}
        for row in cells:
            by_cell.setdefault(row["cell"], []).append(row)
        for cell, rows in by_cell.items():
            volumes = [float(r["volume_um3"]) for r in rows]
            np.testing.assert_allclose(volumes, volumes[0], rtol=1e-2, err_msg=f"cell {cell}")
            # the cells move with the flow: mean node velocity along +x, below the centre-line speed
            vx = float(rows[-1]["vx_mm_s"])
            self.assertTrue(0.0 < vx < 1.05 * reached, f"cell {cell}: vx {vx} mm/s")
        # the pressure-driven flow carries the cells towards the bifurcation (+x)
        x0 = np.mean([float(rows[0]["x_um"]) for rows in by_cell.values()])
        x2 = np.mean([float(rows[-1]["x_um"]) for rows in by_cell.values()])
        self.assertGreater(x2, x0)
        # haematocrit: the cells' volume over the parent channel's fluid volume
        # (all cells start there); the branches are empty at first
        h = read_csv(os.path.join(folder, "haematocrit.csv"))
        self.assertEqual(len(h), 3)
        scene = json.load(open(os.path.join(folder, "scene.json")))
        volume = sum(float(r["volume_um3"]) for r in cells[:4])
        parent_fluid = (scene["height_um"] * (scene["parent_um"][1] - scene["parent_um"][0])
                        * (scene["channel_length_um"] - scene["join_um"] + scene["split_um"]))
        self.assertAlmostEqual(float(h[0]["parent"]), volume / parent_fluid, delta=0.1 * volume / parent_fluid)
        self.assertEqual((float(h[0]["lower"]), float(h[0]["upper"])), (0.0, 0.0))
        # the fluid splits between the branches (measured before the cells
        # came) as two rectangular ducts of equal length at equal pressure
        # drop do: Q ~ w h^3 (1 - 192 h / (pi^5 w) sum_odd tanh(n pi w / 2h) / n^5)
        # (h <= w; e.g. F. M. White, Viscous Fluid Flow), 0.201 for 10 x 14
        # against 20 x 14 um; within 10 % (the rounded ends, the junctions)
        def duct(a, b):
            h, w = min(a, b), max(a, b)
            series = sum(np.tanh(n * np.pi * w / (2 * h)) / n**5 for n in range(1, 40, 2))
            return w * h**3 * (1 - 192 * h / (np.pi**5 * w) * series)
        q_low, q_up = (duct(w, scene["height_um"]) for w in scene["branch_widths_um"])
        self.assertAlmostEqual(scene["lower_flow_share"] / (q_low / (q_low + q_up)), 1.0, delta=0.1)
        self.assertIn("branch entries", out)
        self.assertIn("total (200 steps)", out)  # the timing report
        for number in (2, 3, 4, 5):  # the paper's figures, from plot_bifurcation.py
            self.assertGreater(os.path.getsize(os.path.join(folder, f"bifurcation_fig{number}.png")), 10000)
        self.assertGreater(os.path.getsize(os.path.join(folder, "bifurcation_damage.png")), 10000)
        # the per-cell observables: a relaxed RBC's deformation index is the
        # spread of its nodes through its thickness against across its width
        # (0.357 on rbc374), its
        # strains start at 0 and stay small in 200 steps of this flow, the
        # damage time is 0 below 5 % and never longer than the run
        first = [r for r in cells if float(r["time_ms"]) == 0.0]
        for r in first:
            self.assertAlmostEqual(float(r["deformation_index"]), 0.357, delta=0.002)
            self.assertLess(float(r["max_edge_strain"]), 1e-9)
            self.assertLess(float(r["max_area_strain"]), 1e-9)
        for r in cells:
            self.assertLess(float(r["max_area_strain"]), 0.2, r)
            self.assertLessEqual(float(r["damage_time_ms"]), float(r["time_ms"]) + 1e-12)
            self.assertGreaterEqual(float(r["peak_area_strain"]), float(r["max_area_strain"]) - 1e-12)
        # with the stiff rare cell (642 nodes, its own particle type) and VTK
        run_sample("cell_flow_in_bifurcation.py", "--cells", "2", "--rare", "--cycles", "1", "--steps", "20",
                   "--output", "rare", "--vtk", "--no-plots", cwd=self.tmp.name)
        # --vtk: the membranes and the fluid's mid-plane every output, and the
        # walls as the fluid sees them (VTK XML, read back: a surface at the
        # heights of the channel walls)
        import vtk
        rare = os.path.join(self.tmp.name, "rare")
        reader = vtk.vtkXMLPolyDataReader()
        reader.SetFileName(os.path.join(rare, "walls.vtp"))
        reader.Update()
        walls = reader.GetOutput()
        self.assertGreater(walls.GetNumberOfPolys(), 1000)
        z_low, z_high = walls.GetBounds()[4:6]
        self.assertEqual(z_low, 1.0)  # halfway between the solid node at 0.5 and the fluid node at 1.5
        reader.SetFileName(os.path.join(rare, "cells_000001.vtp"))
        reader.Update()
        self.assertEqual(reader.GetOutput().GetNumberOfPoints(), 2 * 374 + 642)  # two RBCs and the rare cell
        image = vtk.vtkXMLImageDataReader()
        image.SetFileName(os.path.join(rare, "fluid_000001.vti"))
        image.Update()
        self.assertEqual(image.GetOutput().GetDimensions(), (160, 40, 1))  # the mid-height plane
        for name in ("cells.pvd", "fluid.pvd"):
            self.assertIn("cells_000001.vtp" if name == "cells.pvd" else "fluid_000001.vti",
                          open(os.path.join(rare, name)).read())
        table = read_csv(os.path.join(rare, "cells.csv"))
        self.assertEqual(len(table), 2 * 3)
        self.assertEqual(len({row["type"] for row in table}), 2)
        self.assertFalse(any(name.endswith(".png") for name in os.listdir(rare)))  # --no-plots



if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]] + sys.argv[1:])
