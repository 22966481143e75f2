"""The work is really split under `mpirun -np 2` (test_mpi_equality.py shows
that the results do not change; this file, that the ranks do not all do
everything): the lattice is cut into subdomains as chosen or asked for, the
halo carries only the populations that cross, the cuts follow the fluid
nodes, each cell's membrane is evaluated by one rank, and bad requests are
refused on every rank. Each test starts mpirun itself, so this file runs
serially under CTest."""
import os
import shutil
import subprocess
import tempfile
import textwrap
import unittest

BUILD = os.environ.get("PYOIF_BUILD_DIR")
MPIRUN = shutil.which("mpirun") or shutil.which("mpiexec")


@unittest.skipUnless(BUILD and os.path.isfile(os.path.join(BUILD, "pyoif")) and MPIRUN,
                     "needs the launcher (ctest sets PYOIF_BUILD_DIR) and mpirun")
class Decomposition(unittest.TestCase):
    def run_ranks(self, body, ranks=2):
        """Runs body (Python, indented freely) on `ranks` ranks; returns the
        lines every rank gave say(...), each starting with its rank."""
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "script.py")
            with open(path, "w") as f:
                # each rank's lines, collected and printed by rank 0 (the
                # ranks' own prints would interleave)
                f.write("import sys, numpy as np, lbmd\n_out = []\n"
                        "def say(*args):\n    _out.append(' '.join(str(a) for a in (lbmd.rank,) + args))\n"
                        + textwrap.dedent(body)
                        + "\nfor lines in lbmd.comm.gather(_out, root=0) or []:\n    print('\\n'.join(lines))\n")
            env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
                       OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
            proc = subprocess.run([MPIRUN, "--oversubscribe", "-np", str(ranks), os.path.join(BUILD, "pyoif"),
                                   path], capture_output=True, text=True, timeout=120, env=env)
        if proc.returncode != 0:
            raise AssertionError(f"exited with {proc.returncode}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
        return proc.stdout.splitlines()

    def test_lattice_split_and_halo(self):
        lines = self.run_ranks("""
            s = lbmd.System(box_l=[24.0, 12.0, 10.0]); s.time_step = 1.0
            lbf = lbmd.lb.LBFluid(agrid=1.0, tau=1.0, dens=1.0, visc=0.3)
            s.actors.add(lbf)
            c = lbf._core
            say(list(c.node_grid), list(c.local_origin), list(c.local_shape), c.halo_bytes)
            """)
        rows = sorted(line.split(" ", 1) for line in lines if line[:1].isdigit())
        self.assertEqual(len(rows), 2, lines)
        # the long axis is cut; each rank holds half; the halo of a face of
        # 12 x 10 nodes carries the 5 populations that cross it, both faces
        self.assertEqual(rows[0][1], "[2, 1, 1] [0, 0, 0] [12, 12, 10] 9600")
        self.assertEqual(rows[1][1], "[2, 1, 1] [12, 0, 0] [12, 12, 10] 9600")

    def test_node_grid_and_fluid_balance(self):
        lines = self.run_ranks("""
            s = lbmd.System(box_l=[24.0, 12.0, 10.0]); s.time_step = 1.0
            for bad in ([2, 2, 1], [0, 2, 1], [1.5, 2, 1]):
                try:
                    s.cell_system.node_grid = bad
                except ValueError as e:
                    say("refused", "product" in str(e))
            s.cell_system.node_grid = [1, 1, 2]
            lbf = lbmd.lb.LBFluid(agrid=1.0, tau=1.0, dens=1.0, visc=0.3)
            s.actors.add(lbf)
            say("grid", lbf._core.decomposition)
            # solid above z = 7: the cut moves down so both ranks get
            # about as many fluid nodes (7 fluid planes: 3 + 4 or 4 + 3)
            s2 = lbmd.System(box_l=[24.0, 12.0, 10.0]); s2.time_step = 1.0
            s2.cell_system.node_grid = [1, 1, 2]
            lbf2 = lbmd.lb.LBFluid(agrid=1.0, tau=1.0, dens=1.0, visc=0.3)
            s2.actors.add(lbf2)
            s2.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=lbmd.shapes.Wall(normal=[0, 0, -1], dist=-7.0)))
            s2.prepare()  # the explicit collective step: flags, balances the cuts
            say("balanced", lbf2._core.decomposition, lbf2._core.n_fluid_nodes)
            """)
        for rank in "01":
            mine = [line.split(" ", 1)[1] for line in lines if line.startswith(rank + " ")]
            self.assertEqual(mine[:3], ["refused True"] * 3, lines)
            self.assertIn("grid 1x1x2, cuts z: 0 5 10", mine)
            self.assertIn("balanced 1x1x2, cuts z: 0 4 10 2016", mine)

    def test_each_cell_on_one_rank(self):
        lines = self.run_ranks("""
            import oif
            s = lbmd.System(box_l=[30.0, 12.0, 12.0]); s.time_step = 0.1
            lbf = lbmd.lb.LBFluid(agrid=1.0, tau=0.1, dens=1.0, visc=1.5)
            s.actors.add(lbf)
            s.thermostat.set_lb(LB_fluid=lbf, gamma=1.5)
            t = oif.OifCellType(*oif.mesh_files("rbc162"), system=s, resize=(2.0, 2.0, 2.0),
                                ks=0.05, kb=0.01, kal=0.01, kag=0.1, kv=0.5)
            cells = [oif.OifCell(cell_type=t, particle_type=i, origin=[4.0 + 7.0 * i, 6.0, 6.0])
                     for i in range(4)]
            s.integrator.run(10)
            n = s._core.membrane_counts()
            say("spread", s._core.particles_spread, "cells evaluated", n["lane_batches"], n["padded_lanes"],
                n["plain_cells"])
            """)
        rows = {line.split(" ", 1)[0]: line.split(" ", 1)[1] for line in lines if line[:1].isdigit()}
        self.assertEqual(set(rows), {"0", "1"}, lines)
        # 4 cells at x = 4, 11 (rank 0's half) and 18, 25 (rank 1's): each
        # rank evaluates its two as one lane group with two padded lanes per
        # force calculation, 11 calculations (the first and 10 steps), never
        # the others' cells (all four would fill a group: no padding)
        for rank in "01":
            self.assertEqual(rows[rank], "spread True cells evaluated 11 22 0", lines)

    SPEED_SCENE = """
        import warnings
        import lbmd.lb
        s = lbmd.System(box_l=[8.0, 10.0, 4.0]); s.time_step = 0.1
        if lbmd.size > 1:
            s.cell_system.node_grid = [1, 2, 1]  # cut across the flow profile
        lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, ext_force_density=[0.101, 0, 0])
        s.actors.add(lbf)
        for w in (lbmd.shapes.Wall(normal=[0, 1, 0], dist=1), lbmd.shapes.Wall(normal=[0, -1, 0], dist=-9)):
            s.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=w))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(1500)
        mach, node, update = s.__dict__["_mach_highest"]
        say("seen", repr(mach), node, update, sum("reached Mach" in str(w.message) for w in caught))
        """

    def test_speed_watch_agrees(self):
        """The speed watch's fastest node over two ranks (the fastest nodes
        y 4.5 and 5.5 on either side of the cut) is the serial run's, bit for
        bit, and rank 0 alone warns."""
        serial = self.run_ranks(self.SPEED_SCENE, ranks=1)
        lines = self.run_ranks(self.SPEED_SCENE, ranks=2)
        rows = {line.split(" ", 1)[0]: line.split(" ", 1)[1] for line in lines if line[:1].isdigit()}
        one = serial[0].split(" ", 1)[1]
        self.assertTrue(one.startswith("seen 0.1") and one.endswith(" 1"), one)
        self.assertEqual(rows["0"], one)
        self.assertEqual(rows["1"], one[:-1] + "0")


if __name__ == "__main__":
    unittest.main()
