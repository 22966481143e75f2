// Particle-fluid coupling (model eq. 1; Ahlrichs & Duenweg 1999): each
// particle feels F = gamma (u - v) + noise, u the fluid velocity trilinearly
// interpolated from the 8 surrounding lattice nodes (periodic), and the
// opposite impulse F * time_step is spread onto the same nodes with the same
// weights, so particle + fluid momentum is conserved to round-off. With the
// fluid's kT > 0 the noise has variance 2 gamma kT / time_step per component
// (fluctuation-dissipation).
#pragma once

#include "lb/coupling_nodes.hpp"
#include "lb/lb_fluid.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <cstdint>
#include <functional>
#include <vector>

namespace pyoif::lb {

struct CouplingParams {
  double gamma = 0.0;
  double kT = 0.0; ///< taken from the fluid when the thermostat is set
  std::uint64_t seed = 0;
};

/** The coupling's records between passes, owned by whoever couples
 *  (System): the stencils and node list (CouplingNodes, which the lattice
 *  fills with velocities) and the bookkeeping of the impulse under velocity
 *  Verlet. An MD step's coupling force F_n acts on the particles in two half
 *  kicks (dt/2 at the end of step n, dt/2 at the start of step n+1) but goes
 *  to the fluid at once (F_n dt). Half of the last deposit is thus "in
 *  flight": not yet received by the particles. A force recomputation
 *  without a time step (same MD step) replaces that half; the first
 *  computation deposits only that half. in_flight_momentum() is what the
 *  fluid's momentum must exclude so that particle + fluid momentum is
 *  conserved to round-off at every step. A ledger made for one lattice
 *  layout resets itself when the lattice is laid out anew
 *  (LBFluid::layout_generation). */
struct CouplingLedger : CouplingNodes {
  bool any = false;
  std::uint64_t step = 0;
  std::uint64_t lattice_generation = 0; ///< the fluid layout the records are of
  /// how much the last call deposited (full impulse per particle, spread
  /// with that call's stencils, still in `stencils`)
  std::vector<Vec3> last_impulse;
  Vec3 in_flight = Vec3::Zero(); ///< impulse deposited, not yet on particles
  /// in_flight is this rank's share (particles spread over the ranks)
  bool in_flight_partial = false;
  std::uint64_t layout_version = 0, numbered_step = 0; ///< of the last renumbering
  std::vector<CouplingStencil> stencils;               ///< per particle of the current pass
  /// decomposed lattice: per particle the rank of its stencil's first
  /// node, which gives the particle its force (CouplingDistribution)
  std::vector<int> giver;
  std::vector<Vec3> coupling_force;           ///< per particle, this pass
  std::vector<std::uint32_t> stencil_entries; ///< compact entries, 8 per particle
  /// decomposed lattice: the particles this rank keeps current (their
  /// indices, ascending) and the mask the list was made from; the others'
  /// stencils are marked not here, their givers -1, forces and impulses 0
  std::vector<std::uint32_t> current_list;
  std::vector<std::uint8_t> current_mask;

  /** Collective on a decomposed lattice (every rank's share summed where
   *  the particles are spread): the impulse deposited on the fluid and not
   *  yet received by the particles, MD units. */
  Vec3 in_flight_momentum(const LBFluid& fluid) const;
};

/** How the particles are spread over the ranks of a decomposed lattice
 *  (required there; null on an undivided lattice). Only the particles marked
 *  `current` are up to date on this rank, and `share` gives each particle this rank
 *  integrates its force: called with each particle's force as this rank
 *  computed it (where its stencil touches this rank's subdomain) and the
 *  giving rank per particle (that of the stencil's first node, -1 where this
 *  rank did not compute it), it must leave in force[i] the force of every
 *  particle this rank integrates and zero elsewhere. `listed` holds the
 *  indices of the current particles (ascending; null: all particles): the
 *  forces of the others are zero on the call already and must stay so. It
 *  is called on every rank even when the computation failed (then with zero
 *  forces), before the error is raised, so that no rank waits in vain. */
struct CouplingDistribution {
  const std::uint8_t* current = nullptr;
  std::function<void(std::vector<Vec3>& force, const std::vector<int>& giver,
                     const std::vector<std::uint32_t>* listed)>
      share;
};

/** Adds gamma (u - v) (+ noise) to each local particle's force and the opposite
 *  momentum to the fluid's force field. `step` counts MD steps (noise counter:
 *  RNG stream lb_coupling, key = particle id). */
void couple_particles(LBFluid& fluid, CouplingLedger& ledger, ParticleStore& particles,
                      const BoxGeometry& box, const CouplingParams& params, std::uint64_t step,
                      double time_step, const CouplingDistribution* distribution = nullptr);

/** Fluid velocity at pos (MD units), trilinear in the 8 surrounding nodes;
 *  collective on a decomposed lattice. */
Vec3 interpolated_velocity(LBFluid& fluid, const BoxGeometry& box, const Vec3& pos);

} // namespace pyoif::lb
