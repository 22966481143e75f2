// OIF bending (model eq. 4) on a pair of triangles sharing an edge: the
// dihedral angle in ESPResSo/PyOIF's convention and its exact gradient, so the
// force is -grad of E = kb/2 (phi - phi0)^2.
//
// Points: b, c the shared edge; a the wing of triangle (a, b, c), d the wing of
// triangle (b, c, d) -- PyOIF's Angle(A, B, C, D) with A = a, B = b, C = c, D = d.
#pragma once

#include "utils/vector.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>

namespace pyoif::oif {

/** The angle between the triangles, in [0, 2 pi): pi for a flat pair, below pi
 *  when d lies on the side of N1 = (a - b) x (c - b) (PyOIF's
 *  angle_btw_triangles(a, b, c, d)). With a consistently oriented mesh the
 *  convex and concave bends are told apart, so phi0 may lie either side of pi. */
struct Dihedral {
  double phi = 0.0;
  std::array<Vec3, 4> grad; ///< d phi / d (a, b, c, d)
  bool valid = false;       ///< false for a degenerate triangle or edge
};

inline Dihedral dihedral(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Dihedral out;
  const Vec3 e = c - b;
  const Vec3 n1 = (a - b).cross(e);
  const Vec3 n2 = e.cross(d - b);
  const double l2 = e.squaredNorm(), n1_2 = n1.squaredNorm(), n2_2 = n2.squaredNorm();
  if (!(l2 > 0.0) || !(n1_2 > 0.0) || !(n2_2 > 0.0))
    return out;
  const double l = std::sqrt(l2);
  // psi: signed angle between the normals; sign from (n1 x n2) . e = l^2 n1 . (d - b)
  const double psi = std::atan2(n1.cross(n2).dot(e) / l, n1.dot(n2));
  out.phi = M_PI - psi;
  // Wings: moving a wing by delta along its triangle's normal turns the
  // triangle by delta / h, h = |n| / l its height over the edge (Blondel &
  // Karplus 1996; the Cimrak-Jancigova book's errata form of eq. 4).
  const Vec3 ga = -(l / n1_2) * n1;
  const Vec3 gd = -(l / n2_2) * n2;
  // Edge ends: translation and rotation invariance split each wing's term by
  // where its foot point lies on the edge (fraction t from b towards c).
  const double ta = (a - b).dot(e) / l2, td = (d - b).dot(e) / l2;
  out.grad = {ga, -(1.0 - ta) * ga - (1.0 - td) * gd, -ta * ga - td * gd, gd};
  out.valid = true;
  return out;
}

/** Bending of one triangle pair: forces on (a, b, c, d) and energy kb/2 dphi^2,
 *  dphi = phi - phi0 wrapped into (-pi, pi]. Returns false when degenerate. */
inline bool bending(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double phi0,
                    double kb, std::array<Vec3, 4>& f, double& energy) {
  const Dihedral g = dihedral(a, b, c, d);
  if (!g.valid)
    return false;
  double dphi = g.phi - phi0; // wrapped into (-pi, pi]: phi0 may come as [0, 2 pi] or beyond
  while (dphi > M_PI)
    dphi -= 2.0 * M_PI;
  while (dphi <= -M_PI)
    dphi += 2.0 * M_PI;
  for (int k = 0; k < 4; ++k)
    f[k] = -kb * dphi * g.grad[k];
  energy = 0.5 * kb * dphi * dphi;
  return true;
}

} // namespace pyoif::oif
