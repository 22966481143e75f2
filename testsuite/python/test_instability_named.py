"""Every way a run breaks is named: lbmd.SimulationInstability with its cause,
the MD step and time, the place (lattice node, particle, cell) and the value;
a cell whose volume drifts warns (CellDriftWarning). Each test pushes a scene
past one edge of the stable region and checks the named error.

Causes (doc/engine.md, "When a run breaks"): lattice_nan, negative_density,
mach, particle_nan, particle_jump, triangle_collapsed, triangle_inverted,
volume_collapsed, volume_exploded, membrane_crossing (and cell_blown_up,
bond_broken, wall_penetration, outside_lattice, named by the same mechanism,
tested with their messages in test_oif_cell, test_constraints, test_lb_api;
wall_penetration's attributes across ranks in test_mpi_errors).
"""
import unittest
import warnings

import numpy as np

import lbmd
import lbmd.lb
import oif

R = 3.0


def fluid(ext=(0.0, 0.0, 0.0)):
    s = lbmd.System(box_l=[6.0, 6.0, 6.0])
    s.time_step = 0.5
    lbf = lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=0.5, tau=1.0, ext_force_density=list(ext))
    s.actors.add(lbf)
    return s, lbf


def cell_system(kv=3.0, mesh="sphere162"):
    s = lbmd.System(box_l=[40.0, 30.0, 30.0])
    s.time_step = 0.1
    s.cell_system.skin = 0.5
    s.thermostat.set_langevin(kT=0.0, gamma=0.5)
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=s, resize=(R, R, R), ks=0.05, kb=0.02,
                         kal=0.05, kag=0.5, kv=kv, normal=True)
    return s, ct


def one_cell(kv=3.0):
    """A system with one cell in the middle of the box."""
    s, ct = cell_system(kv=kv)
    return s, ct, oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0, 15.0, 15.0])


def first_triangle(ct, cell):
    """Node ids (i, a, b) of the mesh's first triangle and the positions."""
    return (*np.asarray(ct.mesh.triangle_ids)[0], cell.mesh.positions())


