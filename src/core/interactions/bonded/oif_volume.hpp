// OIF volume term (model eq. 7) on one triangle of a closed mesh.
// The cell volume is V = sum over triangles of a . (b x c) / 6 (positions
// relative to any common reference point; positive when the triangles are
// oriented with (b - a) x (c - a) pointing out of the cell). Its gradient with
// respect to a node is the sum over its triangles of (b - a) x (c - a) / 6 =
// S n / 3 (exact on a closed mesh), so the force
//   F(X) = -kv (|V| - V0) / V0 * s * S n / 3,   s = sign of the oriented V,
// is exactly -grad of E = kv/2 (|V| - V0)^2 / V0 for either orientation.
#pragma once

#include "utils/vector.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace pyoif::oif {

/** Oriented volume of the tetrahedron (reference, a, b, c), positions relative
 *  to the reference point. */
inline double tetra_volume(const Vec3& a, const Vec3& b, const Vec3& c) {
  return a.dot(b.cross(c)) / 6.0;
}

/** The force on each vertex of triangle (a, b, c); `volume` is the cell's
 *  oriented volume. */
inline Vec3 volume_force(const Vec3& a, const Vec3& b, const Vec3& c, double volume, double volume0,
                         double kv) {
  const double s = volume < 0.0 ? -1.0 : 1.0;
  const double dv = (s * volume - volume0) / volume0;
  // (b - a) x (c - a) / 6 = S n / 3
  return (-kv * dv * s / 6.0) * (b - a).cross(c - a);
}

inline double volume_energy(double volume, double volume0, double kv) {
  const double dv = std::abs(volume) - volume0;
  return 0.5 * kv * dv * dv / volume0;
}

} // namespace pyoif::oif
