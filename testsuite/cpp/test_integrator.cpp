// Velocity Verlet: NVE energy conservation with soft-sphere + harmonic-bond
// forces (error bounded and scaling as time_step^2), momentum conservation to
// round-off, bonds across the periodic boundary.
#include "shapes/wall.hpp"
#include "system/system.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace pyoif;

namespace {

/** A periodic box of bonded chains with soft-sphere repulsion between all
 *  particles, random thermal velocities with zero total momentum. */
System make_chains(double dt) {
  System s({8, 8, 8}, {true, true, true});
  s.set_time_step(dt);
  s.cells.skin = 0.3;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  int pid = 0;
  Vec3 momentum = Vec3::Zero();
  // 6x6 chains of 6 particles along z, spacing 1.3 (inside the soft-sphere range)
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) {
        const Vec3 x(0.4 + 1.3 * i + u(rng), 0.4 + 1.3 * j + u(rng), 0.4 + 1.3 * k + u(rng));
        const Vec3 v(g(rng), g(rng), g(rng));
        const double m = 1.0 + 0.5 * (pid % 3);
        momentum += m * v;
        s.add_particle(pid++, x, v, m, 0, i * 6 + j, Vec3::Zero(), 0);
      }
  const double total_mass = [&] {
    double M = 0;
    for (double m : s.particles.mass)
      M += m;
    return M;
  }();
  for (std::size_t i = 0; i < s.particles.n_local(); ++i)
    s.particles.vel[i] -= momentum / total_mass;
  // soft sphere with a cutoff where the potential is negligible (V(rc) = 3.8e-7,
  // so crossing the cutoff does not spoil energy conservation)
  s.set_nonbonded<SoftSphere>(0, 0, {0.2, 12.0, 3.0, 0.0});
  const int bond = s.add_bonded_interaction(HarmonicBond{20.0, 1.3, 0.0});
  std::vector<int> ids;
  for (int c = 0; c < 36; ++c)
    for (int k = 0; k + 1 < 6; ++k) {
      ids.push_back(c * 6 + k);
      ids.push_back(c * 6 + k + 1);
    }
  s.add_bonds(bond, ids, {});
  return s;
}

/** Root-mean-square of (E(t) - E(0)) / E_kin(0) over a fixed physical time
 *  (100 samples; the RMS is less noisy than the maximum in a chaotic system). */
double energy_error(double dt, double duration, double* drift = nullptr) {
  System s = make_chains(dt);
  const double e0 = s.compute_energies().total();
  const double ekin0 = s.compute_energies().kinetic;
  const int n_chunks = 100;
  const int steps = static_cast<int>(std::lround(duration / dt / n_chunks));
  double sum2 = 0.0;
  double e_last = e0;
  for (int c = 0; c < n_chunks; ++c) {
    s.integrate(steps);
    e_last = s.compute_energies().total();
    sum2 += std::pow((e_last - e0) / ekin0, 2);
  }
  if (drift)
    *drift = (e_last - e0) / ekin0;
  return std::sqrt(sum2 / n_chunks);
}

} // namespace

TEST(VelocityVerlet, EnergyErrorBoundedAndScalesAsTimeStepSquared) {
  // 10^4 steps at dt = 0.002; the same physical time at 2 dt and dt/2.
  const double duration = 1e4 * 0.002;
  double drift = 0.0;
  const double err_double = energy_error(0.004, duration);
  const double err1 = energy_error(0.002, duration, &drift);
  const double err2 = energy_error(0.001, duration);
  // Bound: the energy error stays below 1e-3 of the initial kinetic energy
  // and there is no secular drift beyond that.
  EXPECT_LT(err1, 1e-3);
  EXPECT_LT(std::abs(drift), 1e-3);
  // Second order: halving dt divides the error by 4 (accept 3..5.5; the
  // measured ratios are printed).
  std::printf("RMS energy error / E_kin: dt=0.004 %.3e, 0.002 %.3e, 0.001 %.3e; ratios %.2f %.2f\n",
              err_double, err1, err2, err_double / err1, err1 / err2);
  EXPECT_GT(err_double / err1, 3.0);
  EXPECT_LT(err_double / err1, 5.5);
  EXPECT_GT(err1 / err2, 3.0);
  EXPECT_LT(err1 / err2, 5.5);
}

