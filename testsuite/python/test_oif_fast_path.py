"""The time-step loop evaluates the OIF membrane bonds (OifLocalForces,
OifGlobalForces, OifOutDirection) with a compiled fast path
(src/core/interactions/bonded/oif_fast_path.*): an OifCellType's local and
global groups together, cell by cell, in one fused pass that also writes the
node normals; a group that does not pair up (a cell type with only local or
only global moduli, bonds added by hand) by its own plan. The generic bond
loop stays for energies and analysis. Both must give the same forces and node
normals: here on two rbc374 cells, randomly rotated, deformed (affine stretch
+ noise) and moving (membrane viscosity), one straddling a corner of the
periodic box, each modulus alone (separate plans), pairs of local and global
moduli and all together (fused), and on two cell types at once. Tolerance:
the largest nodal force difference <= 1e-12 x the largest nodal force
(floating-point operation order differs: the fast path sums each triangle's
local area once, takes the dihedral deviation from its reference in one
angle, the volume as a.N/6). Also: the cached plans follow particle removal,
mol_id changes, cells added later and motion across the boundary; broken
bonds raise the same SimulationInstability."""
import unittest

import numpy as np

import lbmd
import oif

BOX = 24.0
ALL = dict(ks=0.05, kb=0.08, kal=0.03, kag=0.6, kv=0.9, kvisc=0.04)
ALL_LINEAR = dict(ALL, ks=0.0, kslin=0.02)  # the oif package takes ks or kslin
TOL = 1e-12


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


def forces_and_normals(system, fast):
    core = system._core
    core.bonded_fast_path = fast
    core.compute_forces()
    parts = system.part.all()
    return parts.f.copy(), parts.normal.copy()


