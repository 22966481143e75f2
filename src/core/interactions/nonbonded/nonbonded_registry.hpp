// The one place where non-bonded models are registered. Adding a model: write
// its header (Params with active()/range(), static force()/energy() on a
// PairContext), add it to NonbondedModels below, bind it in
// src/python/lbmd/bind_interactions.cpp, and add its Python name in lbmd/interactions.py.
#pragma once

#include "interactions/nonbonded/hard_contact.hpp"
#include "interactions/nonbonded/membrane_collision.hpp"
#include "interactions/nonbonded/morse.hpp"
#include "interactions/nonbonded/soft_sphere.hpp"

#include <tuple>

namespace pyoif {

using NonbondedModels = std::tuple<SoftSphere, MembraneCollision, Morse, HardContact>;

} // namespace pyoif
