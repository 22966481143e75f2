// Stretching of a membrane edge, the model's eq. 3 (doc/model.md): the force
// on the edge's first node A, with p the unit vector from A to B, l the
// length, l0 the relaxed length and lambda = l / l0, is
//   neo-Hookean:  F(A) = ks kappa(lambda) (l - l0) p,
//                 kappa(lambda) = (lambda^0.5 + lambda^-2.5) / (lambda + lambda^-3)
//                 (M. M. Dupin et al., Phys. Rev. E 75, 066707, 2007, eq. 19),
//   linear:       F(A) = kslin (l - l0) p,
// and F(B) = -F(A). Energies: E = ks l0^2 I(lambda) with I the integral of
// kappa(s) (s - 1) from 1 to lambda, so that dE/dl = ks kappa (l - l0)
// exactly, and E = kslin/2 (l - l0)^2.
#pragma once

#include "interactions/membrane/lanes.hpp"

namespace pyoif::membrane {

/** One edge's stretching: the moduli and the relaxed length l0. */
struct StretchingParams {
  double ks = 0.0;     ///< neo-Hookean modulus
  double kslin = 0.0;  ///< linear modulus
  double l0 = 1.0;     ///< relaxed length
  double inv_l0 = 1.0; ///< 1 / l0 (lambda = l / l0 without a division)
};

/** kappa's denominator lambda^4 + 1 (kappa written as sqrt(lambda)
 *  (lambda^3 + 1) / (lambda^4 + 1): one square root, no pow), for the
 *  edge's shared division (FourReciprocals). */
template <class T> inline T neo_hookean_denominator(T lambda) {
  const T lambda2 = lambda * lambda;
  return lambda2 * lambda2 + 1.0;
}

/** The coefficient c of the force c (B - A) on A: eq. 3 divided by l, for
 *  the moduli that are on (neo: ks may be non-zero). lambda = l / l0,
 *  inv_l2 = 1 / l^2, inv_kappa_denominator = 1 / neo_hookean_denominator.
 *  With energy (not null), the edge's energy is added to it. */
template <bool neo, class T>
inline T stretching_coefficient(const StretchingParams& p, T l, T lambda, T inv_l2,
                                T inv_kappa_denominator, T* energy = nullptr);

/** I(lambda) = integral of kappa(s) (s - 1) ds from 1 to lambda. With s = u^2
 *  the integrand is the rational function 2 (u^2 - 1) + 2 (u^2 - 1)^2 /
 *  (u^8 + 1), so I = 2 (u^3/3 - u + 2/3) + 2 J(u), J(u) = integral of
 *  (t^2 - 1)^2 / (t^8 + 1) dt from 1 to u, by composite 8-point
 *  Gauss-Legendre on pieces of length <= 1/8: the integrand's poles lie 0.38
 *  off the real axis, so this is exact to round-off for any lambda > 0. */
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

/** The edge's stretching energy (the quadrature costs more than the force:
 *  analysis only). */
inline double stretching_energy(const StretchingParams& p, double l) {
  double e = 0.5 * p.kslin * (l - p.l0) * (l - p.l0);
  if (p.ks != 0.0)
    e += p.ks * p.l0 * p.l0 * neo_hookean_energy_integral(l * p.inv_l0);
  return e;
}

template <bool neo, class T>
inline T stretching_coefficient(const StretchingParams& p, T l, T lambda, T inv_l2,
                                T inv_kappa_denominator, T* energy) {
  const T stretch = (l - p.l0) * l * inv_l2; // (l - l0) / l
  T c = p.kslin * stretch;
  if constexpr (neo)
    c += p.ks * (sqrt_of(lambda) * (lambda * lambda * lambda + 1.0) * inv_kappa_denominator) *
         stretch;
  if (energy)
    for (int j = 0; j < lanes_of<T>; ++j)
      set_lane(*energy, j, lane(*energy, j) + stretching_energy(p, lane(l, j)));
  return c;
}

} // namespace pyoif::membrane
