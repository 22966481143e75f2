// The lattice update loop: the collide-and-stream sweep (collide_stream.cpp)
// over this rank's runs, the agreement on a failed node across the ranks,
// the halo exchange (lb_halo.cpp), halfway bounce-back and the open faces.
#include "lb/lb_fluid.hpp"

#include "lb/collide_stream.hpp"

#include "utils/errors.hpp"
#include "utils/random.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <type_traits>
#include <utility>

#include "lb/lattice_codegen.hpp" // last: it applies to this file's functions

namespace pyoif::lb {

using namespace d3q19;

template <typename Real> void LBFluid::apply_bounce_back(Real* f) const {
  // Halfway bounce-back (Ladd 1994): f_q* that a fluid node sent towards its
  // solid neighbour comes back as f_{-q}, less the moving-wall term
  // 6 w_q rho0 c_q . u_wall. After an odd update f_q* was pushed into the
  // solid node's slot q and goes to the fluid node's slot -q; after an even
  // update it sits in the fluid node's slot -q and goes to the solid node's
  // slot q, where the next (odd) update reads the fluid node's f_{-q}.
  apply_place_runs(f, m_geometry.bounce_back, m_pop.swapped());
}

void LBFluid::report_instability(const BadNode& bad) {
  const std::size_t n = bad.node;
  const Vec3i g = padded_coordinates(n) - Vec3i::Ones() + m_origin;
  const int x = g[0], y = g[1], z = g[2];
  std::ostringstream msg;
  msg << "lattice-Boltzmann fluid unstable at node (" << x << ", " << y << ", " << z
      << ") in lattice update " << m_updates << ": density " << bad.rho
      << ", speed |u| = " << bad.speed
      << " lattice units (must stay well below the lattice sound speed 0.577); reduce the "
         "forces or flow speed, or increase visc (relaxation rate "
      << 1.0 - m_relax.shear << ")";
  m_failed_update = msg.str();
  // the cause: not a number, a density that is not positive, or the speed
  // (Mach number |u| / c_s, c_s = 1/sqrt(3) lattice units) at the limit
  const bool finite = std::isfinite(bad.rho) && std::isfinite(bad.speed);
  const char* cause = !finite ? "lattice_nan" : !(bad.rho > 0.0) ? "negative_density" : "mach";
  const double value = !finite || !(bad.rho > 0.0) ? bad.rho : bad.speed * std::sqrt(3.0);
  throw SimulationInstability(cause, msg.str()).at_node(x, y, z).with_value(value);
}

void LBFluid::check_usable() const {
  if (!m_failed_update.empty())
    // the failed update stopped half way: its populations mix two time levels
    throw SimulationInstability(
        "lattice-Boltzmann fluid not usable: an earlier update failed and left it half "
        "updated (" +
        m_failed_update +
        "). Its fields can still be read and written out; to go on, create a new fluid");
}

void LBFluid::step() {
  require_flagged("a lattice update");
  check_usable();
  ++m_state_version;
  m_pop.visit([this](auto* f) { step_stored_as(f); });
}

template <typename Real> void LBFluid::step_stored_as(Real* f) {
  const bool field = m_field_used;
  const bool even = !m_pop.swapped();
  SweepParams sweep;
  sweep.read = m_pop.read_offset_in(!even);
  sweep.even = even;
  sweep.relaxation = &m_relax; // one relaxation: every run's index is 0
  sweep.even_ghosts_relaxed = m_relax.even == 0.0;
  sweep.ext_force = m_ext_lattice;
  sweep.density = m_p.density;
  if (field) {
    sweep.field = m_field.data();
    sweep.field_valid = m_field_valid.data();
  }
  if (m_kT_lattice > 0.0) {
    sweep.noise_factor = m_noise_factor.data();
    sweep.basis = &m_basis;
    sweep.seed = m_p.seed;
    sweep.update = m_updates;
    sweep.origin = m_origin;
    sweep.global = m_global;
    sweep.pad = m_pad;
  }
  const std::size_t n_runs = m_geometry.runs.size();
  BadNode bad_node;
  const std::size_t first_bad = collide_stream(sweep, m_geometry.runs, f, m_threads, bad_node);
  if (m_grid.size() > 1) {
    // every rank learns of a bad node anywhere (the lowest rank's is
    // reported by all), before anyone waits for a halo that will not come
    int failing = first_bad < n_runs ? m_grid.rank() : m_grid.size();
    if (m_halo.segment.data()) { // (the agreement also tells the neighbours it is packed)
      const auto start = std::chrono::steady_clock::now();
      pack_shared_halo(f, even);
      m_halo_seconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    MPI_Allreduce(MPI_IN_PLACE, &failing, 1, MPI_INT, MPI_MIN, m_grid.comm());
    if (failing < m_grid.size()) {
      std::string message;
      if (failing == m_grid.rank()) {
        try {
          report_instability(bad_node);
        } catch (const SimulationInstability& e) {
          message = e.pack();
        }
      }
      int length = static_cast<int>(message.size());
      MPI_Bcast(&length, 1, MPI_INT, failing, m_grid.comm());
      message.resize(static_cast<std::size_t>(length));
      MPI_Bcast(message.data(), length, MPI_CHAR, failing, m_grid.comm());
      const SimulationInstability error = SimulationInstability::unpack(message);
      m_failed_update = error.what();
      throw error;
    }
  }
  if (first_bad < n_runs)
    // the update is abandoned half done: the fluid state is not usable after this
    report_instability(bad_node);
  m_pop.set_swapped(even);
  halo_exchange(f, even);
  apply_bounce_back(f);
  if (!m_open.empty())
    apply_open_boundaries();
  if (field) { // every deposit is used: the field is empty again
    std::fill(m_field_valid.begin(), m_field_valid.end(), std::uint64_t{0});
    m_field_used = false;
  }
  ++m_updates;
  if (m_speed_watch.every > 0 && m_updates % static_cast<std::uint64_t>(m_speed_watch.every) == 0)
    watch_speed();
}

void LBFluid::watch_speed() {
  const FastNode fast = m_pop.visit([this](const auto* f) {
    return fastest_node(f, m_pop.read_offset(), m_geometry.runs, m_p.density, m_ext_lattice);
  });
  if (fast.u2 >= 0.0)
    m_speed_watch.note(std::sqrt(3.0 * fast.u2),
                       padded_coordinates(fast.node) - Vec3i::Ones() + m_origin, m_updates);
}

void LBFluid::set_speed_watch_every(int every) {
  if (every < 0)
    throw InputError("speed_watch_every must be >= 0 (0: off), got " + std::to_string(every));
  m_speed_watch.every = every;
}

SpeedWatch LBFluid::take_speed_watch() {
  SpeedWatch seen = m_speed_watch;
  m_speed_watch = SpeedWatch{};
  m_speed_watch.every = seen.every;
  if (m_grid.size() > 1) {
    // the fastest over the ranks (MAXLOC: the lowest rank on a tie), whose
    // node and update every rank then learns
    struct {
      double mach;
      int rank;
    } mine{seen.seen ? seen.mach : -1.0, m_grid.rank()};
    MPI_Allreduce(MPI_IN_PLACE, &mine, 1, MPI_DOUBLE_INT, MPI_MAXLOC, m_grid.comm());
    long long where[4] = {seen.node[0], seen.node[1], seen.node[2],
                          static_cast<long long>(seen.update)};
    MPI_Bcast(where, 4, MPI_LONG_LONG, mine.rank, m_grid.comm());
    seen.seen = mine.mach >= 0.0;
    seen.mach = seen.seen ? mine.mach : 0.0;
    seen.node =
        Vec3i(static_cast<int>(where[0]), static_cast<int>(where[1]), static_cast<int>(where[2]));
    seen.update = static_cast<std::uint64_t>(where[3]);
  }
  return seen;
}

// the halo (lb_halo.cpp) applies its periodic copies with the same runs

} // namespace pyoif::lb
