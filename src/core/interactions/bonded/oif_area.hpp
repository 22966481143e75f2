// OIF area terms on one triangle: local area (model eq. 5) and a triangle's
// share of global area (eq. 6). Both distribute the restoring force towards the
// centroid T, proportionally to each vertex's distance from it (Jancigova &
// Cimrak 2015, "Non-uniform force allocation for area preservation in spring
// network models", Int. J. Numer. Meth. Biomed. Engng., doi:10.1002/cnm.2757):
//   F(X) = c * vec(XT) / (t_a^2 + t_b^2 + t_c^2),
// which is force- and torque-free. This allocation is not the gradient of a
// function of the area; the energies below are the work the forces do along a
// dilation of the triangle (of the cell, for global area), the only motion
// along which they are conservative. They are for analysis only.
#pragma once

#include "utils/vector.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>

namespace pyoif::oif {

inline double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

/** F(X) = coefficient * vec(XT) / sum |XT|^2 for X = a, b, c. Adds to f. */
inline void add_centroid_allocated(const Vec3& a, const Vec3& b, const Vec3& c, double coefficient,
                                   Vec3& fa, Vec3& fb, Vec3& fc) {
  const Vec3 t = (a + b + c) / 3.0;
  const Vec3 ma = t - a, mb = t - b, mc = t - c;
  const double scale = coefficient / (ma.squaredNorm() + mb.squaredNorm() + mc.squaredNorm());
  fa += scale * ma;
  fb += scale * mb;
  fc += scale * mc;
}

/** Local area, eq. 5: coefficient kal (S - S0). Energy along a dilation:
 *  dE/dS = kal (S - S0) / (2 S)  =>  E = kal/2 (S - S0 - S0 ln(S/S0)). */
inline double local_area_coefficient(double area, double area0, double kal) {
  return kal * (area - area0);
}
inline double local_area_energy(double area, double area0, double kal) {
  return 0.5 * kal * (area - area0 - area0 * std::log(area / area0));
}

/** Global area, eq. 6, one triangle of area S of a cell of area S_cell:
 *  coefficient kag (S_cell - S_cell0) S / S_cell0. Energy of the cell along a
 *  dilation: dE/dS_cell = kag (S_cell - S_cell0) / (2 S_cell0)
 *  =>  E = kag (S_cell - S_cell0)^2 / (4 S_cell0). */
inline double global_area_coefficient(double area, double cell_area, double cell_area0,
                                      double kag) {
  return kag * (cell_area - cell_area0) * area / cell_area0;
}
inline double global_area_energy(double cell_area, double cell_area0, double kag) {
  const double ds = cell_area - cell_area0;
  return 0.25 * kag * ds * ds / cell_area0;
}

} // namespace pyoif::oif
