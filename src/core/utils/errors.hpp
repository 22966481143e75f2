// Exception types of the core. The Python bindings translate them:
// InputError -> ValueError, SimulationInstability -> lbmd.SimulationInstability.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace pyoif {

/** A parameter or an input file is invalid; the message names it. */
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/** The simulation state became unphysical (NaN, a violated constraint, a fluid
 *  speed past the lattice sound speed). The message says what, where, when. */
struct SimulationInstability : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/** A number for a message: 10 significant digits, exponent where needed
 *  (std::to_string's fixed 6 decimals shows 1e-7 as 0.000000). */
inline std::string format_number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

} // namespace pyoif
