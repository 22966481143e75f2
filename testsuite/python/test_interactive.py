"""Interactive use: repr() of the objects a user touches shows their key
parameters; dir() lists the parameters served through __getattr__ (tab
completion); integrator.run(n, progress=True) gives the result of
progress=False bit for bit and prints its summary line (wall time, steps/s,
MLUPS, the cells' time per cell)."""
import contextlib
import io
import sys
import unittest

import numpy as np

import lbmd
import oif
from lbmd import interactions, lb, lbboundaries, open_boundaries, shapes, units
from h5md_scene import scene


def build():
    system = lbmd.System(box_l=[20.0, 12.0, 12.0], time_step=0.1)
    system.cell_system.skin = 0.3
    ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(2.5,) * 3, ks=0.05, kb=0.07,
                         kal=0.05, kag=0.7, kv=0.9, normal=True)
    cell = oif.OifCell(cell_type=ct, particle_type=1, origin=[10.0, 6.0, 6.0])
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.5, tau=0.1, ext_force_density=[1e-3, 0, 0])
    system.actors.add(lbf)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=0.5, seed=3)
    wall = shapes.Wall(normal=[0, 0, 1], dist=1.0)
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=wall))
    system.constraints.add(shape=wall, particle_type=10, penetrable=False)
    system.non_bonded_inter[1, 10].soft_sphere.set_params(a=0.0002, n=1.2, cutoff=0.6)
    bond = interactions.HarmonicBond(k=2.0, r_0=1.5)
    system.bonded_inter.add(bond)
    p = system.part.add(pos=[1, 2, 3], type=4)
    return dict(system=system, ct=ct, cell=cell, lbf=lbf, wall=wall, bond=bond, p=p)


class Repr(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.s = build()

    def check(self, obj, *parts):
        text = repr(obj)
        self.assertLess(len(text), 400, text)  # short
        for part in parts:
            self.assertIn(part, text, f"{type(obj).__name__}: {text}")

    def test_engine_objects(self):
        s = self.s
        system = s["system"]
        self.check(system, "box_l=[20.0, 12.0, 12.0]", "time_step=0.1", "particles=163")
        self.check(s["lbf"], "agrid=1.0", "visc=1.5", "tau=0.1", "ext_force_density=[0.001, 0.0, 0.0]")
        self.check(s["wall"], "Wall(", "normal=[0.0, 0.0, 1.0]", "dist=1.0")
        self.check(shapes.Sphere(center=[1, 2, 3], radius=2.0), "center=[1.0, 2.0, 3.0]", "radius=2.0")
        self.check(system.lbboundaries, "LBBoundaries([LBBoundary(shape=Wall(")
        self.check(system.constraints, "Constraints([ShapeBasedConstraint(", "particle_type=10")
        self.check(system.non_bonded_inter, "soft_sphere", "membrane_collision")
        self.check(system.non_bonded_inter[1, 10], "(1, 10", "active=['soft_sphere']")
        self.check(system.non_bonded_inter[1, 10].soft_sphere, "'a': 0.0002", "'cutoff': 0.6")
        self.check(system.bonded_inter, "4 bonds", "OifLocalForces", "3: HarmonicBond")
        self.check(s["bond"], "k=2.0", "r_0=1.5")
        self.check(s["ct"].local_force_interaction, "ks=0.05", "kb=0.07")
        self.check(system.thermostat, "LB(gamma=0.5, seed=3)")
        self.check(system.integrator, "velocity Verlet", "time_step=0.1", "step_count=0")
        self.check(system.cell_system, "skin=0.3", "node_grid=[1, 1, 1]")
        self.check(system.actors, "Actors([LBFluid(")
        self.check(system.analysis, "energy()")
        self.check(s["p"], "id=162", "pos=[1.0, 2.0, 3.0]", "type=4")
        self.check(system.part.all(), "163 particles", "ids [0, 1, 2")
        self.check(system.part, "163 particles")
        self.check(s["lbf"].open_boundaries, "OpenBoundaries([])")
        self.check(open_boundaries.VelocityInlet(face="x-", mean_velocity=0.01), "face='x-'", "mean_velocity=0.01")
        self.check(units.UnitSystem(), "length=1e-06")

    def test_oif_objects(self):
        ct, cell = self.s["ct"], self.s["cell"]
        self.check(ct, "162 nodes", "resize=[2.5, 2.5, 2.5]", "ks=0.05", "kb=0.07", "kag=0.7", "kv=0.9",
                   "normal=True")
        self.assertNotIn("kslin", repr(ct))  # only the moduli in use
        self.check(cell, "cell_id=0", "162 nodes", "particle_type=1", "origin=[10.0, 6.0, 6.0]")
        self.check(cell.mesh, "mol_id 0", "162 nodes", "320 triangles")
        self.check(ct.mesh, "relaxed mesh", "162 nodes")
        self.check(cell.mesh.points[0], "PartPoint(id=0, part_id=0)")
        self.check(ct.mesh.points[0], "FixedPoint(id=0, pos=[")
        e, t, a = cell.mesh.edges[0], cell.mesh.triangles[0], cell.mesh.angles[0]
        self.check(e, f"Edge({e.A.id}, {e.B.id})")
        self.check(t, f"Triangle({t.A.id}, {t.B.id}, {t.C.id})")
        self.check(a, f"Angle({a.A.id}, {a.B.id}, {a.C.id}, {a.D.id})")
        self.check(cell.mesh.neighbors[0], "ThreeNeighbors(")
        from oif import mesh_io
        self.check(mesh_io.from_arrays(ct.mesh._nodes, ct.mesh.triangle_ids), "162 nodes", "320 triangles")

    def test_cell_flow(self):
        system = lbmd.System(box_l=[30.0, 12.0, 12.0], time_step=0.1)
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=system, resize=(2.0,) * 3, ks=0.05)
        flow = oif.CellFlow(system, ct, inlet=([0, 0, 0], [8, 12, 12]), outlet=25.0, rate=0.5, seed=1)
        self.check(flow, "rate=0.5", "inlets=[[[0.0, 0.0, 0.0], [8.0, 12.0, 12.0]]]", "outlets=[x+ at 25]", "0 cells")


