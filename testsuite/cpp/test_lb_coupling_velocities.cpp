// The particle coupling's node velocities that the lattice update computes
// for the next coupling pass (LBFluid::step, CouplingLedger::n_valid) equal
// the fluid velocity of the state the update leaves, node by node: interior
// nodes fed plane by plane during the update, nodes next to walls and on the
// periodic faces after the halo exchange and the bounce-back, the planes at
// the edges of the threads' shares; for even and odd updates, 1 to 3
// threads, particles that move between passes (new nodes appended to the
// list, renumbering) and populations set between an update and a pass.
#include "lb/lb_coupling.hpp"
#include "shapes/sphere.hpp"
#include "shapes/wall.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>

using namespace pyoif;
using namespace pyoif::lb;

namespace {

constexpr double kTolerance = 1e-13; // MD velocity units; fluid speeds are ~1e-2

/** Every node of the ledger's list has the velocity of the fluid's current
 *  state in its entry; returns how many were checked. */
std::size_t check_ledger_velocities(LBFluid& fluid, const char* when) {
  const auto& ledger = fluid.coupling_ledger();
  EXPECT_EQ(ledger.n_valid, ledger.n_nodes) << when;
  EXPECT_EQ(ledger.valid_version, fluid.state_version()) << when;
  for (std::size_t i = 0; i < ledger.n_nodes; ++i) {
    const std::size_t node = ledger.node[i];
    const Vec3 expected = fluid.velocity_at_index(node);
    const Vec3 stored = ledger.node_coupling[ledger.compact[node]].velocity;
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(stored[d], expected[d], kTolerance)
          << when << ": list entry " << i << " (padded node " << node << "), axis " << d;
  }
  return ledger.n_nodes;
}

void run_scene(int n_threads) {
  SCOPED_TRACE("n_threads " + std::to_string(n_threads));
  // odd sizes, walls normal to z (the lower one moving), periodic in x and
  // y, a sphere obstacle in the middle (walls in the interior planes)
  const Vec3 length(13.0, 11.0, 16.0);
  const BoxGeometry box(length, {true, true, false});
  LBParams params;
  params.agrid = 1.0;
  params.tau = 0.1;
  params.viscosity = 1.5;
  params.ext_force_density = Vec3(1e-3, 0.0, 2e-4);
  params.n_threads = n_threads;
  LBFluid fluid(params, box);
  fluid.set_boundaries(
      {{std::make_shared<shapes::Wall>(Vec3(0, 0, 1), 1.0), Vec3(0.02, 0, 0)},
       {std::make_shared<shapes::Wall>(Vec3(0, 0, -1), -15.0), Vec3::Zero()},
       {std::make_shared<shapes::Sphere>(Vec3(6.0, 5.0, 8.0), 2.5), Vec3::Zero()}});
  // a non-uniform, non-equilibrium fluid, so every node's velocity differs
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  for (int x = 0; x < 13; ++x)
    for (int y = 0; y < 11; ++y)
      for (int z = 0; z < 16; ++z) {
        if (fluid.node_boundary({x, y, z}) >= 0)
          continue;
        Populations f;
        for (int q = 0; q < d3q19::Q; ++q)
          f[q] = d3q19::w[q] * (1.0 + jitter(rng));
        fluid.set_node_populations({x, y, z}, f);
      }
  // particles everywhere, the periodic faces and the walls included
  ParticleStore particles;
  std::uniform_real_distribution<double> ux(0.0, 13.0), uy(0.0, 11.0), uz(0.6, 15.4);
  for (int i = 0; i < 400; ++i)
    particles.add(i, Vec3(ux(rng), uy(rng), uz(rng)), Vec3i::Zero(), Vec3(0.01, 0, 0), 1.0, 0, 0,
                  Vec3::Zero(), 0);
  const CouplingParams coupling{1.5, 0.0, 0};
  std::uniform_real_distribution<double> small_move(-0.3, 0.3);
  std::size_t checked = 0;
  for (std::uint64_t step = 1; step <= 70; ++step) { // a renumbering at step 65
    for (auto& f : particles.force)
      f.setZero();
    couple_particles(fluid, particles, box, coupling, step, 0.1);
    // the forces are those of the interpolated velocity of the current state
    for (std::size_t i = 0; i < particles.n_local(); i += 37) {
      const Vec3 u = interpolated_velocity(fluid, box, particles.pos[i]);
      const Vec3 expected = coupling.gamma * (u - particles.vel[i]);
      for (int d = 0; d < 3; ++d)
        ASSERT_NEAR(particles.force[i][d], expected[d], 1e-12) << "step " << step;
    }
    fluid.step();
    checked +=
        check_ledger_velocities(fluid, step % 2 ? "after an even update" : "after an odd update");
    // moves of up to 0.3 agrid: some stencils change, new nodes are appended
    for (std::size_t i = 0; i < particles.n_local(); ++i) {
      Vec3& x = particles.pos[i];
      x += Vec3(small_move(rng), small_move(rng), small_move(rng));
      x[0] = std::fmod(x[0] + 13.0, 13.0);
      x[1] = std::fmod(x[1] + 11.0, 11.0);
      x[2] = std::clamp(x[2], 0.6, 15.4);
    }
    if (step == 30) { // a population set between an update and a pass
      Populations f = fluid.node_populations({6, 5, 5});
      f[1] += 0.01;
      const std::uint64_t version = fluid.state_version();
      fluid.set_node_populations({6, 5, 5}, f);
      EXPECT_NE(fluid.state_version(), version);
    }
  }
  EXPECT_GT(checked, 70u * 400u); // the list covers a good part of the lattice
}

TEST(LbCouplingVelocities, FedByTheUpdateOneThread) {
  run_scene(1);
}
TEST(LbCouplingVelocities, FedByTheUpdateTwoThreads) {
  run_scene(2);
}
TEST(LbCouplingVelocities, FedByTheUpdateThreeThreads) {
  run_scene(3);
}

} // namespace
