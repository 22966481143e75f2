// Membrane collision between nodes of different cells, model eq. 9:
//   V(d) = a / (1 + e^(n d)),  d = r - offset,  for r < cutoff + offset.
// Semantics follow ESPResSo's membrane_collision.hpp (object-in-fluid): the
// pair acts only between nodes of different cells (mol_i != mol_j) and needs
// both nodes' outward normals (OifOutDirection); the normals decide whether the
// membranes have crossed. With u = n_i - n_j, two membranes facing each other
// have u . (x_i - x_j) < 0 (i's outward normal points at j); if instead
// u . (x_i - x_j) > 0, node i has passed through j's membrane and the force
// must pull it back rather than push it further in. So
//   F_i = -s V'(d) (x_i - x_j)/r,  s = +1 not crossed, -1 crossed,
// i.e. F = -grad(s V) for fixed normals; the energy of a crossed pair is
// 2 V(0) - V(d), continuous at the crossing when offset = 0. As in ESPResSo,
// no force when the normals are (nearly) parallel: that happens at the rim of a
// contact zone, where the direction is ambiguous and would make the pair
// oscillate, and none for r <= offset.
// Deviation from ESPResSo (documented in doc/interactions.md): ESPResSo used
// a / (1 + e^(n d)) / r as the force magnitude along u; here eq. 9 is the
// potential, and the force is its derivative along the separation.
#pragma once

#include "interactions/nonbonded/pair_context.hpp"
#include "utils/errors.hpp"

#include <cmath>

namespace pyoif {

struct MembraneCollision {
  static constexpr const char* name = "membrane_collision";
  struct Params {
    using Model = MembraneCollision;
    double a = 0.0, n = 0.0, cutoff = 0.0, offset = 0.0;
    bool active() const { return cutoff > 0.0; }
    double range() const { return cutoff + offset; }
  };

  /** |n_i - n_j| below this: normals parallel, no force. */
  static constexpr double parallel_normals = 1e-6;

  /** +1 membranes not crossed, -1 crossed, 0 no interaction. */
  static int side(const Params& p, const PairContext& c) {
    if (c.wall || c.mol_i == c.mol_j || c.dist >= p.range() || c.dist <= p.offset)
      return 0;
    const Vec3 u = c.normal_i - c.normal_j;
    if (c.normal_i.squaredNorm() == 0.0 || c.normal_j.squaredNorm() == 0.0)
      throw InputError("membrane_collision: a membrane node has no outward normal; add "
                       "OifOutDirection bonds to the cells (OifCellType(normal=True))");
    if (u.norm() < parallel_normals)
      return 0;
    return u.dot(c.d) > 0.0 ? -1 : 1;
  }
  static double potential(const Params& p, double d) { return p.a / (1.0 + std::exp(p.n * d)); }

  static double energy(const Params& p, const PairContext& c) {
    const int s = side(p, c);
    const double d = c.dist - p.offset;
    if (s == 0)
      return 0.0;
    return s > 0 ? potential(p, d) : 2.0 * potential(p, 0.0) - potential(p, d);
  }
  /** Force on i. -V'(d) = a n e^(n d) / (1 + e^(n d))^2, written with
   *  e^(-n d) so that large n d cannot overflow. */
  static Vec3 force(const Params& p, const PairContext& c) {
    const int s = side(p, c);
    if (s == 0)
      return Vec3::Zero();
    const double q = std::exp(-p.n * (c.dist - p.offset));
    const double minus_dv = p.a * p.n * q / ((1.0 + q) * (1.0 + q));
    return (s * minus_dv / c.dist) * c.d;
  }
};

} // namespace pyoif