class Dir(unittest.TestCase):
    def test_parameters_listed(self):
        s = build()
        system = s["system"]
        names = dir(system)
        for name in ("box_l", "periodicity", "time_step", "time", "part", "integrator", "thermostat",
                     "actors", "cell_system", "non_bonded_inter", "bonded_inter", "constraints",
                     "lbboundaries", "analysis", "step_count"):
            self.assertIn(name, names)
        for obj, params in ((s["lbf"], ("agrid", "dens", "visc", "tau", "ext_force_density", "kT", "shape")),
                            (s["wall"], ("normal", "dist")),
                            (s["bond"], ("k", "r_0")),
                            (system.constraints[0], ("shape", "particle_type", "penetrable")),
                            (s["p"], ("pos", "v", "f", "type", "mol_id", "mass", "id", "image_box", "fix")),
                            (system.part.all(), ("pos", "v", "f")),
                            (system.non_bonded_inter[0, 1], ("soft_sphere", "membrane_collision")),
                            (s["cell"], ("cell_id", "mesh", "volume", "surface", "get_origin")),
                            (s["ct"], ("ks", "kb", "kv", "mesh", "volume0")),
                            (system.cell_system, ("skin", "node_grid")),
                            (system.integrator, ("run", "timings"))):
            names = dir(obj)
            for name in params:
                self.assertIn(name, names, type(obj).__name__)
                getattr(obj, name)  # and it can be read


class Progress(unittest.TestCase):
    def test_bit_identical_and_summary(self):
        states, lines = [], []
        for progress in (False, True):
            system, cell, _ = scene()
            out, err = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                system.integrator.run(7, recalc_forces=True, progress=progress)
                result = system.integrator.run(150, progress=progress)
            lines.append(out.getvalue())
            if progress:
                self.assertIsInstance(result, str)
                self.assertIn(result, out.getvalue())
            else:
                self.assertIsNone(result)
                self.assertEqual(out.getvalue(), "")  # progress=False prints nothing
                self.assertEqual(err.getvalue(), "")
            part = system.part.all()
            states.append((system.step_count, system.time, part.pos, part.v, part.f, cell.volume()))
        for a, b in zip(*states):
            self.assertTrue(np.array_equal(a, b), (a, b))
        self.assertEqual(states[0][0], 157)
        summary = lines[1].strip().splitlines()[-1]
        self.assertRegex(summary, r"^integrator.run: 150 steps \(time 0\.7 -> 15\.7\) in [0-9.]+ s, [0-9.]+ steps/s; "
                                  r"fluid [0-9.]+ MLUPS \(16x12x12 nodes\); 1 cell: [0-9.]+ s per cell per 1000 steps")

    def test_bar_for_a_script_loop(self):
        from lbmd.progress import Bar
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            bar = Bar(100, initial=20, mode="lines", every=0.0)
            bar.update(30, postfix="entries 3")
            bar.update(50)
            bar.close()
        lines = out.getvalue().splitlines()
        self.assertEqual(len(lines), 2)
        self.assertRegex(lines[0], r"^50/100 steps +[0-9]+ steps/s +[0-9]+ s left  entries 3$")
        self.assertTrue(lines[1].startswith("100/100 steps"))
        with contextlib.redirect_stdout(io.StringIO()) as quiet:
            off = Bar(10, mode="off")
            off.update(10)
        self.assertEqual(quiet.getvalue(), "")
        with self.assertRaisesRegex(ValueError, "mode must be one of auto, bar, lines, off"):
            Bar(10, mode="verbose")

    def test_zero_steps_and_bad_value(self):
        system, _, _ = scene()
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            system.integrator.run(0, progress=True)
        self.assertIn("integrator.run: 0 steps", out.getvalue())
        self.assertGreater(np.abs(system.part.all().f).max(), 0.0)  # the forces of the start, as run(0)
        with self.assertRaisesRegex(TypeError, "progress"):
            system.integrator.run(5, progress="yes")


if __name__ == "__main__":
    sys.exit(unittest.main())
