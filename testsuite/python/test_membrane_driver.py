"""The membrane component (src/core/interactions/membrane/): every OIF bond
(OifLocalForces, OifGlobalForces, OifOutDirection) is compiled into cells and
evaluated by one driver, four cells of a type at once in vector lanes (the
last two or three padded) and a lone cell alone, for the time step and the
analysis alike.

Checked here through the Python API, on rbc374 cells randomly rotated,
deformed (affine stretch + noise) and moving (membrane viscosity), one
straddling a corner of the periodic box:
- the lanes give the forces and node normals of every cell alone, bit for
  bit, for each modulus alone, pairs of them and all together, for two cell
  types, cells of one type with other references, bonds added by hand;
- the time step runs the lanes (counters), and the tables compiled once are
  kept until particles, mol_ids or bonds change; after each change they equal
  a fresh compilation bit for bit;
- the sum of the analysis' per-term forces (oif_forces) is the time step's
  force to round-off (1e-12 relative);
- a broken bond raises a SimulationInstability naming the bond."""
import unittest

import numpy as np

import lbmd
import oif

BOX = 24.0
ALL = dict(ks=0.05, kb=0.08, kal=0.03, kag=0.6, kv=0.9, kvisc=0.04)
ALL_LINEAR = dict(ALL, ks=0.0, kslin=0.02)  # the oif package takes ks or kslin


def make(moduli, seed=5, noise=0.04, origins=([0.4, BOX - 0.3, 0.2], [12.0, 11.0, 13.0])):
    rng = np.random.default_rng(seed)
    system = lbmd.System(box_l=[BOX, BOX, BOX])
    system.time_step = 0.01
    system.cell_system.skin = 0.3
    # a particle outside the membranes, first in the store: removing it moves
    # the last membrane node into its slot (local indices change, bonds do not)
    system.part.add(pos=[1.0, 2.0, 3.0], type=1)
    rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.0, 3.0, 3.0),
                          normal=True, **moduli)
    cells = [oif.OifCell(cell_type=rbc, particle_type=0, origin=origin,
                         rotate=rng.uniform(0, 2 * np.pi, 3))
             for origin in origins]
    for cell, cell_noise in zip(cells, np.broadcast_to(noise, len(cells))):
        x = cell.particles.pos
        centre = x.mean(axis=0)
        stretch = np.diag(rng.uniform(0.85, 1.15, 3))
        x = centre + (x - centre) @ stretch + rng.normal(scale=cell_noise, size=x.shape)
        cell.particles.pos = x
        cell.particles.v = rng.normal(scale=0.1, size=x.shape)
    return system, cells


def forces_and_normals(system, lanes=True, fresh=False):
    core = system._core
    core.membrane_lanes = lanes
    if fresh:
        core.membrane_invalidate()
    core.compute_forces()
    parts = system.part.all()
    core.membrane_lanes = True
    return parts.f.copy(), parts.normal.copy()


