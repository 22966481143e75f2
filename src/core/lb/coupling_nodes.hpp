// What the particle coupling and the lattice exchange: the coupling's
// stencils (which lattice nodes a particle reads and deposits on, with which
// weights) and the list of lattice nodes one coupling pass needs. The
// coupling (lb_coupling.hpp, CouplingLedger) owns and fills the list; the
// lattice (LBFluid::velocities_at) writes the fluid velocity of each listed
// node into it and takes the deposits back through add_field_impulse. This
// is all the two share: the lattice never sees particles, the coupling never
// sees populations.
#pragma once

#include "utils/vector.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pyoif::lb {

/** The stencil of a particle as its first node (lowest index on every axis),
 *  per axis whether the second node lies across the box's periodic edge,
 *  and the fraction towards it: node m = (dx, dy, dz) (m = dx + 2 dy + 4 dz)
 *  is base + the steps of the axes with d = 1 (StencilSteps: the lattice
 *  stride, or less the period where the stencil wraps round the box), its
 *  weight the product of (d ? frac : 1 - frac) over the axes (trilinear
 *  interpolation, model eq. 1). key = base << 3 | wrap bits: one comparison
 *  tells a stencil that moved; 32 bytes, read and written for every coupled
 *  particle and step. */
struct CouplingStencil {
  std::uint64_t key;
  double frac[3];
  std::size_t base() const { return static_cast<std::size_t>(key >> 3); }
  double weight(int m) const {
    return ((m & 1) ? frac[0] : 1.0 - frac[0]) * ((m & 2) ? frac[1] : 1.0 - frac[1]) *
           ((m & 4) ? frac[2] : 1.0 - frac[2]);
  }
};

/** Per axis the index step from a stencil's first to its second node: the
 *  lattice stride, or the stride less the period (wrapped). */
struct StencilSteps {
  std::ptrdiff_t plain[3], wrapped[3];
  std::size_t node(const CouplingStencil& s, int m) const {
    std::ptrdiff_t n = static_cast<std::ptrdiff_t>(s.base());
    for (int d = 0; d < 3; ++d)
      if ((m >> d) & 1)
        n += ((s.key >> d) & 1) ? wrapped[d] : plain[d];
    return static_cast<std::size_t>(n);
  }
};

/** The lattice nodes of the coupling passes since the last renumbering:
 *  marked in `needed` (one bit per padded node), numbered in the order the
 *  particles' stencils first touched them (compact[n], stale for unmarked
 *  nodes, which are never looked up), listed in `node` by number (see
 *  couple_particles). Each lattice node serves several membrane nodes, and
 *  its 19 populations lie in 19 different streams, so its velocity is
 *  computed once per pass, in memory order, into its compact entry. */
struct CouplingNodes {
  std::vector<std::uint64_t> needed;
  std::vector<std::uint32_t> compact;
  std::vector<std::size_t> node; ///< the first n_nodes are the list (the rest: room)
  std::size_t n_nodes = 0;
  struct NodeCoupling {
    Vec3 velocity; ///< of the fluid at the node, MD units
    Vec3 impulse;  ///< this pass's deposit, field units (see add_field_impulse)
  };
  std::vector<NodeCoupling> node_coupling;
  /// decomposed lattice: this pass still owes its neighbours their
  /// ghost-layer velocities (velocities_at sends them; a pass that failed
  /// before sends none, so that no rank waits)
  bool ghosts_pending = false;
};

} // namespace pyoif::lb
