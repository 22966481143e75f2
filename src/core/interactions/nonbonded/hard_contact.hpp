// A contact that cannot be crossed: a repulsion between nodes of different
// cells (and between a node and a wall) that diverges as the gap closes,
//   h = r - offset,  F(h) = a ((cutoff / h)^n - 1)  for 0 < h < cutoff,
//   V(h) = a (cutoff^n (h^(1-n) - cutoff^(1-n)) / (n - 1) - (cutoff - h))
//          (n != 1; a (cutoff ln(cutoff / h) - (cutoff - h)) for n = 1),
// zero at and beyond the cutoff with its force (no jump there, unlike a
// soft sphere). Why it holds: a node that passes through another cell's
// membrane passes through one of its triangles, and there it is at most the
// triangle's covering radius (the circumradius of an acute triangle, half
// the longest edge of an obtuse one) from one of the triangle's nodes. With
// the offset at least the largest covering radius of the other cell's mesh
// (oif.contact_settings), the gap h to that node reaches 0 first, and the
// force grows without bound before it does: no finite squeeze pushes a node
// through. Unlike membrane_collision (V = a / (1 + e^(n d)), largest force
// a n / 4, which a strong enough squeeze overcomes), it needs no normals.
//
// The time step sets the one limit: an explicit integrator follows the
// contact only while its stiffness k(h) = a n cutoff^n / h^(n+1) satisfies
// k dt^2 / m <= 1 (a spring's velocity-Verlet limit is 4; a factor 2 in the
// frequency kept as margin). The gap where that is reached, guard_gap, is
// computed at the start of every run from the time step and the lightest
// particle of the pair's types (System::update_contact_guards); a pair that
// closes below it stops the run with SimulationInstability "contact_overrun"
// naming the particles, the gap and the limit: the push on the cells is
// stronger than the contact can hold at this time step (a smaller time step,
// a larger a or heavier nodes hold it).
#pragma once

#include "interactions/nonbonded/pair_context.hpp"
#include "utils/errors.hpp"

#include <cmath>
#include <string>

namespace pyoif {

struct HardContact {
  static constexpr const char* name = "hard_contact";
  struct Params {
    using Model = HardContact;
    double a = 0.0, n = 2.0, cutoff = 0.0, offset = 0.0;
    double guard_gap =
        0.0; ///< derived: the gap below which the time step cannot follow (see above)
    bool active() const { return cutoff > 0.0; }
    double range() const { return cutoff + offset; }
  };

  /** The gap where the contact's stiffness reaches the integrator's limit
   *  k dt^2 / m = 1 for time step dt and the lighter particle's mass m. */
  static double guard_for(const Params& p, double dt, double mass) {
    if (!(p.active() && p.a > 0.0 && dt > 0.0 && mass > 0.0))
      return 0.0;
    return std::pow(p.a * p.n * std::pow(p.cutoff, p.n) * dt * dt / mass, 1.0 / (p.n + 1.0));
  }

  static bool acts(const Params& p, const PairContext& c) {
    return (c.wall || c.mol_i != c.mol_j) && c.dist < p.range();
  }

  static double potential(const Params& p, double h) {
    const double c = p.cutoff;
    if (p.n == 1.0)
      return p.a * (c * std::log(c / h) - (c - h));
    return p.a *
           (std::pow(c, p.n) * (std::pow(h, 1.0 - p.n) - std::pow(c, 1.0 - p.n)) / (p.n - 1.0) -
            (c - h));
  }

  /** Energy (no error for a closed gap: analysis of any state must work;
   *  the gap is taken at a millionth of the cutoff there). */
  static double energy(const Params& p, const PairContext& c) {
    if (!acts(p, c))
      return 0.0;
    return potential(p, std::max(c.dist - p.offset, 1e-6 * p.cutoff));
  }

  /** The error of a pair closed below the guard gap, out of line: the pair
   *  loop's fast path stays small. */
  [[noreturn]] [[gnu::cold]] [[gnu::noinline]] static void overrun(const Params& p, double h) {
    throw SimulationInstability(
        "contact_overrun",
        "hard_contact overrun: a gap closed to " + format_number(h) + " (offset " +
            format_number(p.offset) + ", cutoff " + format_number(p.cutoff) + "), below the " +
            format_number(p.guard_gap) +
            " at which the contact's stiffness outruns the time step. The cells are pushed "
            "harder than the contact can hold at this time step: lower the time step or the "
            "driving force, or raise a. If this is a run's first step, the cells started that "
            "close: pack them further apart (oif.pack_cells with clearance="
            "oif.contacts.packing_clearance(cell_types, scale, time_step, node_mass))")
        .with_value(h);
  }

  /** Force on i; throws "contact_overrun" below the guard gap (the caller
   *  adds the particles). */
  static Vec3 force(const Params& p, const PairContext& c) {
    if (!acts(p, c))
      return Vec3::Zero();
    const double h = c.dist - p.offset;
    if (h <= p.guard_gap || h <= 0.0)
      overrun(p, h);
    const double magnitude = p.a * (std::pow(p.cutoff / h, p.n) - 1.0);
    return (magnitude / c.dist) * c.d;
  }
};

} // namespace pyoif