TEST(VelocityVerlet, MomentumConservedToRoundOff) {
  System s = make_chains(0.002);
  const Vec3 p0 = s.particle_momentum();
  s.integrate(5000);
  const Vec3 p1 = s.particle_momentum();
  // |p| of one particle is O(1); round-off accumulates over 5000 steps of
  // 216 particles: allow 1e-11.
  EXPECT_LT((p1 - p0).norm(), 1e-11) << (p1 - p0).transpose();
  EXPECT_GT(s.cells.n_rebuilds(), 2u) << "particles must have crossed cells and the boundary";
}

TEST(PeriodicImages, BondAcrossTheBoundary) {
  System s({10, 10, 10}, {true, true, true});
  s.add_particle(0, {0.1, 5, 5}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.add_particle(1, {9.9, 5, 5}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  const int bond = s.add_bonded_interaction(HarmonicBond{3.0, 0.5, 1.0});
  s.add_bonds(bond, {0, 1}, {});
  s.compute_forces();
  // minimum-image distance 0.2: compressed by 0.3, particle 0 pushed to +x
  EXPECT_NEAR(s.particles.force[0][0], 3.0 * 0.3, 1e-12);
  EXPECT_NEAR(s.particles.force[1][0], -3.0 * 0.3, 1e-12);
  EXPECT_NEAR(s.particles.force[0][1], 0.0, 1e-15);
}

TEST(PeriodicImages, PairForceThroughGhostsAndUnfoldedTrajectory) {
  System s({6, 6, 6}, {true, true, true});
  s.set_time_step(0.01);
  s.add_particle(0, {0.2, 3, 3}, {-1.0, 0, 0}, 1.0, 0, 0, Vec3::Zero(), 0);
  s.add_particle(1, {5.3, 3, 3}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.set_nonbonded<SoftSphere>(0, 0, {1.0, 2.0, 1.5, 0.0});
  s.compute_forces();
  // distance through the boundary 0.9: force n a r^-(n+1) = 2 / 0.9^3
  EXPECT_NEAR(s.particles.force[0][0], 2.0 / std::pow(0.9, 3), 1e-12);
  EXPECT_NEAR(s.particles.force[1][0], -2.0 / std::pow(0.9, 3), 1e-12);
  s.integrate(100);
  // particle 0 bounced back: momentum conserved, positions folded into the box
  EXPECT_NEAR(s.particle_momentum()[0], -1.0, 1e-12);
  for (std::size_t i = 0; i < 2; ++i)
    EXPECT_TRUE(s.particles.pos[i][0] > -0.5 && s.particles.pos[i][0] < 6.5);
}

// A change of the force field between two runs through System's methods
// (non-bonded parameters, exclusions, thermostat) reaches the next run's
// first half kick: v(dt) = v(0) + dt/2 (F(x0) + F(x1)) / m with the new F.
namespace {
System two_particles_at_rest() {
  System s({8, 8, 8}, {true, true, true});
  s.set_time_step(0.01);
  s.add_particle(0, {3.0, 4.0, 4.0}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.add_particle(1, {4.0, 4.0, 4.0}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  return s;
}
/** x-force on particle 0 of the soft sphere V = 1 / r^2 (a = 1, n = 2) with
 *  particle 1 at +x, separation r: pushed to -x. */
double pair_force_x(double r) {
  return -2.0 / (r * r * r);
}
} // namespace

TEST(ForcesBetweenRuns, NewPairParametersReachTheFirstHalfKick) {
  System s = two_particles_at_rest();
  s.integrate(1); // no interaction yet: nothing moves
  ASSERT_EQ(s.particles.vel[0][0], 0.0);
  s.set_nonbonded<SoftSphere>(0, 0, {1.0, 2.0, 1.5, 0.0});
  s.integrate(1);
  const double r1 = s.particles.pos[1][0] - s.particles.pos[0][0];
  const double expected = 0.005 * (pair_force_x(1.0) + pair_force_x(r1));
  // with the old (zero) forces in the first half kick it would be 0.005 F(x1)
  EXPECT_NEAR(s.particles.vel[0][0], expected, 1e-12);
}

TEST(ForcesBetweenRuns, NewExclusionReachesTheFirstHalfKick) {
  System s = two_particles_at_rest();
  s.set_nonbonded<SoftSphere>(0, 0, {1.0, 2.0, 1.5, 0.0});
  s.integrate(1);
  const Vec3 v_before = s.particles.vel[0];
  s.add_exclusion(0, 1);
  s.integrate(1);
  // no force in either half kick (the old force would add 0.005 F)
  EXPECT_NEAR((s.particles.vel[0] - v_before).norm(), 0.0, 1e-15);
  s.remove_exclusion(0, 1);
  const Vec3 x0 = s.particles.pos[0], x1 = s.particles.pos[1];
  s.integrate(1);
  const double expected =
      v_before[0] + 0.005 * (pair_force_x(x1[0] - x0[0]) +
                             pair_force_x(s.particles.pos[1][0] - s.particles.pos[0][0]));
  EXPECT_NEAR(s.particles.vel[0][0], expected, 1e-12);
}

TEST(ForcesBetweenRuns, LangevinSwitchedOnReachesTheFirstHalfKick) {
  System s = two_particles_at_rest();
  s.particles.vel[0] = Vec3(1.0, 0.0, 0.0);
  s.invalidate_forces(); // a direct write to the particle store
  s.integrate(1);        // no friction yet: v stays 1
  ASSERT_DOUBLE_EQ(s.particles.vel[0][0], 1.0);
  s.set_langevin({true, 0.0, 2.0, 0}); // kT 0: friction -gamma v only
  s.integrate(1);
  // v1 = v0 + dt/2 (-g v0) + dt/2 (-g v_half) with v_half = v0 (1 - g dt/2)
  // (the velocity the second force evaluation sees)
  const double g = 2.0, h = 0.005, v0 = 1.0, v_half = v0 - h * g * v0;
  EXPECT_NEAR(s.particles.vel[0][0], v_half - h * g * v_half, 1e-14);
}

TEST(ForcesBetweenRuns, ConstraintAddedAndRemovedReachesTheFirstHalfKick) {
  System s = two_particles_at_rest();
  s.set_nonbonded<SoftSphere>(0, 1, {1.0, 2.0, 1.2, 0.0}); // particle type 0, wall type 1
  s.integrate(1);                                          // no constraint yet: nothing moves
  ASSERT_EQ(s.particles.vel[0][0], 0.0);
  // wall at x = 2.5 facing +x: particle 0 (x = 3) within the cutoff, 1 (x = 4) not
  auto wall = std::make_shared<ShapeBasedConstraint>();
  wall->shape = std::make_shared<shapes::Wall>(Vec3(1, 0, 0), 2.5);
  wall->particle_type = 1;
  s.add_constraint(wall);
  s.integrate(1);
  auto wall_force = [](double d) { return 2.0 / (d * d * d); }; // -dV/dd, V = 1 / d^2
  const double v1 = 0.005 * (wall_force(0.5) + wall_force(s.particles.pos[0][0] - 2.5));
  EXPECT_NEAR(s.particles.vel[0][0], v1, 1e-12);
  EXPECT_EQ(s.particles.vel[1][0], 0.0);
  s.remove_constraint(wall);
  s.integrate(1);
  // no force in either half kick (the old wall force would add 0.005 F)
  EXPECT_NEAR(s.particles.vel[0][0], v1, 1e-15);
}
