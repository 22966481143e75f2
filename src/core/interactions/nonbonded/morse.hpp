// Morse interaction, with ESPResSo's semantics (ESPResSo 4.2 user guide,
// "Morse interaction", doc/sphinx/inter_non-bonded.rst; Morse, Phys. Rev. 34,
// 57 (1929)): for r < cutoff
//   U(r) = eps (exp(-2 alpha (r - rmin)) - 2 exp(-alpha (r - rmin))) - shift,
//   shift = eps (exp(-2 alpha (cutoff - rmin)) - 2 exp(-alpha (cutoff - rmin))),
// so that U(cutoff) = 0; zero at and beyond the cutoff. The minimum, -eps
// (before the shift), is at r = rmin. Unlike soft_sphere there is no offset:
// the range is the cutoff itself. The force on i is
//   F_i = -U'(r) d/r = 2 eps alpha (e^2 - e) d/r,  e = exp(-alpha (r - rmin)),
// repulsive below rmin, attractive above.
#pragma once

#include "interactions/nonbonded/pair_context.hpp"

#include <cmath>

namespace pyoif {

struct Morse {
  static constexpr const char* name = "morse";
  struct Params {
    using Model = Morse;
    double eps = 0.0, alpha = 0.0, rmin = 0.0, cutoff = 0.0;
    double shift = 0.0; ///< U_unshifted(cutoff), derived by make()
    bool active() const { return cutoff > 0.0; }
    double range() const { return cutoff; }
  };

  /** Parameters with the energy shift derived from the others. */
  static Params make(double eps, double alpha, double rmin, double cutoff) {
    Params p{eps, alpha, rmin, cutoff, 0.0};
    p.shift = cutoff > 0.0 ? unshifted(p, cutoff) : 0.0;
    return p;
  }
  static double unshifted(const Params& p, double r) {
    const double e = std::exp(-p.alpha * (r - p.rmin));
    return p.eps * (e * e - 2.0 * e);
  }

  static double energy(const Params& p, const PairContext& c) {
    if (c.dist >= p.cutoff)
      return 0.0;
    return unshifted(p, c.dist) - p.shift;
  }
  /** Force on i: -dU/dr * d/|d| (no force at r = 0, where d has no direction). */
  static Vec3 force(const Params& p, const PairContext& c) {
    if (c.dist >= p.cutoff || c.dist <= 0.0)
      return Vec3::Zero();
    const double e = std::exp(-p.alpha * (c.dist - p.rmin));
    const double minus_du = 2.0 * p.eps * p.alpha * (e * e - e);
    return (minus_du / c.dist) * c.d;
  }
};

} // namespace pyoif
