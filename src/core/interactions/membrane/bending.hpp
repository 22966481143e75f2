// Bending of a pair of triangles ABC and BCD sharing the edge BC, the model's
// eq. 4 (doc/model.md) in its exact-gradient form (ESPResSo 4.2, the
// Cimrak-Jancigova book's errata): E = kb/2 (phi - phi0)^2 and F = -grad E,
//   F(A) = kb dphi |BC| n1 / |n1|^2,   F(D) = kb dphi |BC| n2 / |n2|^2,
// n1 = (A - B) x (C - B), n2 = (C - B) x (D - B); the edge ends B and C take
// -F(A) and -F(D) split by where the wings' foot points lie on the edge
// (translation and rotation invariance; Blondel & Karplus 1996).
//
// phi is PyOIF's angle between the triangles (angle_btw_triangles): pi for a
// flat pair, below pi when D lies on the side of n1, in [0, 2 pi). It is
// written here once, as pi - psi with psi = atan2(y, x), y = |BC| n1.(D - B)
// = (n1 x n2).(C - B) / |BC| and x = n1.n2; the time step takes the deviation
// dphi = phi - phi0 directly as one angle, (y, x) turned by psi0 = pi - phi0.
#pragma once

#include "interactions/membrane/lanes.hpp"
#include "utils/vector.hpp"

#include <cmath>

namespace pyoif::membrane {

/** One pair's bending: the modulus and the relaxed angle, kept as psi0 = pi -
 *  phi0 (cos psi0 = -cos phi0, sin psi0 = sin phi0) for the deviation. */
struct BendingParams {
  double kb = 0.0;
  double cos_psi0 = -1.0, sin_psi0 = 0.0; ///< phi0 = pi: a flat pair
  static BendingParams of(double kb, double phi0) { return {kb, -std::cos(phi0), std::sin(phi0)}; }
};

/** The wings' normals n1 = u x e (triangle ABC) and n2 = e x w (BCD) of the
 *  edge e = C - B with u = A - B, w = D - B; |n| is twice the area. */
template <class T> struct Wings {
  T n1[3], n2[3], n1_2, n2_2;
  Wings(const T (&e)[3], const T (&u)[3], const T (&w)[3]) {
    n1[0] = u[1] * e[2] - u[2] * e[1], n1[1] = u[2] * e[0] - u[0] * e[2],
    n1[2] = u[0] * e[1] - u[1] * e[0];
    n2[0] = e[1] * w[2] - e[2] * w[1], n2[1] = e[2] * w[0] - e[0] * w[2],
    n2[2] = e[0] * w[1] - e[1] * w[0];
    n1_2 = n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2];
    n2_2 = n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2];
  }
  /** (y, x) of psi = atan2(y, x) = pi - phi (l = |e|). */
  T y(T l, const T (&w)[3]) const { return l * (n1[0] * w[0] + n1[1] * w[1] + n1[2] * w[2]); }
  T x() const { return n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]; }
};

/** PyOIF's angle phi of the pair (a, b, c, d) from positions: the reference
 *  angle phi0 of a relaxed mesh (the oif package asks for it through
 *  lbmd._lbmd.membrane_angles). */
