"""Python API of the OIF interactions (lbmd.interactions.OifLocalForces,
OifGlobalForces, OifOutDirection, membrane_collision) and the engine's OIF
analysis calls (system._core.oif_cell_sums / oif_energies / oif_forces,
add_exclusions): parameter validation naming the parameter, ESPResSo-style
per-angle instances against one instance with per-bond reference values, and
the consistency of the per-term analysis with the integrator's forces."""
import unittest

import numpy as np

import lbmd
from lbmd.interactions import OifGlobalForces, OifLocalForces, OifOutDirection


# --- a small closed mesh, built here -----------------------------------------
def icosphere(level, radius):
    t = (1.0 + 5 ** 0.5) / 2.0
    nodes = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    nodes = [np.array(v, float) / np.linalg.norm(v) for v in nodes]
    tris = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
            (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
            (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid, new = {}, []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                v = nodes[a] + nodes[b]
                nodes.append(v / np.linalg.norm(v))
                mid[key] = len(nodes) - 1
            return mid[key]
        for a, b, c in tris:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        tris = new
    nodes = radius * np.array(nodes)
    tris = np.array(tris)
    # PyOIF's Angle(A, B, C, D): triangles ABC and BCD share the edge BC
    directed = {}
    for a, b, c in tris:
        directed[(a, b)], directed[(b, c)], directed[(c, a)] = c, a, b
    angles = np.array([(w, u, v, directed[(v, u)]) for (u, v), w in directed.items() if u < v])
    return nodes, tris, angles


def angle_btw_triangles(p1, p2, p3, p4):
    """PyOIF's oif_utils.angle_btw_triangles (common edge p2 p3), in [0, 2 pi)."""
    n1 = np.cross(p1 - p2, p3 - p2)
    n2 = np.cross(p3 - p2, p4 - p2)
    phi = np.pi - np.arccos(np.clip(n1 @ n2 / np.linalg.norm(n1) / np.linalg.norm(n2), -1, 1))
    return 2 * np.pi - phi if n1 @ (p4 - p1) < 0 else phi


def area(a, b, c):
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a))


def references(nodes, angles):
    """Per-angle (r0, phi0, A01, A02), PyOIF's definitions."""
    out = []
    for a, b, c, d in angles:
        A, B, C, D = nodes[a], nodes[b], nodes[c], nodes[d]
        out.append((np.linalg.norm(C - B), angle_btw_triangles(A, B, C, D), area(A, B, C),
                    area(D, B, C)))
    return np.array(out)


def surface_volume(x, tris):
    a, b, c = x[tris[:, 0]], x[tris[:, 1]], x[tris[:, 2]]
    s = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    v = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    return s, v


NODES, TRIS, ANGLES = icosphere(2, 3.0)
REF = references(NODES, ANGLES)
MODULI = dict(ks=0.05, kslin=0.01, kb=0.08, kal=0.03, kvisc=0.02)


def deformed(rng, centre):
    x = NODES * np.array([1.15, 0.9, 1.05]) + 0.08 * rng.uniform(-1, 1, NODES.shape)
    return x + centre


def new_system(box=30.0):
    s = lbmd.System(box_l=[box] * 3)
    s.time_step = 0.01
    return s


