// The one place where bonded interactions are registered. Two kinds:
//  - generic bonds (HarmonicBond, future ones): a header with n_particles,
//    per_bond_stride and a forces() method; the one bond loop (bond_loop.hpp)
//    evaluates them bond by bond;
//  - membrane bonds (OifLocalForces, OifGlobalForces, OifOutDirection,
//    `membrane = true`): descriptions that the membrane component compiles
//    into cells and evaluates cell by cell (interactions/membrane/).
// Adding a bond: its header, one line in the variant below, its binding in
// src/python/lbmd/bind_interactions.cpp. The integrator never changes.
#pragma once

#include "interactions/bonded/bond_group.hpp"
#include "interactions/bonded/harmonic.hpp"
#include "interactions/membrane/oif_bonds.hpp"

#include <type_traits>
#include <variant>

namespace pyoif {

using BondedInteraction =
    std::variant<HarmonicBond, OifLocalForces, OifGlobalForces, OifOutDirection>;

/** One registered bonded interaction and its bonds. */
struct BondedEntry {
  BondedInteraction interaction;
  BondGroup bonds;
};

namespace detail {
template <class IA, class = void> struct is_membrane_bond : std::false_type {};
template <class IA>
struct is_membrane_bond<IA, std::void_t<decltype(IA::membrane)>>
    : std::bool_constant<IA::membrane> {};
} // namespace detail

/** Whether a bond kind is a membrane description (compiled into the membrane
 *  component) rather than a generic bond (the bond loop). */
template <class IA> constexpr bool is_membrane_bond = detail::is_membrane_bond<IA>::value;

} // namespace pyoif