class FastPathMatchesGeneric(unittest.TestCase):
    def compare(self, system, label):
        f_fast, n_fast = forces_and_normals(system, True)
        f_gen, n_gen = forces_and_normals(system, False)
        system._core.bonded_fast_path = True  # integration goes on with the fast path
        scale = np.linalg.norm(f_gen, axis=1).max()
        self.assertGreater(scale, 0.0, label)
        err = np.linalg.norm(f_fast - f_gen, axis=1).max() / scale
        self.assertLessEqual(err, TOL, f"{label}: relative force difference {err:.2e}")
        n_err = np.linalg.norm(n_fast - n_gen, axis=1).max()
        self.assertLessEqual(n_err, TOL, f"{label}: normal difference {n_err:.2e}")
        return err

    def test_each_modulus_and_all(self):
        errors = {}
        # alone: each group by its own plan; local and global moduli together:
        # the fused pass (with and without the wings of bending)
        cases = {k: {k: v} for k, v in ALL_LINEAR.items() if v}
        cases.update(ks={"ks": ALL["ks"]}, all=ALL, all_linear=ALL_LINEAR,
                     kb_kv={"kb": ALL["kb"], "kv": ALL["kv"]},
                     ks_kal_kag={k: ALL[k] for k in ("ks", "kal", "kag")},
                     kvisc_kv={"kvisc": ALL["kvisc"], "kv": ALL["kv"]})
        for name, moduli in cases.items():
            system, cells = make(moduli)
            # the first cell straddles the box corner: folded positions on both sides
            folded = cells[0].particles.pos_folded
            self.assertTrue((folded[:, 0] < 2).any() and (folded[:, 0] > BOX - 2).any())
            errors[name] = self.compare(system, name)
        print("fast/generic relative force difference:",
              ", ".join(f"{k} {v:.1e}" for k, v in errors.items()))

    def test_many_cells_of_one_type(self):
        """Six cells of one type: the fused pass evaluates four of them
        together, one per vector lane (FusedMembranePlan::evaluate_batch),
        and the other two one at a time. The cells are deformed by different
        amounts, so that some lanes have dihedral deviations beyond the
        polynomial arctangent's 14 degrees and others not; one cell straddles
        the box corner; then a batched cell's mol_id changes (regroup)."""
        origins = ([0.4, BOX - 0.3, 0.2], [12.0, 11.0, 13.0], [6.0, 18.0, 6.0],
                   [18.0, 6.0, 18.0], [6.0, 6.0, 18.0], [18.0, 18.0, 6.0])
        noise = [0.01, 0.04, 0.15, 0.02, 0.08, 0.03]
        cases = dict(all=ALL, all_linear=ALL_LINEAR,
                     kb_kv={"kb": ALL["kb"], "kv": ALL["kv"]},
                     ks_kal_kag={k: ALL[k] for k in ("ks", "kal", "kag")},
                     kvisc_kv={"kvisc": ALL["kvisc"], "kv": ALL["kv"]})
        for name, moduli in cases.items():
            system, cells = make(moduli, origins=origins, noise=noise)
            self.compare(system, f"six cells, {name}")
        cells[2].particles.mol_id = 17
        self.compare(system, "six cells, a mol_id changed")
        system.integrator.run(20)
        self.compare(system, "six cells, 20 steps")

    def test_batch_equals_one_cell_pass(self):
        """Four cells of a type go through the fused pass together, one per
        vector lane, with the one-cell pass's arithmetic: each cell's forces
        and node normals are bit for bit those of the same cell alone in a
        system (evaluated one at a time). Fails also if the batch declines
        and the generic loop (other rounding) takes over."""
        origins = ([6.0, 6.0, 6.0], [18.0, 6.0, 6.0], [6.0, 18.0, 6.0], [6.0, 6.0, 18.0],
                   [18.0, 18.0, 18.0])
        system, cells = make(ALL, origins=origins, noise=[0.01, 0.04, 0.15, 0.02, 0.08])
        f_all, n_all = forces_and_normals(system, True)
        ids_all = np.asarray(system.part.all().id)
        for k, (cell, origin) in enumerate(zip(cells, origins)):
            alone, (single,) = make(ALL, origins=[origin])
            single.particles.pos = cell.particles.pos
            single.particles.v = cell.particles.v
            f_one, n_one = forces_and_normals(alone, True)
            mine = np.isin(ids_all, cell.mesh.part_ids)
            its = np.isin(np.asarray(alone.part.all().id), single.mesh.part_ids)
            self.assertTrue(np.array_equal(f_all[mine], f_one[its]), f"cell {k}: forces")
            self.assertTrue(np.array_equal(n_all[mine], n_one[its]), f"cell {k}: normals")

    def test_plan_follows_changes(self):
        # a milder deformation than make's default: 200 steps of it fold a
        # node so far that an edge shrinks to 2 % of its length, where the
        # bending of either path is ill-conditioned (~3e-12 apart)
        system, cells = make(ALL, seed=11, noise=0.01)
        system.thermostat.set_langevin(kT=0.0, gamma=0.5)
        system.part.all().ext_force = [0.05, -0.03, 0.02]
        system.integrator.run(200)  # fast path; the cells drift across the boundary
        self.assertTrue((np.abs(system.part.all().image_box) > 0).any())
        self.compare(system, "after 200 steps")
        # another cell numbering: the per-cell sums regroup
        cells[1].particles.mol_id = 7
        self.compare(system, "mol_id changed")
        cells[0].particles.mol_id = 7  # both cells one "cell": sums over both
        self.compare(system, "two cells, one mol_id")
        # mixed mol_ids within a cell: triangles of two "cells" share nodes
        # (the fast global forces decline, the generic loop evaluates them)
        n_nodes = len(cells[0].particles.id)
        cells[0].particles.mol_id = np.where(np.arange(n_nodes) % 2 == 0, 3, 7)
        self.compare(system, "mixed mol_ids in a cell")
        cells[0].particles.mol_id = 3
        system.part.by_id(0).remove()
        self.compare(system, "free particle removed")
        # a node removed (its bonds go with it; local indices move)
        system.part.by_id(int(cells[1].particles.id[5])).remove()
        self.compare(system, "node removed")
        system.integrator.run(20)
        self.compare(system, "node removed, 20 steps")
        # a cell added later: the groups' bonds grow, the plans rebuild
        oif.OifCell(cell_type=cells[0].cell_type, particle_type=0, origin=[6.0, 18.0, 6.0],
                    rotate=[0.3, 1.1, 0.2])
        self.compare(system, "cell added")
        system.integrator.run(20)
        self.compare(system, "cell added, 20 steps")

    def test_two_cell_types(self):
        """Two cell types (two pairs of groups, fused each with its own
        partner), their cells interleaved in id order, one across a corner
        of the box; the types' groups added in different orders."""
        rng = np.random.default_rng(7)
        system = lbmd.System(box_l=[BOX, BOX, BOX])
        system.time_step = 0.01
        system.cell_system.skin = 0.3
        rbc = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(3.0, 3.0, 3.0),
                              normal=True, **ALL)
        sphere = oif.OifCellType(*oif.mesh_files("sphere162"), system=system,
                                 resize=(2.5, 2.5, 2.5), normal=True,
                                 ks=0.03, kb=0.05, kal=0.02, kag=0.4, kv=0.7)
        cells = [oif.OifCell(cell_type=t, particle_type=0, origin=o, rotate=rng.uniform(0, 6, 3))
                 for t, o in ((sphere, [0.3, 0.2, BOX - 0.4]), (rbc, [12.0, 11.0, 13.0]),
                              (sphere, [12.0, 3.0, 6.0]), (rbc, [4.0, 16.0, 18.0]))]
        for cell in cells:
            x = cell.particles.pos
            cell.particles.pos = x + rng.normal(scale=0.03, size=x.shape)
            cell.particles.v = rng.normal(scale=0.1, size=x.shape)
        print(f"two cell types: relative force difference {self.compare(system, 'two types'):.1e}")
        system.integrator.run(30)
        self.compare(system, "two types, 30 steps")
        # four more cells of each type, interleaved: each type's fused pass
        # takes four of its six cells as a batch (evaluate_batch), the other
        # two one at a time
        for k in range(4):
            for t in (rbc, sphere):
                cell = oif.OifCell(cell_type=t, particle_type=0,
                                   origin=[3.0 + 5.0 * k, 8.0 if t is rbc else 20.0, 12.0],
                                   rotate=rng.uniform(0, 6, 3))
                x = cell.particles.pos
                cell.particles.pos = x + rng.normal(scale=0.03, size=x.shape)
        self.compare(system, "two types, six cells each")

    def test_cells_of_one_type_with_different_references(self):
        """The fused pass keeps one copy of the triangle and edge tables for
        the cells of a type that have them bit for bit equal; a cell whose
        bonds carry other references (here re-added by hand with 2 % longer
        relaxed edges) keeps its own, and both paths still agree."""
        # six cells: the five with equal tables give a batch of four (the
        # other cell must not be in it) and a single
        origins = ([0.4, BOX - 0.3, 0.2], [12.0, 11.0, 13.0], [6.0, 18.0, 6.0],
                   [18.0, 6.0, 18.0], [6.0, 6.0, 18.0], [18.0, 18.0, 6.0])
        system, cells = make(ALL, origins=origins)
        ct = cells[0].cell_type
        rows, per_bond = ct._local_rows()
        ids = cells[1].mesh.part_ids
        h = ct.local_force_interaction
        for row in ids[rows]:
            system.part.by_id(int(row[0])).delete_bond((h, *[int(x) for x in row[1:]]))
        longer = per_bond.copy()
        longer[:, 0] *= 1.02
        system.part.add_bonds(h, ids[rows], longer)
        f_fast, _ = forces_and_normals(system, True)
        self.compare(system, "one type, other references")
        # the second cell does feel the longer references (it is not given the first's)
        system2, cells2 = make(ALL, origins=origins)
        f_same, _ = forces_and_normals(system2, True)
        mine = np.isin(np.asarray(system.part.all().id), ids)
        self.assertGreater(np.abs(f_fast[mine] - f_same[mine]).max(), 1e-4)

    def test_bonds_by_hand(self):
        """Bonds added by hand: a strip of triangle pairs (an open mesh, so
        triangles in one or two bonds) with ks and kslin together and
        ESPResSo-style per-instance references, across the periodic boundary;
        a tetrahedron of OifGlobalForces + OifOutDirection triangles across a
        corner of the box."""
        from lbmd.interactions import OifGlobalForces, OifLocalForces, OifOutDirection
        rng = np.random.default_rng(3)
        system = lbmd.System(box_l=[6.0, 6.0, 6.0])
        system.time_step = 0.01
        system.cell_system.skin = 0.3
        # a zigzag strip: nodes 0..7 around x = 0 (= 6), triangles (i, i+1, i+2)
        strip = np.array([[0.5 * i - 1.7, 1.0 + 0.8 * (i % 2), 2.0] for i in range(8)])
        strip += rng.normal(scale=0.08, size=strip.shape)
        # unfolded positions, continuous over the cell as the integrator keeps
        # them (the cell sums of both paths need that); folded onto both sides
        tetra = np.array([[5.6, 5.7, 0.3], [6.5, 5.8, 0.1], [5.9, 6.6, 0.2], [6.0, 6.0, -0.6]])
        ids = system.part.add(pos=np.vstack([strip, tetra]), v=rng.normal(scale=0.2, size=(12, 3))).id
        local = OifLocalForces(r0=0.6, ks=0.05, kslin=0.03, phi0=2.9, kb=0.07, A01=0.2, A02=0.25,
                               kal=0.04, kvisc=0.02)
        system.bonded_inter.add(local)
        # pairs (i, i+1, i+2) and (i+1, i+2, i+3) share the edge (i+1, i+2): rows (B, A, C, D)
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
        print(f"bonds by hand: relative force difference {self.compare(system, 'bonds by hand'):.1e}")

    def test_broken_bond_raises_the_same(self):
        # a lone local group (own plan) and a cell type's pair (fused pass):
        # the fast path declines, the generic loop names the bond
        for moduli in (dict(ks=0.05, kb=0.08), ALL):
            system, cells = make(moduli)
            system._core.compute_forces()  # the plans are built
            # one edge's ends on top of each other: zero length
            edge = cells[1].mesh.edges[0]
            system.part.by_id(edge.B.part_id).pos = system.part.by_id(edge.A.part_id).pos
            messages = []
            for fast in (True, False):
                system._core.bonded_fast_path = fast
                with self.assertRaises(lbmd.SimulationInstability) as ctx:
                    system._core.compute_forces()
                messages.append(str(ctx.exception))
            self.assertEqual(messages[0], messages[1])
            self.assertIn("OifLocalForces", messages[0])


if __name__ == "__main__":
    unittest.main()
