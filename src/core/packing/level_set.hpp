// The signed distance of a closed triangulated surface on a regular grid
// (a level set, negative inside), sampled by trilinear interpolation with
// its gradient. The rigid packer (rigid_packer.hpp) tests a body's nodes
// against another body's level set: one lookup per node instead of a
// search over triangles (the level-set discrete-element idea of Kawamoto,
// Andò, Viggiani & Andrade, J. Mech. Phys. Solids 91, 1 (2016)).
#pragma once

#include "utils/vector.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <vector>

namespace pyoif::packing {

/** Closest point of triangle (a, b, c) to p, by the Voronoi regions of its
 *  vertices, edges and face (Ericson, Real-Time Collision Detection, 2005,
 *  sec. 5.1.5). */
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/** Winding number of a closed, outward-oriented surface about p: 1 inside,
 *  0 outside; the solid angle of each triangle over 4 pi (Van Oosterom &
 *  Strackee, IEEE Trans. Biomed. Eng. 30, 125 (1983)). */
double winding_number(const Vec3& p, const std::vector<Vec3>& nodes,
                      const std::vector<std::array<int, 3>>& triangles);

class LevelSet {
public:
  /** Grid of the given spacing over the surface's box padded by `band`;
   *  exact distances within `band` of the surface, `band` beyond (so band
   *  must cover every interior point: at least half the body's thinnest
   *  width). The sign comes from ray parity along z per grid column. */
  LevelSet(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& triangles,
           double spacing, double band);
  /** Signed distance at p (>= band outside the grid) and, if grad is given,
   *  its gradient (zero outside the grid). */
  double sample(const Vec3& p, Vec3* grad) const;
  const Vec3& lower() const { return m_lo; }
  const Vec3& upper() const { return m_hi; }
  double band() const { return m_band; }
  double spacing() const { return m_h; }

private:
  double at(int i, int j, int k) const {
    return m_phi[(static_cast<std::size_t>(k) * m_n[1] + j) * m_n[0] + i];
  }
  Vec3 m_lo, m_hi;
  double m_h, m_inv_h, m_band;
  std::array<int, 3> m_n;
  std::vector<float> m_phi;
};

inline double LevelSet::sample(const Vec3& p, Vec3* grad) const {
  const Vec3 u = (p - m_lo) * m_inv_h;
  int idx[3];
  double f[3];
  for (int d = 0; d < 3; ++d) {
    if (!(u[d] >= 0.0 && u[d] <= m_n[d] - 1)) {
      if (grad)
        grad->setZero();
      return m_band;
    }
    idx[d] = std::min(static_cast<int>(u[d]), m_n[d] - 2);
    f[d] = u[d] - idx[d];
  }
  const int i = idx[0], j = idx[1], k = idx[2];
  const double c000 = at(i, j, k), c100 = at(i + 1, j, k), c010 = at(i, j + 1, k),
               c110 = at(i + 1, j + 1, k), c001 = at(i, j, k + 1), c101 = at(i + 1, j, k + 1),
               c011 = at(i, j + 1, k + 1), c111 = at(i + 1, j + 1, k + 1);
  const double fx = f[0], fy = f[1], fz = f[2];
  const double c00 = c000 + fx * (c100 - c000), c10 = c010 + fx * (c110 - c010);
  const double c01 = c001 + fx * (c101 - c001), c11 = c011 + fx * (c111 - c011);
  const double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  if (grad) {
    const double gx0 = (1 - fy) * (c100 - c000) + fy * (c110 - c010);
    const double gx1 = (1 - fy) * (c101 - c001) + fy * (c111 - c011);
    (*grad)[0] = ((1 - fz) * gx0 + fz * gx1) * m_inv_h;
    (*grad)[1] = ((1 - fz) * (c10 - c00) + fz * (c11 - c01)) * m_inv_h;
    (*grad)[2] = (c1 - c0) * m_inv_h;
  }
  return c0 + fz * (c1 - c0);
}

} // namespace pyoif::packing
