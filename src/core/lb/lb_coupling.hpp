// Particle-fluid coupling (model eq. 1; Ahlrichs & Duenweg 1999): each
// particle feels F = gamma (u - v) + noise, u the fluid velocity trilinearly
// interpolated from the 8 surrounding lattice nodes (periodic), and the
// opposite impulse F * time_step is spread onto the same nodes with the same
// weights, so particle + fluid momentum is conserved to round-off. With the
// fluid's kT > 0 the noise has variance 2 gamma kT / time_step per component
// (fluctuation-dissipation).
#pragma once

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
void couple_particles(LBFluid& fluid, ParticleStore& particles, const BoxGeometry& box,
                      const CouplingParams& params, std::uint64_t step, double time_step,
                      const CouplingDistribution* distribution = nullptr);

/** Fluid velocity at pos (MD units), trilinear in the 8 surrounding nodes;
 *  collective on a decomposed lattice. */
Vec3 interpolated_velocity(LBFluid& fluid, const BoxGeometry& box, const Vec3& pos);

} // namespace pyoif::lb
