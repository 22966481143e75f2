"""Contacts: two cells of one particle type pressed together do not
interpenetrate with membrane collision (they do without it); a cell pushed
against a wall keeps its nodes outside (soft sphere through a shape
constraint); self-cell exclusions leave the relaxed cell force-free."""
import unittest

import numpy as np

import lbmd
import oif
from oif import mesh_io

R = 3.0


def inside_fraction(points, nodes, outward_tris):
    """Fraction of points inside the closed surface (generalised winding
    number > 1/2, solid angles of the triangles, Van Oosterom & Strackee)."""
    a = nodes[outward_tris[:, 0]][None] - points[:, None]
    b = nodes[outward_tris[:, 1]][None] - points[:, None]
    c = nodes[outward_tris[:, 2]][None] - points[:, None]
    la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
    num = np.einsum("pij,pij->pi", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("pij,pij->pi", a, b) * lc + np.einsum("pij,pij->pi", b, c) * la \
        + np.einsum("pij,pij->pi", c, a) * lb
    w = (2 * np.arctan2(num, den)).sum(axis=1) / (4 * np.pi)
    return float(np.mean(w > 0.5))


class TestContacts(unittest.TestCase):

    def make_system(self):
        s = lbmd.System(box_l=[40.0, 30.0, 30.0])
        s.time_step = 0.1
        s.cell_system.skin = 0.5
        s.thermostat.set_langevin(kT=0.0, gamma=0.5)
        return s

    def two_cells(self, collide):
        s = self.make_system()
        ct = oif.OifCellType(*oif.mesh_files("sphere162"), system=s, resize=(R, R, R), ks=0.05, kb=0.02,
                             kal=0.05, kag=0.5, kv=3.0, normal=True)
        # one particle type for both: contacts act through the cells' ids
        c1 = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0 - R - 0.6, 15.0, 15.0])
        c2 = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0 + R + 0.6, 15.3, 15.2])
        if collide:
            s.non_bonded_inter[0, 0].membrane_collision.set_params(a=0.2, n=4.0, cutoff=1.0, offset=0.0)
        push = 1.0 / ct.mesh.get_n_nodes()  # total 1.0 on each cell, towards the other
        c1.set_force([push, 0.0, 0.0])
        c2.set_force([-push, 0.0, 0.0])
        return s, ct, c1, c2

    def overlap(self, ct, c1, c2):
        tris = mesh_io.outward(ct.mesh.triangle_ids)
        p1, p2 = c1.mesh.positions(), c2.mesh.positions()
        return max(inside_fraction(p1, p2, tris), inside_fraction(p2, p1, tris))

    def test_membrane_collision(self):
        s, ct, c1, c2 = self.two_cells(collide=True)
        worst = 0.0
        for _ in range(20):
            s.integrator.run(100)
            worst = max(worst, self.overlap(ct, c1, c2))
        self.assertEqual(worst, 0.0)
        # pressed into contact: the gap closed to the interaction range
        gap = np.min(np.linalg.norm(c1.mesh.positions()[:, None] - c2.mesh.positions()[None], axis=2))
        self.assertLess(gap, 1.0)
        self.assertGreater(gap, 0.0)
        # volumes held (the cells flatten against each other, kv keeps V)
        self.assertAlmostEqual(c1.volume() / ct.volume0, 1.0, delta=0.01)

    def test_without_collision_they_interpenetrate(self):
        s, ct, c1, c2 = self.two_cells(collide=False)
        s.integrator.run(2000)
        self.assertGreater(self.overlap(ct, c1, c2), 0.05)

    def wall_cell(self, repel):
        s = self.make_system()
        ct = oif.OifCellType(*oif.mesh_files("rbc162"), system=s, resize=(R, R, R), ks=0.05, kb=0.02,
                             kal=0.05, kag=0.5, kv=3.0)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0, 15.0, 5.0], rotate=(0.3, 0.2, 0.0))
        wall = lbmd.shapes.Wall(normal=[0, 0, 1], dist=2.0)
        s.constraints.add(shape=wall, particle_type=10, penetrable=not repel)
        if repel:
            s.non_bonded_inter[0, 10].soft_sphere.set_params(a=0.002, n=1.5, cutoff=0.8, offset=0.0)
        cell.set_force([0.0, 0.0, -1.0 / ct.mesh.get_n_nodes()])
        return s, ct, cell

    def test_cell_against_wall(self):
        s, ct, cell = self.wall_cell(repel=True)
        zmin = []
        for _ in range(20):
            s.integrator.run(100)
            zmin.append(cell.mesh.positions()[:, 2].min())
        self.assertGreater(min(zmin), 2.0)        # all nodes stay outside the wall
        self.assertLess(zmin[-1], 2.8)           # and it did get pushed onto it
        self.assertAlmostEqual(cell.volume() / ct.volume0, 1.0, delta=0.01)

    def test_without_wall_repulsion_nodes_cross(self):
        s, ct, cell = self.wall_cell(repel=False)
        s.integrator.run(2000)
        self.assertLess(cell.mesh.positions()[:, 2].min(), 2.0)

    def test_self_cell_exclusions(self):
        """A self-cell soft sphere whose range exceeds the mesh spacing leaves
        the relaxed cell force-free once neighbours within that range are
        excluded (self_cell_cutoff)."""
        s = self.make_system()
        ct = oif.OifCellType(*oif.mesh_files("rbc162"), system=s, resize=(R, R, R), ks=0.05)
        cut = 1.5 * ct.mesh.max_edge_length()
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.001, n=1.5, cutoff=cut, offset=0.0)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0, 15.0, 15.0], exclusion_neighbours=1,
                           self_cell_cutoff=cut)
        s.integrator.run(0, recalc_forces=True)
        self.assertLess(np.abs(cell.particles.f).max(), 1e-12)
        # control: excluding only the first neighbours, the soft sphere acts in the relaxed cell
        s = self.make_system()
        ct = oif.OifCellType(*oif.mesh_files("rbc162"), system=s, resize=(R, R, R), ks=0.05)
        s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.001, n=1.5, cutoff=cut, offset=0.0)
        cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0, 15.0, 15.0], exclusion_neighbours=1)
        s.integrator.run(0, recalc_forces=True)
        self.assertGreater(np.abs(cell.particles.f).max(), 1e-6)


if __name__ == "__main__":
    unittest.main()
