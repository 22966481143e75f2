// Collide-and-stream: one lattice update over runs of fluid nodes, in place
// with the AA pattern (population_storage.hpp), as a function of the
// populations, the runs and what SweepParams lists. No lattice object, no
// virtual calls: the kernel that a PyOIF run spends its time in
// (collide_stream.cpp; the halo, bounce-back and the update loop are
// LBFluid's, lb_kernel.cpp).
#pragma once

#include "lb/boundary_links.hpp"
#include "lb/lb_lattice.hpp"
#include "utils/vector.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pyoif::lb {

/** The relaxation factors lambda = 1 - omega of the shear, bulk, even-ghost
 *  and odd-ghost modes (Duenweg, Schiller & Ladd 2007). */
struct Relaxation {
  double shear, bulk, even, odd;
};

/** Where an update found a node out of the model's range. */
struct BadNode {
  std::size_t node = 0;
  double rho = 0.0, speed = 0.0;
};

/** What one sweep reads besides the populations and the runs. */
struct SweepParams {
  /// per population, the offset of its pre-collision value in the layout the
  /// update starts from (PopulationStorage::read_offset_in)
  const std::ptrdiff_t* read = nullptr;
  /// the update's parity: even reads the normal layout and leaves it swapped
  bool even = true;
  /// the relaxation of each run, relaxation[run.relaxation]: one parameter
  /// per run, so that runs may differ in viscosity
  const Relaxation* relaxation = nullptr;
  /// every relaxation has even == 0 (the even ghosts relaxed at once): a
  /// cheaper collision
  bool even_ghosts_relaxed = false;
  Vec3 ext_force = Vec3::Zero(); ///< force density, lattice units
  double density = 1.0;          ///< rho0 (the deviations' rest state in float)
  /// the coupling's force field (3 values per padded node) and its marks (a
  /// bit per padded node, one spare word at the end); null: none
  const double* field = nullptr;
  const std::uint64_t* field_valid = nullptr;
  /// thermal fluctuations (noise_factor null: none), keyed by the global
  /// node and the update counter, so the same on any decomposition
  const double* noise_factor = nullptr;
  const std::array<std::array<double, d3q19::Q>, d3q19::Q>* basis = nullptr;
  std::uint64_t seed = 0, update = 0;
  Vec3i origin = Vec3i::Zero(), global = Vec3i::Zero(), pad = Vec3i::Zero();
};

/** One update of the runs (OpenMP over runs with `threads` > 1). Returns the
 *  index of the first run with a node out of range (density not positive
 *  or not finite, speed at the sound speed), with that node in `bad`; then
 *  the update is abandoned half done. runs.size(): all went well. */
template <typename Real>
std::size_t collide_stream(const SweepParams& s, const std::vector<FluidRun>& runs, Real* f,
                           int threads, BadNode& bad);

} // namespace pyoif::lb
