// The one place where bonded interactions are registered. Adding a bond:
// write its header (n_particles, per_bond_stride, a forces() method; optionally
// prepare() for a pass over all bonds before the forces, e.g. per-cell sums),
// add it to the variant below, and bind it in src/python/lbmd/bind_interactions.cpp.
// The integrator and the bond loop never change.
#pragma once

#include "interactions/bonded/harmonic.hpp"
#include "interactions/bonded/oif_global_forces.hpp"
#include "interactions/bonded/oif_local_forces.hpp"
#include "interactions/bonded/oif_out_direction.hpp"

#include <variant>

namespace pyoif {

using BondedInteraction =
    std::variant<HarmonicBond, OifLocalForces, OifGlobalForces, OifOutDirection>;

} // namespace pyoif
