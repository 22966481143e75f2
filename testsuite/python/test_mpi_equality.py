"""The same result on any rank count: each scene of mpi_scenes.py runs under
`mpirun -np K` for K = 1, 2, 3, 4, and the state after the run (fluid
velocities, densities and populations of every node, particle positions,
velocities and forces, cell volumes, energies, ...) must equal the 1-rank
state bit for bit. Only sums over ranks may differ in round-off (the fluid's
total mass and momentum, the boundary forces: keys with "sum_"; with the
particles spread over the ranks, the energies and the walls' total forces):
rtol 1e-12.
The 1-rank state must also be physically sane, so that equal garbage cannot
pass.

One scene alone: pyoif test_mpi_equality.py MpiEquality.test_cells
(the scene script by hand: mpirun -np 3 pyoif mpi_scenes.py cells 100 out.npz).

This process starts mpirun, so it must not initialise MPI itself: it
imports neither mpi4py nor lbmd (a singleton MPI process hands its job
identity to its children's mpirun).
"""
import csv
import io
import re
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("PYOIF_SOURCE_DIR", os.path.join(HERE, "..", ".."))
BUILD = os.environ.get("PYOIF_BUILD_DIR", os.path.join(SOURCE, "build"))
LAUNCHER = os.path.join(BUILD, "pyoif")
MPIRUN = shutil.which("mpirun") or shutil.which("mpiexec")
SCENE_SCRIPT = os.path.join(HERE, "mpi_scenes.py")

RANKS = (2, 3, 4)
STEPS = {"fluid": 40, "fluid_thermal": 40, "boundaries": 60, "boundaries_single": 60, "cells": 100, "cells_viscous": 100, "cells_thermal": 100, "crossing": 300, "open_channel": 100, "packed": 40,
         "bifurcation": 200}
KT_THERMAL = 1e-3          # mpi_scenes.scene_fluid(thermal=True)
KT_CELLS = 1e-4            # mpi_scenes.scene_cells_thermal
RUN_TIMEOUT = 180          # s per mpirun; each takes under 5 s today (4 ranks on 2 cores)
# sums over ranks (round-off depends on the decomposition), as documented
SUM_RTOL = 1e-12
# facts about the run, not its state: not compared with the 1-rank run
NOT_STATE = ("ranks", "shared_halo_peers")


def is_sum(key):
    # the fluid's totals and boundary forces, and with the particles spread
    # over the ranks the energies and the walls' forces: sums of every
    # rank's share, whose round-off depends on the decomposition
    return "sum_" in key or "energy" in key or "constraint_force" in key


def compare_states(ref, res, label):
    """Raise AssertionError naming label, every quantity that differs and its
    largest difference, unless res equals ref: exactly, or for sums over
    ranks within SUM_RTOL."""
    missing, extra = sorted(set(ref) - set(res)), sorted(set(res) - set(ref))
    if missing or extra:
        raise AssertionError(f"{label}: quantities differ: missing {missing}, extra {extra}")
    failures = [msg for msg in (compare_one(key, res[key], ref[key]) for key in sorted(ref) if key not in NOT_STATE)
                if msg]
    if failures:
        raise AssertionError(f"{label}: {len(failures)} quantities differ:\n  " + "\n  ".join(failures))


def compare_one(key, res, ref):
    """None if equal, else a line: what differs and by how much."""
    a, b = np.asarray(res), np.asarray(ref)
    if a.shape != b.shape or a.dtype != b.dtype:
        return f"{key}: shape/dtype {a.shape} {a.dtype}, 1 rank: {b.shape} {b.dtype}"
    if a.dtype.kind in "US":
        if a.tolist() == b.tolist():
            return None
        la, lb = str(a).splitlines(), str(b).splitlines()
        first = next((i for i, (x, y) in enumerate(zip(la, lb)) if x != y), min(len(la), len(lb)))
        return f"{key}: text differs from line {first}: {la[first:first + 1]} vs 1 rank {lb[first:first + 1]}"
    if a.size == 0:
        return None
    diff = np.abs(a.astype(float) - b.astype(float))
    where = tuple(int(i) for i in np.unravel_index(np.nanargmax(diff), diff.shape)) if np.any(diff > 0) else None
    if is_sum(key):
        atol = SUM_RTOL * float(np.max(np.abs(b)))   # components near 0 of a vector sum
        bad = ~(diff <= atol + SUM_RTOL * np.abs(b))
        if not np.any(bad):
            return None
        return (f"{key} (a sum over ranks, rtol {SUM_RTOL}): {np.sum(bad)} of {a.size} values differ, largest "
                f"difference {np.max(diff):.3e} at {where} ({a[where]!r} vs 1 rank {b[where]!r})")
    try:
        np.testing.assert_array_equal(a, b)
    except AssertionError:
        n = int(np.sum(~((a == b) | (np.isnan(a) & np.isnan(b)))))
        if where is None:
            return f"{key}: {n} of {a.size} values differ (NaN where the other has a number)"
        return (f"{key}: {n} of {a.size} values differ, largest difference {np.nanmax(diff):.3e} at {where} "
                f"({a[where]!r} vs 1 rank {b[where]!r})")
    return None


