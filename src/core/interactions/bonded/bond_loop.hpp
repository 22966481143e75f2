// The generic bond loop, written once for every generic bonded interaction
// (the membrane bonds are compiled into the membrane component instead):
// gathers the bond's particles (minimum image relative to the first), calls
// the interaction's forces(), hands the result to a sink (adding forces, or
// summing energies, ...).
#pragma once

#include "interactions/bonded/bond_group.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"
#include "utils/errors.hpp"

#include <array>
#include <sstream>

namespace pyoif {

/** What an interaction's forces() sees of one bond. */
template <int K> struct BondInput {
  std::array<Vec3, K> x;             ///< positions, x[k>0] as minimum image relative to x[0]
  std::array<Vec3, K> v;             ///< velocities
  const double* reference = nullptr; ///< per-bond reference values (or nullptr)
};

/** Visit every bond: sink(local_indices, forces, energy, input); with owned
 *  (per local index, particles spread over ranks) only the bonds with a
 *  particle this rank owns. */
template <class IA, class Sink>
void for_each_bond(const IA& ia, const BondGroup& group, const ParticleStore& p,
                   const BoxGeometry& box, double time, Sink&& sink,
                   const std::uint8_t* owned = nullptr) {
  constexpr int K = IA::n_particles;
  BondInput<K> in;
  std::array<int, K> idx;
  std::array<Vec3, K> f;
  const std::size_t n = group.size();
  for (std::size_t b = 0; b < n; ++b) {
    const int* ids = group.bond(b);
    for (int k = 0; k < K; ++k) {
      idx[k] = p.index(ids[k]);
      if (idx[k] < 0)
        throw SimulationInstability(std::string(IA::name) + " bond refers to particle " +
                                    std::to_string(ids[k]) + ", which does not exist");
    }
    if (owned) {
      bool any = false;
      for (int k = 0; k < K; ++k)
        any |= owned[idx[k]] != 0;
      if (!any)
        continue;
    }
    in.x[0] = p.pos[idx[0]];
    in.v[0] = p.vel[idx[0]];
    for (int k = 1; k < K; ++k) {
      in.x[k] = in.x[0] + box.minimum_image(p.pos[idx[k]], p.pos[idx[0]]);
      in.v[k] = p.vel[idx[k]];
    }
    in.reference = group.reference(b);
    double energy = 0.0;
    if (!ia.forces(in, f, energy)) {
      std::ostringstream msg;
      msg << IA::name << " bond between particles";
      for (int k = 0; k < K; ++k)
        msg << ' ' << ids[k];
      msg << " broke at time " << time << " (stretched beyond its cutoff or degenerate)";
      throw SimulationInstability("bond_broken", msg.str()).at_particle(ids[0]).at_time(time);
    }
    sink(idx, f, energy, in);
  }
}

} // namespace pyoif
