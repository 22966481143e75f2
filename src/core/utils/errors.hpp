// Exception types of the core. The Python bindings translate them:
// InputError -> ValueError, SimulationInstability -> lbmd.SimulationInstability.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace pyoif {

/** A parameter or an input file is invalid; the message names it. */
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/** Throws InputError(msg) unless ok (argument checks). */
inline void require(bool ok, const std::string& msg) {
  if (!ok)
    throw InputError(msg);
}

/** The simulation state became unphysical (NaN, a violated constraint, a fluid
 *  speed past the lattice sound speed). The message says what, where, when;
 *  the fields say it for programs (lbmd.SimulationInstability's attributes):
 *  cause, a short name from the list in doc/engine.md ("lattice_nan",
 *  "negative_density", "mach", "particle_nan", "particle_jump",
 *  "triangle_collapsed", "triangle_inverted", "cell_blown_up",
 *  "volume_collapsed", "volume_exploded", "membrane_crossing", "contact_overrun",
 *  "bond_broken", "wall_penetration", "outside_lattice", "coupling");
 *  the MD step and time (filled in by System::integrate where the thrower
 *  does not know them), the place (a lattice node, a particle, a cell's
 *  mol_id; -1 where none) and the offending value. */
struct SimulationInstability : std::runtime_error {
  std::string cause = "unspecified";
  long long step = -1;
  double time = std::numeric_limits<double>::quiet_NaN();
  long long particle = -1, cell = -1;
  std::array<long long, 3> node{{-1, -1, -1}};
  double value = std::numeric_limits<double>::quiet_NaN();

  explicit SimulationInstability(const std::string& message) : std::runtime_error(message) {}
  SimulationInstability(std::string cause_name, const std::string& message)
      : std::runtime_error(message), cause(std::move(cause_name)) {}
  SimulationInstability& at_particle(long long id) {
    particle = id;
    return *this;
  }
  SimulationInstability& in_cell(long long mol_id) {
    cell = mol_id;
    return *this;
  }
  SimulationInstability& at_node(long long x, long long y, long long z) {
    node = {{x, y, z}};
    return *this;
  }
  SimulationInstability& with_value(double v) {
    value = v;
    return *this;
  }
  SimulationInstability& at_time(double t) {
    time = t;
    return *this;
  }
  /** Step and time where the thrower did not know them (step < 0). */
  SimulationInstability& at_step(unsigned long long step_number, double t) {
    if (step < 0) {
      step = static_cast<long long>(step_number);
      if (std::isnan(time))
        time = t;
    }
    return *this;
  }
  /** The same error with message m (the fields kept). */
  SimulationInstability with_message(const std::string& m) const {
    SimulationInstability e(cause, m);
    e.step = step;
    e.time = time;
    e.particle = particle;
    e.cell = cell;
    e.node = node;
    e.value = value;
    return e;
  }
  /** Fields and message as bytes, for the ranks that raise another rank's
   *  error (MPI), and back. */
  std::string pack() const {
    std::ostringstream s;
    s.precision(17);
    s << cause << '\n'
      << step << ' ' << time << ' ' << particle << ' ' << cell << ' ' << node[0] << ' ' << node[1]
      << ' ' << node[2] << ' ' << value << '\n'
      << what();
    return s.str();
  }
  static SimulationInstability unpack(const std::string& bytes) {
    const std::size_t first = bytes.find('\n');
    const std::size_t second = bytes.find('\n', first + 1);
    SimulationInstability e(bytes.substr(0, first), bytes.substr(second + 1));
    std::istringstream fields(bytes.substr(first + 1, second - first - 1));
    std::string t, v; // "nan" does not read back through operator>>
    fields >> e.step >> t >> e.particle >> e.cell >> e.node[0] >> e.node[1] >> e.node[2] >> v;
    e.time = t == "nan" ? e.time : std::stod(t);
    e.value = v == "nan" ? e.value : std::stod(v);
    return e;
  }
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
