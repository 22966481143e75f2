// Area conservation of a membrane, the model's eqs. 5 (local area, per
// triangle) and 6 (global area, per cell) (doc/model.md). Both allocate the
// restoring force of a triangle ABC towards its centroid T, each vertex in
// proportion to its distance from it:
//   F(X) = c (T - X) / (t_a^2 + t_b^2 + t_c^2),   X = A, B, C,
// (I. Jancigova, I. Cimrak, Int. J. Numer. Meth. Biomed. Eng. 32, e02757,
// 2016: non-uniform allocation), which is force- and torque-free, with
//   local area:  c = kal (S - S0),
//   global area: c = kag (S_cell - S_cell0) / S_cell0 * S.
// This allocation is not the gradient of a function of the area; the
// energies below are the work the forces do along a dilation of the triangle
// (local) or of the cell (global), the only motion along which they are
// conservative: for analysis only.
#pragma once

#include "interactions/membrane/lanes.hpp"

#include <cmath>

namespace pyoif::membrane {

/** One triangle's local area (eq. 5), summed over the bonds that have it:
 *  each triangle is in three pairs of triangles, each applying a third of
 *  kal (S - S0) (ESPResSo's convention: on a closed mesh eq. 5 once per
 *  triangle), so kal_weight = sum of kal / 3 and kal_area0 = sum of kal S0 /
 *  3 over them, and the coefficient is kal_weight S - kal_area0. */
struct LocalAreaParams {
  double kal_weight = 0.0;
  double kal_area0 = 0.0;
};
/** A cell's global area (eq. 6); T: double, or Lanes for four cells. */
template <class T = double> struct GlobalAreaParams {
  T kag{};
  T area0{}; ///< the cell's relaxed surface S_cell0 (> 0 where kag is not 0)
};

/** Component d of the centroid's offsets from the vertices: T - A = (e1 +
 *  e2) / 3, T - B = (T - A) - e1, T - C = (T - A) - e2. */
template <class T> struct CentroidOffsets {
  T a, b, c;
  CentroidOffsets(T e1, T e2) : a((e1 + e2) * (1.0 / 3.0)), b(a - e1), c(a - e2) {}
};

/** One triangle of a cell: edge vectors e1 = B - A, e2 = C - A and its first
 *  vertex ra relative to the cell's volume reference point. N = e1 x e2
 *  (|N| = 2 S), its area S, the volume term ra.N (eq. 7: V = sum of ra.N / 6),
 *  and the centroid allocation's scale: vertex X gets c (T - X) inv_moment,
 *  inv_moment = 1 / sum over the vertices of |T - X|^2. */
template <class T> struct TriangleGeometry {
  T n[3], area, volume_term, inv_moment;
  TriangleGeometry(const T (&e1)[3], const T (&e2)[3], const T (&ra)[3]) {
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    area = 0.5 * sqrt_of(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    volume_term = ra[0] * n[0] + ra[1] * n[1] + ra[2] * n[2];
    T moment{};
    for (int d = 0; d < 3; ++d) {
      const CentroidOffsets<T> m(e1[d], e2[d]);
      moment += m.a * m.a + m.b * m.b + m.c * m.c;
    }
    // a triangle collapsed to a point has no direction to allocate along:
    // no area force (not NaN; where its terms are on, the pass names it)
    inv_moment = select<T>(moment > T{}, 1.0 / moment, T{});
  }
};

/** eq. 5's coefficient over the centroid moment: (kal_weight S - kal_area0)
 *  inv_moment. With energy (not null), the triangle's local area energy
 *  along its dilation is added to it: dE/dS = kal (S - S0) / (2 S), so E =
 *  kal/2 (S - S0 - S0 ln(S / S0)), kal = kal_weight, S0 = kal_area0 /
 *  kal_weight. */
template <class T>
inline T local_area_coefficient(const LocalAreaParams& p, T area, T inv_moment,
                                T* energy = nullptr) {
  if (energy && p.kal_weight != 0.0) {
    const double area0 = p.kal_area0 / p.kal_weight;
    for (int j = 0; j < lanes_of<T>; ++j) {
      const double s = lane(area, j);
      set_lane(*energy, j,
               lane(*energy, j) + 0.5 * p.kal_weight * (s - area0 - area0 * std::log(s / area0)));
    }
  }
  return (p.kal_weight * area - p.kal_area0) * inv_moment;
}

/** The cell's factor of eq. 6: each triangle's global area force is this
 *  factor times S inv_moment (T - X). Zero where kag is. With energy (not
 *  null), the cell's global area energy along its dilation: dE/dS = kag (S -
 *  S0) / (2 S0), so E = kag (S - S0)^2 / (4 S0). */
template <class T>
inline T global_area_factor(const GlobalAreaParams<T>& p, T cell_area, T* energy = nullptr) {
  const Mask<T> on = p.kag != T{};
  const T area0 = select<T>(on, p.area0, splat<T>(1.0));
  const T ds = cell_area - area0;
  if (energy)
    *energy = select<T>(on, 0.25 * p.kag * ds * ds / area0, T{});
  return select<T>(on, p.kag * ds / area0, T{});
}

} // namespace pyoif::membrane