class LanesEqualOneCellAtATime(unittest.TestCase):
    def compare(self, system, label):
        """Lanes against every cell alone, and the cached tables against a
        fresh compilation: bit for bit."""
        f_lanes, n_lanes = forces_and_normals(system)
        f_plain, n_plain = forces_and_normals(system, lanes=False)
        f_fresh, n_fresh = forces_and_normals(system, fresh=True)
        self.assertGreater(np.abs(f_lanes).max(), 0.0, label)
        for name, (f, n) in {"one at a time": (f_plain, n_plain), "fresh": (f_fresh, n_fresh)}.items():
            self.assertTrue(np.array_equal(f_lanes, f), f"{label}, {name}: forces differ by "
                                                        f"{np.abs(f_lanes - f).max():.2e}")
            self.assertTrue(np.array_equal(n_lanes, n), f"{label}, {name}: normals")
        return f_lanes

    def test_each_modulus_and_all(self):
        cases = {k: {k: v} for k, v in ALL_LINEAR.items() if v}
        cases.update(ks={"ks": ALL["ks"]}, all=ALL, all_linear=ALL_LINEAR,
                     kb_kv={"kb": ALL["kb"], "kv": ALL["kv"]},
                     ks_kal_kag={k: ALL[k] for k in ("ks", "kal", "kag")},
                     kvisc_kv={"kvisc": ALL["kvisc"], "kv": ALL["kv"]})
        for name, moduli in cases.items():
            # two cells: one group of lanes, two of them padded
            system, cells = make(moduli)
            folded = cells[0].particles.pos_folded  # the first straddles the box corner
            self.assertTrue((folded[:, 0] < 2).any() and (folded[:, 0] > BOX - 2).any())
            self.compare(system, name)
            counts = system._core.membrane_counts()
            self.assertGreater(counts["lane_batches"], 0, name)

    def test_six_cells_and_changes(self):
        """Six cells of one type (a group of four and one of two), deformed by
        different amounts (some dihedral deviations beyond the polynomial
        arctangent's 14 degrees), then changes: a mol_id, a node removed, a
        cell added, 20 steps across the boundary."""
        origins = ([0.4, BOX - 0.3, 0.2], [12.0, 11.0, 13.0], [6.0, 18.0, 6.0],
                   [18.0, 6.0, 18.0], [6.0, 6.0, 18.0], [18.0, 18.0, 6.0])
        noise = [0.01, 0.04, 0.15, 0.02, 0.08, 0.03]
        system, cells = make(ALL, origins=origins, noise=noise)
        self.compare(system, "six cells")
        cells[2].particles.mol_id = 17
        self.compare(system, "a mol_id changed")
        cells[0].particles.mol_id = 17  # two cells one "cell": sums over both
        self.compare(system, "two cells, one mol_id")
        cells[0].particles.mol_id = np.where(np.arange(374) % 2 == 0, 3, 40)  # mixed within a cell
        self.compare(system, "mixed mol_ids in a cell")
        cells[0].particles.mol_id = 3
        system.part.by_id(0).remove()
        self.compare(system, "free particle removed")
        system.part.by_id(int(cells[1].particles.id[5])).remove()
        self.compare(system, "node removed")
        oif.OifCell(cell_type=cells[0].cell_type, particle_type=0, origin=[12.0, 3.0, 3.0],
                    rotate=[0.3, 1.1, 0.2])
        self.compare(system, "cell added")
        system.thermostat.set_langevin(kT=0.0, gamma=0.5)
        system.part.all().ext_force = [0.05, -0.03, 0.02]
        # the noisy cells have folded triangles (noise 0.15) and one "cell" of
        # two: a comparison of drivers, not a physical run
        system.cell_checks = False
        system.integrator.run(20)
        self.compare(system, "20 steps")

    def test_two_cell_types(self):
        rng = np.random.default_rng(7)
        system = lbmd.System(box_l=[BOX, BOX, BOX])
        system.time_step = 0.01
        system.cell_system.skin = 0.3
        rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.0, 3.0, 3.0),
                              normal=True, **ALL)
        sphere = oif.OifCellType(*oif.mesh_files("sphere162"), system=system,
                                 resize=(2.5, 2.5, 2.5), normal=True,
                                 ks=0.03, kb=0.05, kal=0.02, kag=0.4, kv=0.7)
        for k in range(5):  # interleaved: five of each type (a group of four, one alone)
            for t in (rbc, sphere):
                cell = oif.OifCell(cell_type=t, particle_type=0, rotate=rng.uniform(0, 6, 3),
                                   origin=[0.3 + 5.0 * k, 6.0 if t is rbc else 18.0, BOX - 0.4])
                x = cell.particles.pos
                cell.particles.pos = x + rng.normal(scale=0.03, size=x.shape)
                cell.particles.v = rng.normal(scale=0.1, size=x.shape)
        self.compare(system, "two types")
        before = system._core.membrane_counts()
        system._core.compute_forces()
        after = system._core.membrane_counts()
        self.assertEqual(after["lane_batches"] - before["lane_batches"], 2)
        self.assertEqual(after["plain_cells"] - before["plain_cells"], 2)

    def test_cells_with_other_references(self):
        """A cell of a type whose bonds carry other references (re-added by
        hand with 2 % longer relaxed edges) gets its own tables and feels them."""
        origins = ([0.4, BOX - 0.3, 0.2], [12.0, 11.0, 13.0], [6.0, 18.0, 6.0],
                   [18.0, 6.0, 18.0], [6.0, 6.0, 18.0], [18.0, 18.0, 6.0])
        system, cells = make(ALL, origins=origins)
        f_same = self.compare(system, "one type")
        ct = cells[0].cell_type
        rows, per_bond = ct._local_rows()
        ids = cells[1].mesh.part_ids
        h = ct.local_force_interaction
        for row in ids[rows]:
            system.part.by_id(int(row[0])).delete_bond((h, *[int(x) for x in row[1:]]))
        longer = per_bond.copy()
        longer[:, 0] *= 1.02
        system.part.add_bonds(h, ids[rows], longer)
        f_other = self.compare(system, "one type, other references")
        mine = np.isin(np.asarray(system.part.all().id), ids)
        self.assertGreater(np.abs(f_other[mine] - f_same[mine]).max(), 1e-4)
        self.assertTrue(np.array_equal(f_other[~mine], f_same[~mine]))

    def test_bonds_by_hand(self):
        """A strip of triangle pairs (an open mesh: triangles in one or two
        bonds) with ks and kslin together across the periodic boundary; a
        tetrahedron of OifGlobalForces + OifOutDirection triangles across a
        corner of the box."""
        from lbmd.interactions import OifGlobalForces, OifLocalForces, OifOutDirection
        rng = np.random.default_rng(3)
        system = lbmd.System(box_l=[6.0, 6.0, 6.0])
        system.time_step = 0.01
        system.cell_system.skin = 0.3
        strip = np.array([[0.5 * i - 1.7, 1.0 + 0.8 * (i % 2), 2.0] for i in range(8)])
        strip += rng.normal(scale=0.08, size=strip.shape)
        tetra = np.array([[5.6, 5.7, 0.3], [6.5, 5.8, 0.1], [5.9, 6.6, 0.2], [6.0, 6.0, -0.6]])
        ids = system.part.add(pos=np.vstack([strip, tetra]), v=rng.normal(scale=0.2, size=(12, 3))).id
        local = OifLocalForces(r0=0.6, ks=0.05, kslin=0.03, phi0=2.9, kb=0.07, A01=0.2, A02=0.25,
                               kal=0.04, kvisc=0.02)
        system.bonded_inter.add(local)
        system.part.add_bonds(local, np.array([[ids[i + 1], ids[i], ids[i + 2], ids[i + 3]]
                                               for i in range(5)]))
        glob = OifGlobalForces(A0_g=3.0, ka_g=0.5, V0=0.6, kv=0.8)
        out = OifOutDirection()
        system.bonded_inter.add(glob)
        system.bonded_inter.add(out)
        t = ids[8:]
        tris = np.array([[t[0], t[2], t[1]], [t[0], t[1], t[3]], [t[1], t[2], t[3]], [t[0], t[3], t[2]]])
        system.part.add_bonds(glob, tris)
        system.part.add_bonds(out, tris)
        f = self.compare(system, "bonds by hand")
        self.assertGreater(np.abs(f[:8]).max(), 1e-3)
        self.assertGreater(np.abs(f[8:]).max(), 1e-3)
        # the tetrahedron's normals point away from its centre
        x = system.part.all().pos[8:]
        n = system.part.all().normal[8:]
        self.assertTrue((np.einsum("ij,ij->i", x - x.mean(axis=0), n) > 0).all())