inline double dihedral_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double e[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
  const double u[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  const double w[3] = {d[0] - b[0], d[1] - b[1], d[2] - b[2]};
  const Wings<double> g(e, u, w);
  const double l = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  return M_PI - std::atan2(g.y(l, w), g.x());
}

/** (sine, cosine) of the deviation's angle psi - psi0 (times |n1| |n2| l):
 *  (y, x) turned by psi0 = pi - phi0, cos psi0 = -cos phi0, sin psi0 = sin phi0. */
template <class T> struct Deviation {
  T sine, cosine;
  Deviation(const BendingParams& p, T y, T x)
      : sine(y * p.cos_psi0 - x * p.sin_psi0), cosine(x * p.cos_psi0 + y * p.sin_psi0) {}
  /** Whether the polynomial arctangent covers the deviation (|tan| <= 1/4,
   *  deviations below 14 degrees: most of a membrane's). */
  Mask<T> small() const { return (cosine > T{}) & (abs_of(sine) <= 0.25 * cosine); }
};
template <> inline Mask<double> Deviation<double>::small() const {
  return cosine > 0.0 && std::abs(sine) <= 0.25 * cosine;
}

/** atan(t) for |t| <= 1/4: t P(t^2), P the Chebyshev economisation on
 *  [0, 1/16] of the Taylor series of atan(sqrt s)/sqrt s, derived in exact
 *  rational arithmetic (dropped terms < 5e-18; largest relative error
 *  against libm's atan on 2e5 random points 2.2e-16). Branch-free. */
template <class T> inline T atan_small(T t) {
  const T s = t * t;
  T pz = splat<T>(0.04599761088928747);
  pz = pz * s - 0.06523656687585018;
  pz = pz * s + 0.07683492919828101;
  pz = pz * s - 0.09090589248444612;
  pz = pz * s + 0.11111104259672454;
  pz = pz * s - 0.1428571420303533;
  pz = pz * s + 0.19999999999499324;
  pz = pz * s - 0.33333333333332166;
  pz = pz * s + 1.0;
  return t * pz;
}

/** dphi = phi - phi0 in (-pi, pi]: the polynomial where the deviation is
 *  small (tangent = sine / cosine there), std::atan2 in the other lanes. */
template <class T> inline T bending_deviation(const Deviation<T>& d, Mask<T> small, T tangent) {
  T dphi = -atan_small(select<T>(small, tangent, T{}));
  if (any_lane<T>(~small))
    for (int j = 0; j < lanes_of<T>; ++j)
      if (!lane_set<T>(small, j)) {
        const double large = -std::atan2(lane(d.sine, j), lane(d.cosine, j));
        set_lane(dphi, j, large <= -M_PI ? large + 2.0 * M_PI : large);
      }
  return dphi;
}
template <>
inline double bending_deviation(const Deviation<double>& d, bool small, double tangent) {
  if (small)
    return -atan_small(tangent);
  const double large = -std::atan2(d.sine, d.cosine);
  return large <= -M_PI ? large + 2.0 * M_PI : large;
}

/** The factors of the bending forces: F(A) = ca n1, F(D) = cd n2, and the
 *  foot points ta, td of A and D along the edge (fractions from B to C).
 *  inv_n1n2 = 1 / (|n1|^2 |n2|^2), inv_l2 = 1 / l^2. With energy (not
 *  null), kb/2 dphi^2 is added to it. */
template <class T> struct BendingFactors {
  T ca, cd, ta, td;
  BendingFactors() = default;
  BendingFactors(const BendingParams& p, T dphi, T l, T inv_n1n2, const Wings<T>& g, T inv_l2,
                 const T (&e)[3], const T (&u)[3], const T (&w)[3], T* energy = nullptr) {
    if (energy)
      *energy += 0.5 * p.kb * dphi * dphi;
    const T c = p.kb * dphi * l * inv_n1n2;
    ca = c * g.n2_2;
    cd = c * g.n1_2;
    ta = (u[0] * e[0] + u[1] * e[1] + u[2] * e[2]) * inv_l2;
    td = (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) * inv_l2;
  }
  /** Component d of the forces on A, B, C, D, with fe the edge force on B
   *  (stretching, viscosity; C gets -fe) and n1, n2 the normals' component d. */
  void forces(T fe, T n1, T n2, T& fa, T& fb, T& fc, T& fd) const {
    fa = ca * n1;
    fd = cd * n2;
    fb = fe - ((1.0 - ta) * fa + (1.0 - td) * fd);
    fc = -fe - (ta * fa + td * fd);
  }
};

} // namespace pyoif::membrane