class Validation(unittest.TestCase):

    def assertNames(self, exc_type, fragment, fn, *args, **kw):
        with self.assertRaises(exc_type) as cm:
            fn(*args, **kw)
        self.assertIn(fragment, str(cm.exception))

    def test_local_forces_parameters(self):
        self.assertNames(ValueError, "'ks'", OifLocalForces, ks=-1.0)
        self.assertNames(ValueError, "'kvisc'", OifLocalForces, kvisc=-0.1)
        self.assertNames(ValueError, "'phi0'", OifLocalForces, phi0=7.0)
        self.assertNames(TypeError, "'kb'", OifLocalForces, kb="stiff")
        self.assertNames(TypeError, "'stiffness'", OifLocalForces, stiffness=1.0)
        b = OifLocalForces(r0=1.0, ks=0.1, kslin=0.0, phi0=3.0, kb=0.2, A01=0.4, A02=0.5, kal=0.3,
                           kvisc=0.0)
        self.assertEqual(b.get_params()["A02"], 0.5)  # reads back as set
        self.assertEqual(b.kb, 0.2)

    def test_global_forces_parameters(self):
        self.assertNames(TypeError, "'A0_g'", OifGlobalForces, ka_g=1.0, V0=1.0, kv=1.0)
        self.assertNames(ValueError, "'V0'", OifGlobalForces, A0_g=1.0, ka_g=1.0, V0=0.0, kv=1.0)
        self.assertNames(ValueError, "'kv'", OifGlobalForces, A0_g=1.0, ka_g=1.0, V0=1.0, kv=-1.0)
        self.assertNames(TypeError, "'x'", OifOutDirection, x=1)

    def test_per_bond_values(self):
        s = new_system()
        s.part.add(pos=NODES + 10)
        b = OifLocalForces(**MODULI)  # no reference values: per bond only
        s.bonded_inter.add(b)
        rows = ANGLES[:, [1, 0, 2, 3]]
        # without per_bond, the instance's r0 etc. are used: 0 is rejected by name
        self.assertNames(ValueError, "'r0'", s.part.add_bonds, b, rows)
        bad = REF.copy()
        bad[5, 2] = 0.0  # A01 of bond 5
        self.assertNames(ValueError, "'A01' of bond 5", s.part.add_bonds, b, rows, bad)
        bad = REF.copy()
        bad[1, 0] = np.nan
        self.assertNames(ValueError, "'r0'", s.part.add_bonds, b, rows, bad)
        self.assertNames(ValueError, "M×4", s.part.add_bonds, b, rows[:, :3], REF)
        s.part.add_bonds(b, rows, REF)
        self.assertEqual(len(s._core.get_bonds(0)), len(ANGLES))

    def test_membrane_collision_parameters(self):
        s = new_system()
        mc = s.non_bonded_inter[0, 1].membrane_collision
        self.assertNames(ValueError, "'a'", mc.set_params, a=-1.0, n=10.0, cutoff=0.5)
        self.assertNames(ValueError, "'n'", mc.set_params, a=1.0, n=0.0, cutoff=0.5)
        self.assertNames(TypeError, "'cutoff'", mc.set_params, a=1.0, n=10.0)
        mc.set_params(a=0.01, n=12.0, cutoff=0.4, offset=0.1)
        self.assertEqual(s.non_bonded_inter[1, 0].membrane_collision.get_params(),
                         dict(a=0.01, n=12.0, cutoff=0.4, offset=0.1))
        self.assertTrue(mc.is_active())
        self.assertAlmostEqual(s._core.max_range, 0.5)
        mc.deactivate()
        self.assertFalse(mc.is_active())

    def test_analysis_errors(self):
        s = new_system()
        s.part.add(pos=NODES + 10)
        h = lbmd.interactions.HarmonicBond(k=1.0, r_0=1.0)
        s.bonded_inter.add(h)
        g = OifGlobalForces(A0_g=1.0, ka_g=1.0, V0=1.0, kv=1.0)
        s.bonded_inter.add(g)
        s.part.add_bonds(g, TRIS)
        self.assertNames(ValueError, "not a triangle bond", s._core.oif_cell_sums, 0)
        self.assertNames(ValueError, "'global_area' and 'volume'", s._core.oif_forces, 1, "bending")
        self.assertNames(ValueError, "not OifLocalForces or OifGlobalForces", s._core.oif_energies, 0)
        self.assertNames(ValueError, "not registered", s._core.oif_forces, 7, "volume")
        self.assertNames(ValueError, "M×2", s._core.add_exclusions, np.zeros((3, 3), int))
        self.assertNames(ValueError, "from itself", s._core.add_exclusions, [[4, 4]])
        self.assertNames(ValueError, "does not exist", s._core.add_exclusions, [[4, 99999]])