class TimeStepAndAnalysis(unittest.TestCase):
    def test_time_step_runs_the_lanes(self):
        origins = [[6.0 + 12.0 * (k % 2), 6.0 + 12.0 * (k // 2 % 2), 6.0 + 12.0 * (k // 4)]
                   for k in range(8)]
        system, _ = make(ALL, origins=origins, noise=0.01)
        system.thermostat.set_langevin(kT=0.0, gamma=0.5)
        system.integrator.run(30)
        counts = system._core.membrane_counts()
        self.assertEqual(counts["compiles"], 1)
        self.assertEqual(counts["lane_batches"], 2 * 31)  # the run's first force calculation + 30 steps
        self.assertEqual(counts["plain_cells"], 0)
        self.assertEqual(counts["padded_lanes"], 0)

    def test_analysis_terms_add_up_to_the_time_step(self):
        system, cells = make(ALL)
        f_step, _ = forces_and_normals(system)
        ct = cells[0].cell_type
        total = np.zeros_like(f_step)
        ids = np.asarray(system.part.all().id)
        for inter, terms in ((ct.local_force_interaction, ("stretching", "bending", "local_area", "visc")),
                             (ct.global_force_interaction, ("global_area", "volume"))):
            for term in terms:
                fid, f = system._core.oif_forces(system.bonded_inter._id_of(inter), term)
                total[np.searchsorted(ids, fid)] += f
        err = np.abs(total - f_step).max() / np.abs(f_step).max()
        self.assertLess(err, 1e-12)

    def test_positions_set_folded(self):
        """A script that sets a cell's positions to their folded values (the
        cell across the box corner, so its unfolded positions jump by a box
        length) gets the same forces: the gather falls back to the minimum
        image relative to the cell's first node (1e-12 relative)."""
        system, cells = make(ALL)
        f_before, _ = forces_and_normals(system)
        folded = cells[0].particles.pos_folded
        self.assertGreater(np.ptp(folded, axis=0).max(), BOX / 2)  # really split by the faces
        cells[0].particles.pos = folded
        f_after, _ = forces_and_normals(system)
        err = np.abs(f_after - f_before).max() / np.abs(f_before).max()
        self.assertLess(err, 1e-12)
        system.integrator.run(5)  # and runs on

    def test_collapsed_surface_triangle_names_it(self):
        """A triangle of a cell's closed surface collapsed to a line: with
        global terms on it is named, as the local bonds' are; a cell with
        normals only goes on."""
        from lbmd.interactions import OifGlobalForces, OifOutDirection
        for interaction in (OifGlobalForces(A0_g=3.0, ka_g=0.0, V0=0.6, kv=0.8), OifOutDirection()):
            for lanes in (True, False):
                system = lbmd.System(box_l=[10.0, 10.0, 10.0])
                system.time_step = 0.01
                # vertex 3 on the line through 0 and 1: triangle (0, 1, 3) has no area
                x = np.array([[1.0, 1.0, 1.0], [2.0, 1.0, 1.0], [1.2, 2.0, 1.1], [1.5, 1.0, 1.0]])
                ids = system.part.add(pos=x).id
                system.bonded_inter.add(interaction)
                system.part.add_bonds(interaction, np.array(
                    [[ids[0], ids[2], ids[1]], [ids[0], ids[1], ids[3]], [ids[1], ids[2], ids[3]],
                     [ids[0], ids[3], ids[2]]]))
                system._core.membrane_lanes = lanes
                if isinstance(interaction, OifOutDirection):
                    system._core.compute_forces()
                    continue
                with self.assertRaises(lbmd.SimulationInstability) as ctx:
                    system._core.compute_forces()
                self.assertIn("OifGlobalForces triangle of particles", str(ctx.exception))
                self.assertIn("zero area", str(ctx.exception))

    def test_bad_analysis_inputs(self):
        system, cells = make(ALL)
        bond = system.bonded_inter._id_of(cells[0].cell_type.local_force_interaction)
        with self.assertRaisesRegex(ValueError, "mol_id"):
            system._core.oif_energies(bond, -3)
        with self.assertRaisesRegex(ValueError, "angle 1 .* is degenerate"):
            lbmd._lbmd.membrane_angles(np.array([[0.0, 1, 0], [0, 0, 0], [1, 0, 0], [0, -1, 0]]),
                                       np.array([[0, 1, 2, 3], [0, 1, 1, 3]]))

    def test_broken_bond_names_it(self):
        for moduli in (dict(ks=0.05, kb=0.08), ALL):
            system, cells = make(moduli)
            system._core.compute_forces()
            edge = cells[1].mesh.edges[0]  # one edge's ends on top of each other: zero length
            system.part.by_id(edge.B.part_id).pos = system.part.by_id(edge.A.part_id).pos
            for lanes in (True, False):
                system._core.membrane_lanes = lanes
                with self.assertRaises(lbmd.SimulationInstability) as ctx:
                    system._core.compute_forces()
                message = str(ctx.exception)
                self.assertIn("OifLocalForces bond between particles", message)
                self.assertIn(f"mol_id {cells[1].cell_id}", message)
                self.assertIn(str(edge.A.part_id), message)



class ImplicitViscositySeesEveryForce(unittest.TestCase):
    """The implicit membrane viscosity is solved last, against every force of
    the step (doc/interactions.md): a contact's push on one node of a cell at
    rest is shared at once with the node's neighbours, as stiff dashpots
    should; solved inside the membrane pass, before the contacts, it let the
    node take the whole push (the speed ratio was 1, and membranes crossed in
    dense flow). The dashpots are internal forces: the forces on the cell's
    nodes add up to the contact's alone, minus the obstacle's."""

    def pushed(self, kvisc):
        s = lbmd.System(box_l=[BOX, BOX, BOX])
        s.time_step = 0.01
        s.cell_system.skin = 0.3
        rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=s, resize=(3.0, 3.0, 3.0), ks=0.05,
                              kvisc=kvisc)
        cell = oif.OifCell(cell_type=rbc, particle_type=0, origin=[12.0, 12.0, 12.0], particle_mass=1.0)
        x = cell.particles.pos
        k = int(np.argmax(x[:, 0]))  # the node farthest along +x, pushed back by a fixed particle
        obstacle = s.part.add(pos=x[k] + [0.5, 0.0, 0.0], type=1, fix=[True, True, True])
        s.non_bonded_inter[0, 1].soft_sphere.set_params(a=1.0, n=2.0, cutoff=1.0)
        s.integrator.run(1)
        v = cell.particles.v
        unbalanced = cell.particles.f.sum(axis=0) + obstacle.f  # elastic and viscous forces: internal
        return v[k], unbalanced / np.abs(obstacle.f).max(), s._core.membrane_counts()["viscous_solves"]

    def test_a_push_is_shared_with_the_patch(self):
        v_free, unbalanced_free, solves_free = self.pushed(0.0)
        # dt kvisc_node / m = 0.01 * 6 * 1000: far beyond the explicit limit 1.5
        v_stiff, unbalanced_stiff, solves_stiff = self.pushed(1000.0)
        self.assertEqual(solves_free, 0)
        self.assertGreater(solves_stiff, 0)  # the implicit solve ran
        self.assertLess(v_free[0], -1e-3)  # the push, along -x
        ratio = v_stiff[0] / v_free[0]
        self.assertGreater(ratio, 0.0)
        # measured 0.415: the dashpots resist along the edges only, and the
        # push is along the normal at the cell's rim; solved before the
        # contacts the ratio was 1 (no elastic force at rest, nothing to damp)
        self.assertLess(ratio, 0.6, f"the pushed node kept {ratio:.3f} of its free speed")
        for unbalanced in (unbalanced_free, unbalanced_stiff):
            np.testing.assert_allclose(unbalanced, 0.0, atol=1e-12)

if __name__ == "__main__":
    unittest.main()
