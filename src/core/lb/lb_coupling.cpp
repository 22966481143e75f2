#include "lb/lb_coupling.hpp"

#include "utils/errors.hpp"
#include "utils/random.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace pyoif::lb {

namespace {

/** The 8 nodes around pos and their trilinear weights. Node (i, j, k) sits at
 *  ((i, j, k) + 1/2) agrid. */
struct Stencil {
  std::array<std::size_t, 8> node;
  std::array<double, 8> weight;
};

/** i folded into [0, n): one add or subtract for the usual case (positions
 *  are folded at every re-sort and move less than the skin in between). */
inline int wrap_node(int i, int n) {
  if (i < 0)
    i += n;
  else if (i >= n)
    i -= n;
  if (static_cast<unsigned>(i) >= static_cast<unsigned>(n)) // far outside the box
    i = ((i % n) + n) % n;
  return i;
}

Stencil stencil(const LBFluid& fluid, const Vec3& pos) {
  const double inv_agrid = 1.0 / fluid.agrid();
  const Vec3i& n = fluid.grid();
  int node[3][2]; // the two node indices per axis, folded into [0, N)
  double frac[3];
  for (int d = 0; d < 3; ++d) {
    const double x = pos[d] * inv_agrid - 0.5;
    if (!(std::abs(x) < 1e9)) // NaN or flown away: no index to compute
      throw SimulationInstability("lattice-Boltzmann coupling: particle position (" +
                                  std::to_string(pos[0]) + ", " + std::to_string(pos[1]) + ", " +
                                  std::to_string(pos[2]) +
                                  ") is not finite or far outside the box");
    const double fl = std::floor(x);
    const int lo = static_cast<int>(fl);
    frac[d] = x - fl;
    node[d][0] = wrap_node(lo, n[d]);
    node[d][1] = wrap_node(lo + 1, n[d]);
  }
  Stencil s;
  int m = 0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx, ++m) {
        s.node[m] = fluid.padded_index_in_box(node[0][dx], node[1][dy], node[2][dz]);
        s.weight[m] = (dx ? frac[0] : 1.0 - frac[0]) * (dy ? frac[1] : 1.0 - frac[1]) *
                      (dz ? frac[2] : 1.0 - frac[2]);
      }
  return s;
}

} // namespace

Vec3 interpolated_velocity(const LBFluid& fluid, const BoxGeometry& box, const Vec3& pos) {
  const Stencil s = stencil(fluid, box.folded(pos));
  Vec3 u = Vec3::Zero();
  for (int m = 0; m < 8; ++m)
    u += s.weight[m] * fluid.velocity_at_index(s.node[m]);
  return u;
}

void couple_particles(LBFluid& fluid, ParticleStore& particles, const BoxGeometry& /*box*/,
                      const CouplingParams& params, std::uint64_t step, double time_step) {
  if (params.gamma <= 0.0)
    return;
  // see LBFluid::CouplingLedger: a new MD step deposits F dt; a first or a
  // repeated computation for the same step deposits F dt / 2 after taking
  // back the in-flight half of the previous computation of this step
  auto& ledger = fluid.coupling_ledger();
  const bool same_step = ledger.any && ledger.step == step;
  const double fraction = (ledger.any && !same_step) ? 1.0 : 0.5;
  // the force field is switched on (and read by the next update) only when
  // something is deposited: a fluid without particles keeps the plain kernel
  const bool deposits = particles.n_local() > 0 || (same_step && !ledger.last_position.empty());
  double* const field = deposits ? fluid.impulse_field() : nullptr;
  const double scale = fluid.impulse_scale();
  auto deposit = [&](const Stencil& s, const Vec3& impulse) {
    const Vec3 p = scale * impulse;
    for (int m = 0; m < 8; ++m) {
      double* g = field + 3 * s.node[m];
      const double wgt = s.weight[m];
      g[0] += wgt * p[0];
      g[1] += wgt * p[1];
      g[2] += wgt * p[2];
    }
  };
  if (same_step)
    for (std::size_t i = 0; i < ledger.last_position.size(); ++i)
      deposit(stencil(fluid, ledger.last_position[i]), -0.5 * ledger.last_impulse[i]);
  ledger.any = true;
  ledger.step = step;
  auto& p = particles;
  const std::size_t n = p.n_local();
  ledger.last_position.resize(n);
  ledger.last_impulse.resize(n);
  Vec3 impulse_sum = Vec3::Zero();
  // Three passes: (1) stencils, marking the lattice nodes they need; (2)
  // those nodes' velocities, in memory order; (3) forces and deposits.
  if (ledger.velocity.size() != fluid.n_padded_slots()) {
    ledger.velocity.assign(fluid.n_padded_slots(), Vec3::Zero());
    ledger.needed.assign((fluid.n_padded_slots() + 63) / 64, 0);
  }
  ledger.stencil_nodes.resize(8 * n);
  ledger.stencil_weights.resize(8 * n);
  std::size_t* const nodes = ledger.stencil_nodes.data();
  double* const weights = ledger.stencil_weights.data();
  std::uint64_t* const needed = ledger.needed.data();
  Vec3* const velocity = ledger.velocity.data();
  for (std::size_t i = 0; i < n; ++i) {
    const Stencil s = stencil(fluid, p.pos[i]);
    for (int m = 0; m < 8; ++m) {
      nodes[8 * i + m] = s.node[m];
      weights[8 * i + m] = s.weight[m];
      needed[s.node[m] >> 6] |= std::uint64_t{1} << (s.node[m] & 63);
    }
  }
  for (std::size_t word = 0; word < ledger.needed.size(); ++word) {
    std::uint64_t bits = needed[word];
    if (!bits)
      continue;
    needed[word] = 0;
    do {
      const std::size_t node = 64 * word + static_cast<std::size_t>(__builtin_ctzll(bits));
      velocity[node] = fluid.velocity_at_index(node);
      bits &= bits - 1;
    } while (bits);
  }
  const double noise =
      params.kT > 0.0 ? std::sqrt(2.0 * params.gamma * params.kT / time_step) : 0.0;
  random::Key key{params.seed, static_cast<std::uint64_t>(random::Stream::lb_coupling), step, 0};
  for (std::size_t i = 0; i < n; ++i) {
    Stencil s;
    Vec3 u = Vec3::Zero();
    for (int m = 0; m < 8; ++m) {
      s.node[m] = nodes[8 * i + m];
      s.weight[m] = weights[8 * i + m];
      u += s.weight[m] * velocity[s.node[m]];
    }
    Vec3 f = params.gamma * (u - p.vel[i]);
    if (noise > 0.0) {
      key.key = static_cast<std::uint64_t>(p.id[i]);
      for (int d = 0; d < 3; ++d)
        f[d] += noise * random::normal(key, d);
    }
    p.force[i] += f;
    // the fluid gets -F time_step of momentum per MD step, applied at its next update
    const Vec3 impulse = -time_step * f;
    deposit(s, fraction * impulse);
    ledger.last_position[i] = p.pos[i];
    ledger.last_impulse[i] = impulse;
    impulse_sum += impulse;
  }
  ledger.in_flight = 0.5 * impulse_sum;
}

} // namespace pyoif::lb
