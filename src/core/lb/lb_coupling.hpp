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

namespace pyoif::lb {

struct CouplingParams {
  double gamma = 0.0;
  double kT = 0.0; ///< taken from the fluid when the thermostat is set
  std::uint64_t seed = 0;
};

/** Adds gamma (u - v) (+ noise) to each local particle's force and the opposite
 *  momentum to the fluid's force field. `step` counts MD steps (noise counter:
 *  RNG stream lb_coupling, key = particle id). */
void couple_particles(LBFluid& fluid, ParticleStore& particles, const BoxGeometry& box,
                      const CouplingParams& params, std::uint64_t step, double time_step);

/** Fluid velocity at pos (MD units), trilinear in the 8 surrounding nodes;
 *  collective on a decomposed lattice. */
Vec3 interpolated_velocity(LBFluid& fluid, const BoxGeometry& box, const Vec3& pos);

} // namespace pyoif::lb
