// Soft-sphere repulsion, model eq. 8: V(r) = a (r - offset)^-n for
// r - offset < cutoff (ESPResSo's convention: the range is cutoff + offset).
// Used between particles and, through shape constraints, between a node and a wall.
#pragma once

#include "interactions/nonbonded/pair_context.hpp"

#include <cmath>

namespace pyoif {

struct SoftSphere {
  static constexpr const char* name = "soft_sphere";
  struct Params {
    using Model = SoftSphere;
    double a = 0.0, n = 0.0, cutoff = 0.0, offset = 0.0;
    bool active() const { return cutoff > 0.0; }
    double range() const { return cutoff + offset; }
  };

  /** Zero where the force is (at or inside the offset, where the potential
   *  is singular: no inf or NaN in an energy sum). */
  static double energy(const Params& p, const PairContext& c) {
    if (c.dist >= p.range() || c.dist <= p.offset)
      return 0.0;
    return p.a * std::pow(c.dist - p.offset, -p.n);
  }
  /** Force on i: -dV/dr * d/|d|. */
  static Vec3 force(const Params& p, const PairContext& c) {
    if (c.dist >= p.range() || c.dist <= p.offset)
      return Vec3::Zero();
    const double r_off = c.dist - p.offset;
    const double magnitude = p.n * p.a * std::pow(r_off, -(p.n + 1.0));
    return (magnitude / c.dist) * c.d;
  }
};

} // namespace pyoif
