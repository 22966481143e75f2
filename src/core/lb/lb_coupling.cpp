#include "lb/lb_coupling.hpp"

#include "utils/random.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace pyoif::lb {

namespace {

/** The 8 nodes around pos and their trilinear weights. Node (i, j, k) sits at
 *  ((i, j, k) + 1/2) agrid. */
struct Stencil {
  std::array<std::size_t, 8> node;
  std::array<double, 8> weight;
};

Stencil stencil(const LBFluid& fluid, const BoxGeometry& box, const Vec3& pos) {
  const Vec3 p = box.folded(pos) / fluid.agrid() - Vec3::Constant(0.5);
  const Vec3i& n = fluid.grid();
  int node[3][2]; // the two node indices per axis, folded into [0, N)
  double frac[3];
  for (int d = 0; d < 3; ++d) {
    const double fl = std::floor(p[d]);
    int lo = static_cast<int>(fl);
    frac[d] = p[d] - fl;
    // p lies in [-0.5, N - 0.5), so lo in [-1, N - 1] (N when round-off puts
    // a folded position at L): fold without a division
    if (lo >= n[d])
      lo -= n[d];
    node[d][0] = lo < 0 ? lo + n[d] : lo;
    node[d][1] = lo + 1 >= n[d] ? lo + 1 - n[d] : lo + 1;
  }
  Stencil s;
  int m = 0;
  for (int dx = 0; dx < 2; ++dx)
    for (int dy = 0; dy < 2; ++dy)
      for (int dz = 0; dz < 2; ++dz, ++m) {
        s.node[m] = fluid.padded_index_in_box(node[0][dx], node[1][dy], node[2][dz]);
        s.weight[m] = (dx ? frac[0] : 1.0 - frac[0]) * (dy ? frac[1] : 1.0 - frac[1]) *
                      (dz ? frac[2] : 1.0 - frac[2]);
      }
  return s;
}

} // namespace

Vec3 interpolated_velocity(const LBFluid& fluid, const BoxGeometry& box, const Vec3& pos) {
  const Stencil s = stencil(fluid, box, pos);
  Vec3 u = Vec3::Zero();
  for (int m = 0; m < 8; ++m)
    u += s.weight[m] * fluid.velocity_at_index(s.node[m]);
  return u;
}

void couple_particles(LBFluid& fluid, ParticleStore& particles, const BoxGeometry& box,
                      const CouplingParams& params, std::uint64_t step, double time_step) {
  if (params.gamma <= 0.0)
    return;
  const auto field = fluid.impulse_field();
  const double scale = fluid.impulse_scale();
  auto deposit = [&](const Stencil& s, const Vec3& impulse) {
    const Vec3 p = scale * impulse;
    for (int m = 0; m < 8; ++m) {
      const std::size_t node = s.node[m];
      const double wgt = s.weight[m];
      field[0][node] += wgt * p[0];
      field[1][node] += wgt * p[1];
      field[2][node] += wgt * p[2];
    }
  };
  // see LBFluid::CouplingLedger: a new MD step deposits F dt; a first or a
  // repeated computation for the same step deposits F dt / 2 after taking
  // back the in-flight half of the previous computation of this step
  auto& ledger = fluid.coupling_ledger();
  const bool same_step = ledger.any && ledger.step == step;
  const double fraction = (ledger.any && !same_step) ? 1.0 : 0.5;
  if (same_step)
    for (std::size_t i = 0; i < ledger.last_position.size(); ++i)
      deposit(stencil(fluid, box, ledger.last_position[i]), -0.5 * ledger.last_impulse[i]);
  ledger.any = true;
  ledger.step = step;
  auto& p = particles;
  const std::size_t n = p.n_local();
  ledger.last_position.resize(n);
  ledger.last_impulse.resize(n);
  Vec3 impulse_sum = Vec3::Zero();
  // fresh velocity cache for this pass (the fluid may have changed since the last)
  if (ledger.velocity_stamp.size() != fluid.n_padded_slots()) {
    ledger.velocity_stamp.assign(fluid.n_padded_slots(), 0);
    ledger.velocity_cache.resize(fluid.n_padded_slots());
    ledger.stamp = 0;
  }
  if (++ledger.stamp == 0) {
    std::fill(ledger.velocity_stamp.begin(), ledger.velocity_stamp.end(), 0);
    ledger.stamp = 1;
  }
  std::uint32_t* const stamps = ledger.velocity_stamp.data();
  Vec3* const cache = ledger.velocity_cache.data();
  const std::uint32_t stamp = ledger.stamp;
  const double noise =
      params.kT > 0.0 ? std::sqrt(2.0 * params.gamma * params.kT / time_step) : 0.0;
  random::Key key{params.seed, static_cast<std::uint64_t>(random::Stream::lb_coupling), step, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const Stencil s = stencil(fluid, box, p.pos[i]);
    Vec3 u = Vec3::Zero();
    for (int m = 0; m < 8; ++m) {
      const std::size_t node = s.node[m];
      if (stamps[node] != stamp) {
        cache[node] = fluid.velocity_at_index(node);
        stamps[node] = stamp;
      }
      u += s.weight[m] * cache[node];
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