def load(path):
    with np.load(path) as f:
        return {k: f[k] for k in f.files}


@unittest.skipUnless(os.path.isfile(LAUNCHER), "no launcher: run through ctest (PYOIF_BUILD_DIR)")
@unittest.skipUnless(MPIRUN, "no mpirun/mpiexec")
class MpiEquality(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="mpi_equality_")
        cls.results = {}

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_scene(self, scene, ranks, node_grid=None, messages=False):
        """The state of `scene` on `ranks` ranks (cached), or skip when the
        engine has no node_grid for a requested grid. messages: the lattice
        halo through MPI messages only (PYOIF_HALO_SHARED=0), as between
        ranks on different machines."""
        key = (scene, ranks, node_grid, messages)
        if key in self.results:
            return self.results[key]
        grid_tag = ("" if node_grid is None else "_" + "x".join(map(str, node_grid))) + ("_messages" if messages else "")
        out = os.path.join(self.tmp.name, f"{scene}{grid_tag}_np{ranks}.npz")
        cmd = [MPIRUN, "--oversubscribe", "-np", str(ranks), LAUNCHER, SCENE_SCRIPT, scene, str(STEPS[scene]), out]
        if node_grid is not None:
            cmd += ["--node-grid", ",".join(map(str, node_grid))]
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
                   PYOIF_SOURCE_DIR=SOURCE, PYOIF_HALO_SHARED="0" if messages else "1")
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, cwd=self.tmp.name, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=env)
        try:
            stdout, stderr = proc.communicate(timeout=RUN_TIMEOUT)
        except subprocess.TimeoutExpired:
            # SIGTERM first: mpirun then ends its ranks (SIGKILL would orphan them)
            proc.terminate()
            try:
                stdout, stderr = proc.communicate(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                stdout, stderr = proc.communicate()
            raise AssertionError(f"{scene} on {ranks} ranks{grid_tag}: not done after {RUN_TIMEOUT} s (a rank "
                                 f"waiting in a collective call the others skipped?):\n{stdout[-2000:]}\n"
                                 f"{stderr[-2000:]}") from None
        seconds = time.perf_counter() - start
        if proc.returncode != 0 or not os.path.isfile(out):
            raise AssertionError(f"{scene} on {ranks} ranks{grid_tag}: {' '.join(cmd)} exited with "
                                 f"{proc.returncode}:\n{stdout[-3000:]}\n{stderr[-3000:]}")
        if os.environ.get("PYOIF_MPI_EQUALITY_VERBOSE"):
            print(f"  {scene}{grid_tag} np {ranks}: {seconds:.1f} s", file=sys.stderr)
        result = load(out)
        os.remove(out)
        self.assertEqual(int(result["ranks"]), ranks)
        # the ranks share this machine: the halo goes through shared memory
        # between every pair of neighbours, unless told to use messages
        if ranks == 1 or messages:
            self.assertEqual(int(result["shared_halo_peers"]), 0, f"{scene} on {ranks} ranks{grid_tag}")
        else:
            self.assertGreater(int(result["shared_halo_peers"]), 0,
                               f"{scene} on {ranks} ranks{grid_tag}: the lattice halo did not go through shared "
                               f"memory (could the ranks not open each other's /proc/<pid>/fd?)")
        if ranks == 1:  # the reference, also for test_node_grids
            self.results[key] = result
        return result

    def check_scene(self, scene, sane, ranks=RANKS, node_grid=None, messages=False):
        ref = self.run_scene(scene, 1)
        self.check_finite(scene, ref)
        sane(ref)
        for k in ranks:
            with self.subTest(ranks=k, node_grid=node_grid, messages=messages):
                res = self.run_scene(scene, k, node_grid, messages)
                compare_states(ref, res, f"scene {scene!r}, {k} ranks{'' if node_grid is None else f' {node_grid}'}"
                                         f"{' (halo by messages)' if messages else ''} vs 1 rank")

    # --- the 1-rank state is physics, not garbage -------------------------------
    def check_finite(self, scene, r):
        for key, v in r.items():
            if v.dtype.kind == "f":
                self.assertTrue(np.all(np.isfinite(v)), f"{scene}: {key} not finite")
        self.assertAlmostEqual(float(r["time"]), 0.1 * STEPS[scene], places=9)
        fluid = r["fluid_boundary"] == 0
        self.assertTrue(np.all(r["fluid_density"][fluid] > 0.5), f"{scene}: density")
        self.assertLess(np.abs(r["fluid_velocity"]).max(), 1.0, f"{scene}: velocity beyond Mach 0.1")
        # single-node reads and the slice read agree
        nodes = tuple(r["probe_nodes"].T)
        np.testing.assert_array_equal(r["probe_velocity"], r["fluid_velocity"][nodes])
        np.testing.assert_array_equal(r["probe_population"], r["fluid_population"][nodes])
        np.testing.assert_array_equal(r["probe_density"], r["fluid_density"][nodes])

    def check_force_balance(self, r):
        """No boundaries: the body force alone changes the fluid momentum, by
        f V t (mass conserved)."""
        volume = np.prod(r["box_l"])
        dp = r["sum_fluid_momentum"] - r["initial_sum_fluid_momentum"]
        np.testing.assert_allclose(dp, r["force"] * volume * (r["time"] - r["initial_time"]), rtol=1e-9)
        np.testing.assert_allclose(r["sum_fluid_mass"], r["initial_sum_fluid_mass"], rtol=1e-12)
        self.assertGreater(r["fluid_velocity"][..., 0].mean(), r["initial_fluid_velocity"][..., 0].mean())

    def check_cells(self, r, volume_rtol, surface_rtol, min_shift):
        np.testing.assert_allclose(r["cell_volume"], r["initial_cell_volume"], rtol=volume_rtol)
        np.testing.assert_allclose(r["cell_surface"], r["initial_cell_surface"], rtol=surface_rtol)
        shift = r["cell_origin"][:, 0] - r["initial_cell_origin"][:, 0]
        self.assertTrue(np.all(shift > min_shift), f"cells moved by {shift} along the force, not {min_shift}")
        self.assertLess(r["constraint_force"][0, 2], 0.0, "the cell near the bottom wall did not touch it")
        self.assertGreater(float(r["energy_non_bonded"]), 0.0, "no contact acted")
        self.assertEqual(len(r["part_id"]), 3 * 374 + 162)

    # --- scenes --------------------------------------------------------------------
    def test_fluid(self):
        def sane(r):
            self.check_force_balance(r)
            self.assertEqual(r["fluid_population"].shape, (25, 12, 10, 19))
        self.check_scene("fluid", sane)

    def test_fluid_thermal(self):
        def sane(r):
            self.check_force_balance(r)
            var = r["fluid_velocity"].var(axis=(0, 1, 2))
            np.testing.assert_allclose(var, KT_THERMAL, rtol=0.3, err_msg="velocity fluctuations are not kT/rho")
        self.check_scene("fluid_thermal", sane)

    def test_boundaries(self):
        def sane(r):
            flags = r["fluid_boundary"]
            self.assertEqual(sorted(np.unique(flags).tolist()), [0, 1, 2, 3, 4, 5])
            fluid = flags == 0
            self.assertGreater(r["fluid_velocity"][..., 1][fluid].mean(), 0.0, "no flow along the force (y)")
            vx = r["fluid_velocity"][..., 0]
            self.assertGreater(vx[:, :, 8][fluid[:, :, 8]].mean(), vx[:, :, 1][fluid[:, :, 1]].mean() + 1e-3,
                               "the moving top wall does not drag the fluid")
            self.assertLess(r["sum_boundary_force"][1, 0], 0.0, "the fluid does not resist the moving wall")
        self.check_scene("boundaries", sane)

    def test_boundaries_single(self):
        """Populations stored as float (halo as MPI_FLOAT): the same walls,
        moving wall and body force, bit for bit on 2 and 4 ranks."""
        def sane(r):
            fluid = r["fluid_boundary"] == 0
            self.assertGreater(r["fluid_velocity"][..., 1][fluid].mean(), 0.0, "no flow along the force (y)")
            pop = r["fluid_population"][fluid]  # (boundary nodes report a double equilibrium)
            # stored: the deviations from w_q dens (the scene's dens = 1), as floats
            weights = np.array([1.0 / 3.0] + [1.0 / 18.0] * 6 + [1.0 / 36.0] * 12)
            dev = pop - weights
            self.assertGreater(np.mean(dev.astype(np.float32).astype(float) == dev), 0.99,
                               "population deviations not floats")
        self.check_scene("boundaries_single", sane, ranks=(2, 4))
        # and float, not double: the double scene differs by float round-off
        ref = self.run_scene("boundaries", 1)
        single = self.run_scene("boundaries_single", 1)
        fluid = ref["fluid_boundary"] == 0
        diff = np.abs(single["fluid_velocity"][fluid] - ref["fluid_velocity"][fluid]).max()
        scale = np.abs(ref["fluid_velocity"][fluid]).max()
        self.assertGreater(diff, 1e-9 * scale)
        self.assertLess(diff, 1e-4 * scale)

    def test_open_channel(self):
        def sane(r):
            fluid = r["fluid_boundary"] == 0
            self.assertGreater(r["fluid_velocity"][..., 0][fluid].mean(), 0.0, "no flow from the inlet")
            rho = r["fluid_density"][:, 6, 5]
            self.assertGreater(rho[1], rho[-2], "no pressure drop from inlet to outlet")
        self.check_scene("open_channel", sane)

    def test_cells(self):
        self.check_scene("cells", lambda r: self.check_cells(r, volume_rtol=0.01, surface_rtol=0.01, min_shift=0.0))

    def test_cells_viscous(self):
        """The implicit membrane viscosity (a per-cell solve on every rank
        that evaluates the cell) gives the serial result bit for bit."""
        self.check_scene("cells_viscous", lambda r: self.check_cells(r, volume_rtol=0.01, surface_rtol=0.01,
                                                                     min_shift=0.0))

    def test_packed(self):
        """oif.pack_cells at 0.45 (its deformable stage a run of its own on
        a scratch System) places every node where the serial packing does,
        bit for bit, and the packed cells then flow alike."""
        def sane(r):
            self.assertEqual(len(r["part_id"]), 17 * 374)
            # the packed cells at their reference volume and surface (0.45 %)
            np.testing.assert_allclose(r["initial_cell_volume"], r["initial_cell_volume"].mean(), rtol=0.01)
            np.testing.assert_allclose(r["initial_cell_surface"], r["initial_cell_surface"].mean(), rtol=0.01)
            # the run's contacts (the advised strength, 20x the packing's
            # last stage) squeeze the packed cells: volumes fall by up to
            # 1.2 % within the 40 steps
            np.testing.assert_allclose(r["cell_volume"], r["initial_cell_volume"], rtol=0.02)
            np.testing.assert_allclose(r["cell_surface"], r["initial_cell_surface"], rtol=0.02)
            self.assertGreater(float(r["energy_non_bonded"]), 0.0, "no contact acted")
        self.check_scene("packed", sane)

    def test_cells_thermal(self):
        def sane(r):
            self.check_cells(r, volume_rtol=0.01, surface_rtol=0.01, min_shift=-1.0)
            # the coupling's noise heats the nodes to kT, the fluid's the fluid
            per_node = float(r["energy_kinetic"]) / len(r["part_id"])
            np.testing.assert_allclose(per_node, 1.5 * KT_CELLS, rtol=0.3, err_msg="node kinetic energy")
            fluid = r["fluid_boundary"] == 0
            np.testing.assert_allclose(r["fluid_velocity"][fluid].var(axis=0), KT_CELLS, rtol=0.3,
                                       err_msg="fluid velocity fluctuations")
        self.check_scene("cells_thermal", sane)

    def test_crossing(self):
        # the cell near the wall is sheared hardest (surface +7 %) and slowest
        self.check_scene("crossing", lambda r: self.check_cells(r, volume_rtol=0.03, surface_rtol=0.1,
                                                                min_shift=np.array([3.0, 3.0, 3.0, 1.5])))

    def test_bifurcation(self):
        def sane(r):
            rows = list(csv.DictReader(io.StringIO(str(r["text_cells_csv"]))))
            self.assertEqual(len(rows), 3 * 6)
            first, last = rows[:6], rows[-6:]
            np.testing.assert_allclose([float(x["volume_um3"]) for x in last],
                                       [float(x["volume_um3"]) for x in first], rtol=1e-2)
            self.assertTrue(all(float(b["x_um"]) > float(a["x_um"]) for a, b in zip(first, last)),
                            "cells not carried")
            np.testing.assert_allclose(r["cell_volume"], [float(x["volume_um3"]) for x in last], atol=1e-3)
            self.assertIn("small scene, case A: 6 RBCs", str(r["text_sample_stdout"]))
        self.check_scene("bifurcation", sane)

    # --- subdomain grids the automatic choice never makes (it splits the
    # longest axis for up to 4 ranks): edges where 4 subdomains meet ---------
    def test_node_grids(self):
        for scene, k, grid in (("fluid", 4, (2, 2, 1)), ("fluid", 2, (1, 1, 2)), ("fluid_thermal", 4, (1, 2, 2)),
                               ("boundaries", 4, (2, 2, 1)), ("cells", 4, (2, 2, 1)), ("cells_thermal", 4, (1, 2, 2)),
                               ("crossing", 4, (2, 1, 2))):
            self.check_scene(scene, lambda r: None, ranks=(k,), node_grid=grid)

    # --- the halo by MPI messages, as between machines (on one machine the
    # neighbours read each other's halo from shared memory) -----------------
    def test_halo_by_messages(self):
        for scene, ranks, grid in (("boundaries", (2, 4), None), ("boundaries_single", (2,), None),
                                   ("cells", (3,), None), ("fluid", (4,), (2, 2, 1))):
            self.check_scene(scene, lambda r: None, ranks=ranks, node_grid=grid, messages=True)

    # --- the comparison itself can fail ------------------------------------------
    def test_comparison_detects_one_ulp(self):
        rng = np.random.default_rng(1)
        ref = {"fluid_velocity": rng.normal(size=(4, 3, 2, 3)), "part_pos": rng.normal(size=(5, 3)),
               "sum_fluid_momentum": np.array([1.0, 1e-9, 3.0]), "text_x": np.array("a\nb"),
               "ranks": np.array(1)}
        same = {k: v.copy() for k, v in ref.items()}
        same["ranks"] = np.array(2)
        same["sum_fluid_momentum"] = ref["sum_fluid_momentum"] * (1 + 1e-14)
        compare_states(ref, same, "same")
        for key, index in (("fluid_velocity", (3, 2, 1, 2)), ("part_pos", (0, 0))):
            bad = {k: v.copy() for k, v in ref.items()}
            bad[key][index] = np.nextafter(bad[key][index], np.inf)
            with self.assertRaisesRegex(AssertionError, rf"^bad: 1 quantities differ:\n  {key}: 1 of \d+ values "
                                                        r"differ, largest difference [0-9.e+-]+ at " +
                                                        re.escape(str(index))):
                compare_states(ref, bad, "bad")
        bad = dict(ref, sum_fluid_momentum=ref["sum_fluid_momentum"] * (1 + 1e-10))
        with self.assertRaisesRegex(AssertionError, "sum_fluid_momentum"):
            compare_states(ref, bad, "bad")
        with self.assertRaisesRegex(AssertionError, "text_x: text differs from line 1"):
            compare_states(ref, dict(ref, text_x=np.array("a\nc")), "bad")
        with self.assertRaisesRegex(AssertionError, "missing"):
            compare_states(ref, {k: v for k, v in ref.items() if k != "part_pos"}, "bad")


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]] + sys.argv[1:])
