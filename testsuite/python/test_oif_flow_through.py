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
#: the device scenes' contacts, times the advised (oif.set_contacts): at 1x a node
#: passed a chamfer's corner in 1 of 12 runs (T-junction, seed 3)
CONTACT_SCALE = 3.0


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

    def test_several_outlets(self):
        """Planes on any face and regions: each cell leaves by the outlet
        it reached, logged with its index; a list of inlets is filled each."""
        s = lbmd.System(box_l=[40.0, 40.0, 12.0])
        s.time_step = 0.1
        s.cell_system.skin = 0.3
        rbc = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(2.0,) * 3, ks=0.01, kb=0.01,
                              kal=0.01, kag=0.1, kv=0.1, normal=True)
        inlets = [([2.0, 2.0, 2.0], [12.0, 12.0, 10.0]), ([2.0, 26.0, 2.0], [12.0, 36.0, 10.0])]
        flow = oif.CellFlow(s, rbc, inlet=inlets, outlets=[("x+", 35.0), ("y-", 1.5), ([20.0, 30.0, 0.0],
                                                                                        [30.0, 40.0, 12.0])],
                            recycle=True, seed=4)
        flow.cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=p)
                      for p in ([20.0, 20.0, 6.0], [20.0, 8.0, 6.0], [10.0, 20.0, 6.0], [15.0, 33.0, 6.0])]
        moves = {0: [34.0, 20.0, 6.0],   # reaches x >= 35: outlet 0
                 1: [20.0, 3.0, 6.0],    # reaches y <= 1.5: outlet 1
                 3: [22.0, 33.0, 6.0]}   # into the region: outlet 2
        for k, pos in moves.items():
            flow.cells[k].set_origin(pos)
        kept = flow.cells[2]
        added, removed = flow.update()
        self.assertEqual(len(removed), 3)
        self.assertEqual(sorted(k for _, _, k in flow.exits), [0, 1, 2])
        self.assertEqual(flow.exit_counts(), [1, 1, 1])
        self.assertIn(kept, flow.cells)
        # recycled: as many placed again, each in one of the two inlet boxes
        self.assertEqual(len(added), 3)
        for c in added:
            centre = c.get_origin()
            self.assertTrue(any(np.all(centre >= np.array(lo) - 1e-9) and np.all(centre <= np.array(hi) + 1e-9)
                                for lo, hi in inlets), centre)

    def device_run(self, polygon, open_faces, outlets, seed=2):
        """Cells (stiff spheres, radius 1.8) carried through a channel drawn
        as `polygon` (z 1..7; corners met head on chamfered: a sharp one
        pins a cell and crushes it, as in a real device) from a Poiseuille
        inlet on x- to pressure outlets on `open_faces`, for 6000 steps;
        returns (mass flux out / in over the last 2000 steps, CellFlow)."""
        s = lbmd.System(box_l=[40.0, 30.0, 8.0])
        s.time_step = 0.1
        s.cell_system.skin = 0.3
        s.cell_drift_tolerance = 0.1  # squeezed past the walls, within 10 %
        lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1)
        s.actors.add(lbf)
        walls = [shapes.Extrusion(polygons=[polygon], z=[1.0, 7.0], direction=-1)]
        for w in walls:
            s.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
            s.constraints.add(shape=w, particle_type=10, penetrable=False)
        lbf.open_boundaries.add(VelocityInlet(face="x-", profile="poiseuille", mean_velocity=0.1))
        for face in open_faces:
            lbf.open_boundaries.add(PressureOutlet(face=face, density=1.0))
        sphere = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(1.8,) * 3, ks=0.5, kb=0.1,
                                 kal=0.5, kag=0.7, kv=0.9, normal=True)
        s.thermostat.set_lb(LB_fluid=lbf, gamma=sphere.suggest_LBgamma(visc=1.5, dens=1.0))
        oif.set_contacts(s, sphere, particle_types=0, wall_types=10, scale=CONTACT_SCALE)
        flow = oif.CellFlow(s, sphere, inlet=([2.0, 11.0, 1.0], [9.0, 19.0, 7.0]), outlets=outlets, rate=0.05,
                            boundaries=walls, seed=seed)
        inflow = outflow = 0.0
        for k in range(60):
            s.integrator.run(100)
            flow.update()
            if k >= 40:  # the fluxes of the last 20 outputs: a cell near a face makes each one wobble
                inflow += lbf.open_boundaries.mass_flux("x-")
                outflow -= sum(lbf.open_boundaries.mass_flux(face) for face in open_faces)
        self.assertTrue(np.all(np.isfinite(s.part.all().pos)))
        self.assertEqual(sum(flow.exit_counts()), len(flow.removed))
        print(f"{self.id()}: mass out / in {outflow / inflow:.4f}, cells in {len(flow.added)}, out by "
              f"outlet {flow.exit_counts()}")
        return outflow / inflow, flow

    def test_t_junction_cells_leave_by_both(self):
        """A T-junction: the main channel y 10..20 from x- to x+, a side
        branch x 16..26 up to y+ (whose opposite face y- is solid): mass in
        = mass out within 1 %, cells leave by both outlets (seeds 1-6: all
        ran, mass out / in 0.9968-0.9985, 2-4 cells by x+ and 11-13 by y+)."""
        balance, flow = self.device_run(
            [[0, 10], [40, 10], [40, 20], [29, 20], [26, 23], [26, 31], [16, 31], [16, 23], [13, 20], [0, 20]],
            ["x+", "y+"], [("x+", 36.0), ("y+", 26.0)])
        self.assertAlmostEqual(balance, 1.0, delta=0.01)
        self.assertTrue(all(n > 0 for n in flow.exit_counts()), flow)

    def test_bifurcation_cells_leave_by_both(self):
        """A bifurcation: the inlet channel y 10..20 splits around an
        island (its apex chamfered) into branches y 2..10 and y 20..28 that
        both end on x+: two outlet regions on one face. Mass in = mass out
        within 1 %, cells leave by both branches (seeds 1-6: all ran, mass out
        / in 0.9939-0.9971, 4-6 cells by each branch)."""
        balance, flow = self.device_run(
            [[0, 10], [12, 10], [18, 2], [40, 2], [40, 10], [27, 10], [24, 13], [24, 17], [27, 20], [40, 20],
             [40, 28], [18, 28], [12, 20], [0, 20]],
            ["x+"], [([36.0, 0.0, 0.0], [40.0, 10.0, 8.0]), ([36.0, 20.0, 0.0], [40.0, 30.0, 8.0])])
        self.assertAlmostEqual(balance, 1.0, delta=0.01)
        self.assertTrue(all(n > 0 for n in flow.exit_counts()), flow)

    def test_several_outlets_refused(self):
        s, flow = scene(1, "haematocrit")
        rbc = flow.types[0]
        inlet = ([1.0, 1.0, 1.0], [10.0, W - 1.0, H - 1.0])
        with self.assertRaisesRegex(ValueError, "exactly one of 'outlet'"):
            oif.CellFlow(s, rbc, inlet=inlet, outlet=L - 3, outlets=[("x+", L - 3)], recycle=True)
        with self.assertRaisesRegex(ValueError, "face must be one of"):
            oif.CellFlow(s, rbc, inlet=inlet, outlets=[("up", 5.0)], recycle=True)
        with self.assertRaisesRegex(ValueError, "beyond every inlet box"):
            oif.CellFlow(s, rbc, inlet=inlet, outlets=[("x-", 5.0)], recycle=True)
        with self.assertRaisesRegex(ValueError, "overlaps the inlet box"):
            oif.CellFlow(s, rbc, inlet=inlet, outlets=[([5.0, 0.0, 0.0], [15.0, W, H])], recycle=True)
        with self.assertRaisesRegex(ValueError, "plane .* or a region"):
            oif.CellFlow(s, rbc, inlet=inlet, outlets=[42.0], recycle=True)


if __name__ == "__main__":
    unittest.main()