class Named(unittest.TestCase):

    def assert_named(self, run, cause):
        with self.assertRaises(lbmd.SimulationInstability) as ctx:
            run()
        e = ctx.exception
        self.assertEqual(e.cause, cause, str(e))
        self.assertIsNotNone(e.step, str(e))
        self.assertIsNotNone(e.time, str(e))
        return e

    # --- lattice ---------------------------------------------------------------
    def test_mach(self):
        s, lbf = fluid(ext=(0.0, 0.0, 0.05))  # accelerates 0.05 per update: Mach 1 in ~12
        e = self.assert_named(lambda: s.integrator.run(200), "mach")
        self.assertGreaterEqual(e.value, 1.0)  # |u| / c_s
        self.assertEqual(len(e.node), 3)
        self.assertGreater(e.step, 10)
        self.assertLess(e.step, 60)
        self.assertIn("speed", str(e))

    def corrupt(self, lbf, node, populations):
        """A state the API refuses (lbf[...].population checks its input):
        written past the checks, as a bug elsewhere would leave it."""
        lo = np.array(node)
        lbf._core.set_block("population", lo, lo + 1,
                            np.asarray(populations, dtype=float).reshape(1, 1, 1, 19))

    def test_negative_density(self):
        s, lbf = fluid()
        pops = lbf[2, 3, 4].population
        self.corrupt(lbf, (2, 3, 4), pops - 2 * pops.sum() / 19)  # density -1
        e = self.assert_named(lambda: s.integrator.run(4), "negative_density")
        self.assertEqual(e.node, (2, 3, 4))
        self.assertLess(e.value, 0.0)

    def test_lattice_nan(self):
        s, lbf = fluid()
        pops = lbf[1, 1, 1].population
        pops[1] = pops[2] = 1e308  # finite, their sum is not: the density overflows
        self.corrupt(lbf, (1, 1, 1), pops)
        e = self.assert_named(lambda: s.integrator.run(4), "lattice_nan")
        self.assertEqual(e.node, (1, 1, 1))

    # --- particles -------------------------------------------------------------
    def test_particle_nan(self):
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s.time_step = 0.01
        s.part.add(id=7, pos=[1.0, 1.0, 1.0], v=[1e308, 1e308, 0.0])
        e = self.assert_named(lambda: s.integrator.run(10), "particle_nan")
        self.assertEqual(e.particle, 7)

    def test_particle_jump_beyond_skin(self):
        s = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s.time_step = 0.01
        s.cell_system.skin = 0.2
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.001, n=1.0, cutoff=0.5, offset=0.0)
        s.part.add(id=0, pos=[1.0, 1.0, 1.0])
        s.part.add(id=3, pos=[5.0, 5.0, 5.0], v=[30.0, 0.0, 0.0])  # 0.3 per step > skin 0.2
        e = self.assert_named(lambda: s.integrator.run(5), "particle_jump")
        self.assertEqual(e.particle, 3)
        self.assertAlmostEqual(e.value, 0.3, delta=1e-9)
        self.assertEqual(e.step, 1)  # the drift of the first step
        # within the skin: no error
        s2 = lbmd.System(box_l=[10.0, 10.0, 10.0])
        s2.time_step = 0.01
        s2.cell_system.skin = 0.4
        s2.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.001, n=1.0, cutoff=0.5, offset=0.0)
        s2.part.add(id=3, pos=[5.0, 5.0, 5.0], v=[30.0, 0.0, 0.0])
        s2.integrator.run(5)
        # no skin (pair lists rebuilt every step): only the half-box limit
        s2.cell_system.skin = 0.0
        s2.integrator.run(5)

    # --- cells ---------------------------------------------------------------
    def test_inverted_triangle(self):
        s, ct, cell = one_cell()
        # a node moved across the opposite edge of one of its triangles: that
        # triangle turns over onto its neighbour across the edge
        i, a, b, x = first_triangle(ct, cell)
        x[i] = x[a] + x[b] - x[i]
        cell.particles.pos = x
        e = self.assert_named(lambda: s.integrator.run(1), "triangle_inverted")
        self.assertEqual(e.cell, cell.particles.mol_id[0])
        self.assertGreater(e.value, 150.0)  # degrees turned
        s.cell_checks = False  # off: the run goes on (a comparison of drivers may need it)
        s.integrator.run(1)

    def test_collapsed_triangle(self):
        s, ct, cell = one_cell()
        i, a, b, x = first_triangle(ct, cell)
        x[i] = x[a]  # an edge of zero length: its triangles have no area
        cell.particles.pos = x
        e = self.assert_named(lambda: s.integrator.run(1), "triangle_collapsed")
        self.assertEqual(e.cell, cell.particles.mol_id[0])
        self.assertEqual(e.value, 0.0)

    def test_volume_collapsed_and_exploded(self):
        for scale, cause in ((0.55, "volume_collapsed"), (1.7, "volume_exploded")):
            s, ct, cell = one_cell()
            x = cell.mesh.positions()
            c = x.mean(axis=0)
            cell.particles.pos = c + scale * (x - c)
            e = self.assert_named(lambda: s.integrator.run(1), cause)
            # the first step moves the nodes a little (the forces are large)
            self.assertAlmostEqual(e.value, scale ** 3, delta=0.1 * scale ** 3)
            self.assertEqual(e.cell, cell.particles.mol_id[0])

    def test_volume_drift_warns_once(self):
        s, ct, cell = one_cell(kv=0.0)  # kag holds the surface, nothing holds the volume
        s.cell_checks = True
        x = cell.mesh.positions()
        c = x.mean(axis=0)
        cell.particles.pos = c + 0.97 * (x - c)  # surface 0.941 of the relaxed one
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s.integrator.run(3)
            s.integrator.run(3)
        drift = [w for w in caught if issubclass(w.category, lbmd.CellDriftWarning)]
        self.assertEqual(len(drift), 1, [str(w.message) for w in caught])
        self.assertIn(f"mol_id {cell.particles.mol_id[0]}", str(drift[0].message))
        self.assertIn("surface", str(drift[0].message))
        # a looser tolerance: quiet
        s2, _, cell2 = one_cell(kv=0.0)
        s2.cell_drift_tolerance = 0.1
        x = cell2.mesh.positions()
        cell2.particles.pos = x.mean(axis=0) + 0.97 * (x - x.mean(axis=0))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            s2.integrator.run(3)
        self.assertFalse([w for w in caught if issubclass(w.category, lbmd.CellDriftWarning)])
        with self.assertRaises(ValueError):
            s2.cell_drift_tolerance = -0.1

    def test_membrane_crossing(self):
        """Two cells driven into each other with too weak a contact: named;
        with a contact strong enough (test_oif_contacts) they never cross."""
        s, ct = cell_system()
        c1 = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0 - R - 0.6, 15.0, 15.0])
        c2 = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0 + R + 0.6, 15.3, 15.2])
        s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.0002, n=4.0, cutoff=1.0, offset=0.0)
        push = 20.0 / ct.mesh.get_n_nodes()
        c1.set_force([push, 0.0, 0.0])
        c2.set_force([-push, 0.0, 0.0])
        e = self.assert_named(lambda: s.integrator.run(5000), "membrane_crossing")
        self.assertIn(e.cell, (c1.particles.mol_id[0], c2.particles.mol_id[0]))
        self.assertGreater(e.value, 0.0)  # depth inside the other membrane
        self.assertIn("membranes crossed", str(e))


if __name__ == "__main__":
    unittest.main()
