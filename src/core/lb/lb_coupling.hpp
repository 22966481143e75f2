// PLACEHOLDER owned by the lattice-Boltzmann work: particle-fluid coupling
// (model eq. 1), called by the force calculation every MD step.
#pragma once

#include "lb/lb_fluid.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <cstdint>

namespace pyoif::lb {

struct CouplingParams {
  double gamma = 0.0;
  double kT = 0.0;  ///< taken from the fluid when the thermostat is set
  std::uint64_t seed = 0;
};

/** Adds gamma (u - v) (+ noise) to each local particle's force and the opposite
 *  momentum to the fluid's force field. `step` counts MD steps (noise counter). */
void couple_particles(LBFluid& fluid, ParticleStore& particles, const BoxGeometry& box,
                      const CouplingParams& params, std::uint64_t step, double time_step);

}  // namespace pyoif::lb
