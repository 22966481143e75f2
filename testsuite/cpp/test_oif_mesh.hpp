// Test helper: closed triangle meshes built in the test (icospheres), their
// triangle pairs in PyOIF's Angle order, random rotations, and a System with
// one OIF cell. Used by test_oif_membrane.cpp and test_force_energy.cpp.
#pragma once

#include "interactions/membrane/bending.hpp"
#include "interactions/membrane/membrane_model.hpp"
#include "system/system.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace oif_test {

using pyoif::Vec3;

struct Mesh {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 3>> triangles; ///< outward: (b - a) x (c - a) points out
  /** PyOIF Angle(A, B, C, D): triangles ABC and BCD share the edge BC. */
  std::vector<std::array<int, 4>> angles;
  std::vector<std::array<int, 2>> edges;
};

/** Icosphere of radius r: the icosahedron with each triangle split in 4
 *  `level` times, new nodes pushed to the sphere. */
inline Mesh icosphere(int level, double r = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Mesh m;
  for (const auto& v : std::vector<Vec3>{{-1, t, 0},
                                         {1, t, 0},
                                         {-1, -t, 0},
                                         {1, -t, 0},
                                         {0, -1, t},
                                         {0, 1, t},
                                         {0, -1, -t},
                                         {0, 1, -t},
                                         {t, 0, -1},
                                         {t, 0, 1},
                                         {-t, 0, -1},
                                         {-t, 0, 1}})
    m.nodes.push_back(v.normalized());
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end())
        return it->second;
      m.nodes.push_back((m.nodes[a] + m.nodes[b]).normalized());
      const int id = static_cast<int>(m.nodes.size()) - 1;
      mid[key] = id;
      return id;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& tr : m.triangles) {
      const int a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
      next.push_back({tr[0], a, c});
      next.push_back({tr[1], b, a});
      next.push_back({tr[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  for (auto& v : m.nodes)
    v *= r;
  // triangle pairs: for the directed edge (B, C) of triangle (A, B, C) ... the
  // other triangle has the edge as (C, B); take each undirected edge once
  std::map<std::pair<int, int>, std::pair<int, int>> directed; // (u, v) -> (tri, opposite)
  for (int k = 0; k < static_cast<int>(m.triangles.size()); ++k)
    for (int e = 0; e < 3; ++e) {
      const auto& tr = m.triangles[k];
      directed[{tr[e], tr[(e + 1) % 3]}] = {k, tr[(e + 2) % 3]};
    }
  for (const auto& [uv, info] : directed) {
    const auto [u, v] = uv;
    if (u > v)
      continue;
    const int wing_uv = info.second;                // triangle (u, v, wing): A with edge u->v
    const int wing_vu = directed.at({v, u}).second; // triangle (v, u, wing)
    // Angle(A, B, C, D) = (wing_uv, u, v, wing_vu): triangles A u v and u v D
    m.angles.push_back({wing_uv, u, v, wing_vu});
    m.edges.push_back({u, v});
  }
  return m;
}

inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

/** Per-angle reference values (r0, phi0, A01, A02) of a mesh, as the oif
 *  package computes them (PyOIF's Angle conventions). */
inline std::vector<double> angle_references(const Mesh& m, const std::vector<Vec3>& x) {
  std::vector<double> ref;
  for (const auto& an : m.angles) {
    const Vec3 &a = x[an[0]], &b = x[an[1]], &c = x[an[2]], &d = x[an[3]];
    ref.push_back((c - b).norm());
    ref.push_back(pyoif::membrane::dihedral_angle(a, b, c, d));
    ref.push_back(0.5 * (b - a).cross(c - a).norm());
    ref.push_back(0.5 * (c - b).cross(d - b).norm());
  }
  return ref;
}

/** Bond rows (B, A, C, D) of the angles, particle ids = node index + first_id. */
inline std::vector<int> local_bond_ids(const Mesh& m, int first_id = 0) {
  std::vector<int> ids;
  for (const auto& an : m.angles)
    for (int k : {an[1], an[0], an[2], an[3]})
      ids.push_back(k + first_id);
  return ids;
}
inline std::vector<int> triangle_bond_ids(const Mesh& m, int first_id = 0, bool flip = false) {
  std::vector<int> ids;
  for (const auto& tr : m.triangles)
    for (int k : (flip ? std::array<int, 3>{tr[0], tr[2], tr[1]} : tr))
      ids.push_back(k + first_id);
  return ids;
}

inline std::shared_ptr<pyoif::System> make_system(double box = 50.0) {
  return std::make_shared<pyoif::System>(Vec3(box, box, box),
                                         std::array<bool, 3>{true, true, true});
}

/** Adds the nodes x as particles id0.. with mol_id `cell` (velocities v if given). */
inline void add_cell_particles(pyoif::System& s, const std::vector<Vec3>& x, int cell, int id0 = 0,
                               const std::vector<Vec3>* v = nullptr) {
  for (std::size_t i = 0; i < x.size(); ++i)
    s.add_particle(id0 + static_cast<int>(i), x[i], v ? (*v)[i] : Vec3::Zero(), 1.0, 0, cell,
                   Vec3::Zero(), 0);
}

/** Forces on particles id0 .. id0+n-1 after a force calculation. */
inline std::vector<Vec3> forces_of(pyoif::System& s, std::size_t n, int id0 = 0) {
  s.compute_forces();
  std::vector<Vec3> f(n);
  for (std::size_t i = 0; i < n; ++i)
    f[i] = s.particles.force[s.particles.index(id0 + static_cast<int>(i))];
  return f;
}

/** Unfolded positions of particles id0 .. id0+n-1. */
inline std::vector<Vec3> positions_of(const pyoif::System& s, std::size_t n, int id0 = 0) {
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const int k = s.particles.index(id0 + static_cast<int>(i));
    x[i] = s.box.unfolded(s.particles.pos[k], s.particles.image[k]);
  }
  return x;
}

/** (area, oriented volume) of the cells of triangle bond group `bond_id`,
 *  by the membrane component's analysis (the time step's driver). */
inline std::vector<std::pair<double, double>> cell_area_volume(pyoif::System& s, int bond_id) {
  pyoif::membrane::Selection select;
  select.bond_id = bond_id;
  std::vector<std::pair<double, double>> out;
  for (const auto& r :
       pyoif::membrane::analyse(s.bonded, select, s.particles, s.box, s.time, nullptr))
    out.emplace_back(r.area, r.volume);
  return out;
}

inline void set_positions(pyoif::System& s, const std::vector<Vec3>& x, int id0 = 0) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    const int k = s.particles.index(id0 + static_cast<int>(i));
    s.particles.pos[k] = x[i];
    s.particles.image[k].setZero();
  }
  s.cells.invalidate();
}

} // namespace oif_test