class Forces(unittest.TestCase):

    def test_per_angle_instances_equal_bulk_per_bond(self):
        """ESPResSo's PyOIF made one OifLocalForces per angle, bonded on B with
        partners A, C, D; one instance with per-bond values must give the same
        forces (tolerance 1e-14 relative)."""
        rng = np.random.default_rng(5)
        x = deformed(rng, 15.0)
        v = rng.uniform(-1, 1, x.shape)  # loads the membrane viscosity
        forces = []
        for bulk in (False, True):
            s = new_system()
            s.part.add(pos=x, v=v)
            if bulk:
                b = OifLocalForces(**MODULI)
                s.bonded_inter.add(b)
                s.part.add_bonds(b, ANGLES[:, [1, 0, 2, 3]], REF)
            else:
                for (a, bb, c, d), (r0, phi0, a1, a2) in zip(ANGLES, REF):
                    inter = OifLocalForces(r0=r0, phi0=phi0, A01=a1, A02=a2, **MODULI)
                    s.bonded_inter.add(inter)
                    s.part.by_id(int(bb)).add_bond((inter, int(a), int(c), int(d)))
            s.integrator.run(0, recalc_forces=True)
            forces.append(s.part.all().f)
        scale = np.abs(forces[0]).max()
        self.assertGreater(scale, 1e-3)
        np.testing.assert_allclose(forces[1], forces[0], rtol=0, atol=1e-14 * scale)

    def test_relaxed_mesh_with_pyoif_angles_is_force_free(self):
        """phi0 from PyOIF's angle_btw_triangles matches the engine's angle."""
        s = new_system()
        s.part.add(pos=NODES + 15.0)
        b = OifLocalForces(**MODULI)
        s.bonded_inter.add(b)
        s.part.add_bonds(b, ANGLES[:, [1, 0, 2, 3]], REF)
        s.integrator.run(0, recalc_forces=True)
        self.assertLess(np.abs(s.part.all().f).max(), 1e-12)

    def test_cell_sums_energies_and_forces_consistent(self):
        """Two cells (mol_id 0 and 1) of one particle type: oif_cell_sums
        against numpy; the sum over terms of oif_forces equals the particle
        forces of integrator.run(0, recalc_forces=True) (rtol 1e-12); the sum
        over terms and cells of oif_energies equals the bonded energy."""
        rng = np.random.default_rng(11)
        s = new_system(box=20.0)
        n = len(NODES)
        xs = [deformed(rng, np.array([5.0, 5.0, 5.0])), deformed(rng, np.array([19.0, 10.0, 10.0]))]
        for cell, x in enumerate(xs):  # the second crosses the periodic x boundary
            s.part.add(pos=x, v=rng.uniform(-0.5, 0.5, x.shape), mol_id=cell)
        S0, V0 = surface_volume(NODES, TRIS)
        local = OifLocalForces(**MODULI)
        glob = OifGlobalForces(A0_g=S0, ka_g=0.6, V0=V0, kv=0.9)
        out = OifOutDirection()
        for b in (local, glob, out):
            s.bonded_inter.add(b)
        for cell in range(2):
            s.part.add_bonds(local, ANGLES[:, [1, 0, 2, 3]] + cell * n, REF)
            s.part.add_bonds(glob, TRIS + cell * n)
            s.part.add_bonds(out, TRIS + cell * n)
        ids, areas, volumes = s._core.oif_cell_sums(1)
        np.testing.assert_array_equal(ids, [0, 1])
        for cell, x in enumerate(xs):
            sv = surface_volume(x, TRIS)
            self.assertAlmostEqual(areas[cell], sv[0], delta=1e-12 * sv[0])
            self.assertAlmostEqual(volumes[cell], sv[1], delta=1e-12 * sv[1])
        # the same sums from the normals' bond group
        np.testing.assert_allclose(s._core.oif_cell_sums(2)[2], volumes, rtol=1e-15)

        s.integrator.run(0, recalc_forces=True)
        f_total = s.part.all().f
        f_terms = np.zeros_like(f_total)
        for bond_id, terms in ((0, ("stretching", "bending", "local_area", "visc")),
                               (1, ("global_area", "volume"))):
            for term in terms:
                fid, f = s._core.oif_forces(bond_id, term)
                np.testing.assert_array_equal(fid, np.arange(2 * n))
                self.assertGreater(np.abs(f).max(), 1e-6, term)
                f_terms[fid] += f
        np.testing.assert_allclose(f_terms, f_total, rtol=0, atol=1e-12 * np.abs(f_total).max())
        # oif_forces leaves the particle forces alone
        np.testing.assert_array_equal(s.part.all().f, f_total)
        # one cell's bonds only (mol_id): that cell's particles, the same forces
        for bond_id, term in ((0, "bending"), (1, "volume")):
            fid_all, f_all = s._core.oif_forces(bond_id, term)
            for cell in range(2):
                fid, f = s._core.oif_forces(bond_id, term, cell)
                np.testing.assert_array_equal(fid, np.arange(n) + cell * n)
                np.testing.assert_allclose(f, f_all[cell * n:(cell + 1) * n], rtol=0,
                                           atol=1e-15 * np.abs(f_all).max())
            self.assertEqual(len(s._core.oif_forces(bond_id, term, 7)[0]), 0)  # no such cell

        e = s.analysis.energy()
        e_local = s._core.oif_energies(0)
        e_global = s._core.oif_energies(1)
        self.assertEqual(set(e_local), {"stretching", "bending", "local_area"})
        self.assertEqual(set(e_global), {"global_area", "volume"})
        total = 0.0
        for terms in (e_local, e_global):
            for mols, values in terms.values():
                np.testing.assert_array_equal(mols, [0, 1])
                self.assertTrue(np.all(values > 0))
                total += values.sum()
        self.assertAlmostEqual(total, e["bonded"], delta=1e-12 * e["bonded"])
        for cell in range(2):  # one cell's bonds only: that cell's energies
            for bond_id, every in ((0, e_local), (1, e_global)):
                for term, (mols, values) in s._core.oif_energies(bond_id, cell).items():
                    np.testing.assert_array_equal(mols, [cell])
                    self.assertAlmostEqual(values[0], every[term][1][cell], delta=1e-14 * values[0])
        # volume energy per cell: kv/2 (V - V0)^2 / V0
        np.testing.assert_allclose(e_global["volume"][1], 0.45 * (volumes - V0) ** 2 / V0,
                                   rtol=1e-10)

    def test_normals_before_pair_forces(self):
        """The node normals seen by membrane_collision are those of the current
        positions: after moving a cell, one force calculation suffices."""
        s = new_system()
        s.part.add(pos=NODES + 15.0)
        out = OifOutDirection()
        s.bonded_inter.add(out)
        s.part.add_bonds(out, TRIS[:, [0, 2, 1]])  # PyOIF's inward order: still outward normals
        s.integrator.run(0, recalc_forces=True)
        normals = s.part.all().normal
        radial = NODES / np.linalg.norm(NODES, axis=1)[:, None]
        self.assertGreater(np.einsum("ij,ij->i", normals, radial).min(), np.cos(np.radians(3)))
        rot = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
        s.part.all().pos = NODES @ rot.T + 15.0
        s.integrator.run(0, recalc_forces=True)
        normals = s.part.all().normal
        self.assertGreater(np.einsum("ij,ij->i", normals, radial @ rot.T).min(),
                           np.cos(np.radians(3)))

    def test_collision_uses_current_normals(self):
        """The upstream weakness: membrane_collision must see the normals of
        the current positions, not those of the previous force calculation.
        Cell B touches A; between two force calculations B is turned by 180
        degrees about y. The second calculation must give the forces of a
        fresh system in the turned configuration (atol 1e-15). With the
        previous normals, B's nodes facing A would carry normals pointing
        away from A, parallel to A's, and the contact would be silent."""
        n = len(NODES)
        a_pos = NODES + [10.0, 15, 15]

        def build(b_pos):
            s = new_system()
            s.part.add(pos=a_pos, mol_id=0)
            s.part.add(pos=b_pos, mol_id=1)
            out = OifOutDirection()
            s.bonded_inter.add(out)
            s.part.add_bonds(out, np.vstack([TRIS, TRIS + n]))
            s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.01, n=10.0, cutoff=0.5)
            for _ in range(2):  # (twice: the normals of these positions exist either way)
                s.integrator.run(0, recalc_forces=True)
            return s

        turned = NODES @ np.diag([-1.0, 1.0, -1.0]) + [15.9, 15, 15]
        s = build(NODES + [15.9, 15, 15])
        s.part.all().pos = np.vstack([a_pos, turned])
        s.integrator.run(0, recalc_forces=True)
        fresh = build(turned)
        f = fresh.part.all().f
        self.assertLess(f[:n].sum(axis=0)[0], -1e-4)  # the contact pushes A away from B
        np.testing.assert_allclose(s.part.all().f, f, rtol=0, atol=1e-15)

    def test_membrane_collision_between_cells_of_one_type(self):
        """Two touching spheres of one particle type, told apart by mol_id: the
        contact pushes them apart (equal and opposite net forces); with both
        nodes in one cell there is no force."""
        s = new_system()
        n = len(NODES)
        s.part.add(pos=NODES + [10.0, 15, 15], mol_id=0)
        s.part.add(pos=NODES + [15.9, 15, 15], mol_id=1)
        out = OifOutDirection()
        s.bonded_inter.add(out)
        s.part.add_bonds(out, np.vstack([TRIS, TRIS + n]))
        s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.01, n=10.0, cutoff=0.5)
        s.integrator.run(0, recalc_forces=True)
        f = s.part.all().f
        f1, f2 = f[:n].sum(axis=0), f[n:].sum(axis=0)
        self.assertLess(f1[0], 0.0)
        np.testing.assert_allclose(f1 + f2, 0.0, atol=1e-15)
        # one cell only (same mol_id): no membrane-collision force
        s.part.all().mol_id = np.zeros(2 * n)
        s.integrator.run(0, recalc_forces=True)
        self.assertEqual(np.abs(s.part.all().f).max(), 0.0)

    def test_bulk_exclusions(self):
        s = new_system()
        s.part.add(pos=[[5, 5, 5], [5.5, 5, 5], [6, 5, 5], [5, 5.5, 5]])
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=1.0, n=2.0, cutoff=1.0)
        before = set(s.cell_system.get_pairs(0.9))
        s._core.add_exclusions(np.array([[0, 1], [2, 1]]))
        after = set(s.cell_system.get_pairs(0.9))
        self.assertEqual(before - after, {(0, 1), (1, 2)})
        self.assertIn((0, 3), after)


if __name__ == "__main__":
    unittest.main()
