// OIF membrane terms on one edge AB (model eq. 3 and the membrane viscosity):
// neo-Hookean and linear stretching, and viscous damping of the relative
// velocity along the edge. Pure functions of two positions (and velocities):
// the force returned acts on A, the force on B is its negative.
#pragma once

#include "utils/vector.hpp"

#include <cmath>

namespace pyoif::oif {

/** Neo-Hookean stiffening factor kappa(lambda) of model eq. 3
 *  (Dupin et al. 2007, eq. 19): (lambda^0.5 + lambda^-2.5) / (lambda + lambda^-3),
 *  written as sqrt(lambda) (lambda^3 + 1) / (lambda^4 + 1) (one sqrt, no pow). */
inline double neo_hookean_kappa(double lambda) {
  const double l2 = lambda * lambda;
  return std::sqrt(lambda) * (l2 * lambda + 1.0) / (l2 * l2 + 1.0);
}

/** Integral of kappa(s) (s - 1) ds from 1 to lambda: the dimensionless energy of
 *  the neo-Hookean edge, E = ks l0^2 I(lambda), so that dE/dl = ks kappa (l - l0)
 *  exactly (eq. 3). With s = u^2 the integrand is the rational function
 *  2 (u^2 - 1) + 2 (u^2 - 1)^2 / (u^8 + 1), so
 *    I = 2 (u^3/3 - u + 2/3) + 2 J(u),  J(u) = int_1^u (t^2 - 1)^2 / (t^8 + 1) dt,
 *  J by composite 8-point Gauss-Legendre on pieces of length <= 1/8: the
 *  integrand's poles lie 0.38 off the real axis, so this is exact to round-off
 *  for any lambda > 0, at the cost of ~8 rational evaluations per edge near
 *  lambda = 1. */
inline double neo_hookean_energy_integral(double lambda) {
  static constexpr double node[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                     0.9602898564975363};
  static constexpr double weight[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                       0.1012285362903763};
  const double u = std::sqrt(lambda);
  const double span = u - 1.0;
  const int pieces = 1 + static_cast<int>(std::abs(span) * 8.0);
  const double h = span / pieces;
  double sum = 0.0;
  for (int k = 0; k < pieces; ++k) {
    const double mid = 1.0 + (k + 0.5) * h;
    for (int q = 0; q < 4; ++q)
      for (const double sgn : {-1.0, 1.0}) {
        const double t = mid + sgn * 0.5 * h * node[q];
        const double t2 = t * t, t4 = t2 * t2;
        sum += weight[q] * (t2 - 1.0) * (t2 - 1.0) / (t4 * t4 + 1.0);
      }
  }
  return 2.0 * (u * u * u / 3.0 - u + 2.0 / 3.0) + h * sum;
}

/** What a term on one edge gives: force on A (B gets -force) and energy. */
struct EdgeResult {
  Vec3 force_a = Vec3::Zero();
  double energy = 0.0;
};

/** Neo-Hookean stretching, eq. 3: F(A) = ks kappa(lambda) (l - l0) p_AB,
 *  E = ks l0^2 I(lambda). */
inline EdgeResult stretching_neo_hookean(const Vec3& a, const Vec3& b, double l0, double ks,
                                         bool with_energy = true) {
  const Vec3 ab = b - a;
  const double l = ab.norm();
  const double lambda = l / l0;
  // the energy quadrature costs more than the force: skipped in the time-step loop
  return {ks * neo_hookean_kappa(lambda) * (l - l0) / l * ab,
          with_energy ? ks * l0 * l0 * neo_hookean_energy_integral(lambda) : 0.0};
}

/** Linear stretching (eq. 3 with kappa = 1): F(A) = kslin (l - l0) p_AB,
 *  E = kslin/2 (l - l0)^2. */
inline EdgeResult stretching_linear(const Vec3& a, const Vec3& b, double l0, double kslin) {
  const Vec3 ab = b - a;
  const double l = ab.norm();
  return {kslin * (l - l0) / l * ab, 0.5 * kslin * (l - l0) * (l - l0)};
}

/** Membrane viscosity on the edge: F(A) = kvisc ((v_B - v_A) . e) e, e the unit
 *  edge vector: damps the relative velocity along the edge (ESPResSo's
 *  "variant B"); dissipative, no energy. */
inline EdgeResult edge_viscosity(const Vec3& a, const Vec3& b, const Vec3& va, const Vec3& vb,
                                 double kvisc) {
  const Vec3 ab = b - a;
  return {kvisc * (vb - va).dot(ab) / ab.squaredNorm() * ab, 0.0};
}

} // namespace pyoif::oif
