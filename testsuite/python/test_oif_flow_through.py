"""Cells in and out (oif.CellFlow) of a channel with a velocity inlet and a
pressure outlet (lbmd.open_boundaries): cells that reach the outlet plane
are removed before any node wraps round the periodic box; new cells enter
the inlet box without overlapping cells or walls (at insertion the nodes of
different cells are at least the seeding gap apart); recycling keeps the
number of cells; a haematocrit target fills the inlet; the same seed gives
the same cells, entries and exits."""
import unittest

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes
from lbmd.open_boundaries import PressureOutlet, VelocityInlet

L, W, H = 30.0, 12.0, 12.0


def scene(seed, mode):
    s = lbmd.System(box_l=[L, W, H])
    s.time_step = 0.1
    s.cell_system.skin = 0.3
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
    s.actors.add(lbf)
    walls = [shapes.Wall(normal=[0, 0, 1], dist=1.0), shapes.Wall(normal=[0, 0, -1], dist=-(H - 1.0)),
             shapes.Wall(normal=[0, 1, 0], dist=1.0), shapes.Wall(normal=[0, -1, 0], dist=-(W - 1.0))]
    for w in walls:
        s.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
        s.constraints.add(shape=w, particle_type=10, penetrable=False)
    lbf.open_boundaries.add(VelocityInlet(face="x-", profile="poiseuille", mean_velocity=0.15))
    lbf.open_boundaries.add(PressureOutlet(face="x+", density=1.0))
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(2.5, 2.5, 2.5), ks=0.02, kb=0.02,
                          kal=0.02, kag=0.7, kv=0.9, normal=True)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=rbc.suggest_LBgamma(visc=1.5, dens=1.0))
    s.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.001, n=1.5, cutoff=0.8)
    s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.01, n=1.2, cutoff=0.8)
    kwargs = {"recycle": True} if mode == "recycle" else {"haematocrit": 0.12}
    flow = oif.CellFlow(s, rbc, inlet=([3.0, 1.0, 1.0], [12.0, W - 1.0, H - 1.0]), outlet=L - 5.0,
                        boundaries=walls, seed=seed, **kwargs)
    if mode == "recycle":
        flow.cells = oif.seed_cells(s, rbc, counts=2, boundaries=walls, region=([3, 1, 1], [L - 9, W - 1, H - 1]),
                                    seed=seed)
    return s, flow


def min_gap(cells, new):
    """Smallest distance between the nodes of `new` and of the other cells."""
    others = [c for c in cells if c is not new]
    if not others:
        return np.inf
    a = new.mesh.positions()
    b = np.concatenate([c.mesh.positions() for c in others])
    return float(np.min(np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)))


def run(seed, mode, outputs=18, steps=100):
    s, flow = scene(seed, mode)
    history = []
    gaps = []
    counts = []
    flow.update()
    for _ in range(outputs):
        s.integrator.run(steps)
        for c in flow.cells:  # no node wraps round the box into the inlet
            assert c.mesh.positions()[:, 0].max() < L, "a cell crossed the periodic edge"
        added, removed = flow.update()
        gaps += [min_gap(flow.cells, c) for c in added]
        history.append(([c.cell_id for c in added], [c.cell_id for c in removed]))
        counts.append(len(flow.cells))
    return s, flow, history, gaps, counts


class FlowThrough(unittest.TestCase):
    def test_recycle(self):
        s, flow, history, gaps, counts = run(3, "recycle")
        n_out = sum(len(r) for _, r in history)
        self.assertGreater(n_out, 0, "no cell reached the outlet")
        self.assertEqual(len(flow.removed), n_out)
        self.assertTrue(all(c == 2 for c in counts), f"recycling changed the number of cells: {counts}")
        self.assertTrue(all(g >= 0.5 for g in gaps), f"a new cell came too close to another: {gaps}")
        self.assertTrue(np.all(np.isfinite(s.part.all().pos)))

    def test_haematocrit_and_determinism(self):
        s1, flow1, history1, gaps, _ = run(5, "haematocrit", outputs=9)
        self.assertGreater(len(flow1.added), 0)
        self.assertGreaterEqual(flow1.inlet_haematocrit(), 0.12 * 0.5)
        s2, flow2, history2, _, _ = run(5, "haematocrit", outputs=9)
        self.assertEqual(history1, history2)
        np.testing.assert_array_equal(s1.part.all().pos, s2.part.all().pos)

    def test_bad_arguments(self):
        s, flow = scene(1, "haematocrit")
        rbc = flow.types[0]
        inlet = ([1.0, 1.0, 1.0], [10.0, W - 1.0, H - 1.0])
        with self.assertRaisesRegex(ValueError, "exactly one"):
            oif.CellFlow(s, rbc, inlet=inlet, outlet=L - 3, haematocrit=0.1, rate=1.0)
        with self.assertRaisesRegex(ValueError, "outlet"):
            oif.CellFlow(s, rbc, inlet=inlet, outlet=5.0, recycle=True)
        with self.assertRaisesRegex(ValueError, "inlet"):
            oif.CellFlow(s, rbc, inlet=([1, 1, 1], [0, 5, 5]), outlet=L - 3, recycle=True)
        with self.assertRaisesRegex(ValueError, "haematocrit"):
            oif.CellFlow(s, rbc, inlet=inlet, outlet=L - 3, haematocrit=0.9)
        with self.assertRaises(TypeError):
            oif.CellFlow(s, "rbc", inlet=inlet, outlet=L - 3, recycle=True)


if __name__ == "__main__":
    unittest.main()
