// Neighbour search: the Verlet pair list (linked cells + ghosts for periodic
// images) must contain exactly the brute-force set of pairs within the cutoff,
// each physical pair-and-image once, for random configurations.
#include "particles/cell_system.hpp"
#include "system/system.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>

using namespace pyoif;

namespace {

using PairKey = std::tuple<int, int, int, int, int>; // id_a < id_b, image shift of b

// Brute force: every pair and every periodic image of b (|shift| <= 1 per axis,
// enough while the cutoff is below the box length), counted once.
std::map<PairKey, int> brute_force(const ParticleStore& p, const BoxGeometry& box, double cutoff) {
  std::map<PairKey, int> out;
  const std::size_t n = p.n_local();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i; j < n; ++j)
      for (int sx = -1; sx <= 1; ++sx)
        for (int sy = -1; sy <= 1; ++sy)
          for (int sz = -1; sz <= 1; ++sz) {
            const Vec3i s(sx, sy, sz);
            bool ok = true;
            for (int d = 0; d < 3; ++d)
              ok &= box.periodic()[d] || s[d] == 0;
            if (!ok || (i == j && s == Vec3i::Zero()))
              continue;
            const Vec3 xb = p.pos[j] + s.cast<double>().cwiseProduct(box.length());
            if ((p.pos[i] - xb).norm() >= cutoff)
              continue;
            int a = p.id[i], b = p.id[j];
            Vec3i shift = s;
            if (a > b ||
                (a == b && (s[0] < 0 || (s[0] == 0 && (s[1] < 0 || (s[1] == 0 && s[2] < 0)))))) {
              std::swap(a, b);
              shift = -s;
            }
            out[{a, b, shift[0], shift[1], shift[2]}] += 1;
          }
  return out;
}

std::map<PairKey, int> from_cells(const System& s, double cutoff) {
  std::map<PairKey, int> out;
  const auto& p = s.particles;
  for (const auto& pr : s.cells.pairs()) {
    const Vec3 d = p.position(pr[0]) - p.position(pr[1]);
    if (d.norm() >= cutoff)
      continue;
    const int ia = pr[0];
    const int ib = p.owner(pr[1]);
    Vec3i shift = static_cast<std::size_t>(pr[1]) < p.n_local()
                      ? Vec3i::Zero()
                      : Vec3i(p.ghost_shift[pr[1] - p.n_local()]);
    int a = p.id[ia], b = p.id[ib];
    if (a > b ||
        (a == b &&
         (shift[0] < 0 || (shift[0] == 0 && (shift[1] < 0 || (shift[1] == 0 && shift[2] < 0)))))) {
      std::swap(a, b);
      shift = -shift;
    }
    out[{a, b, shift[0], shift[1], shift[2]}] += 1;
  }
  return out;
}

struct Case {
  Vec3 box;
  std::array<bool, 3> periodic;
  int n;
  double cutoff, skin;
};

} // namespace

class NeighbourSearch : public ::testing::TestWithParam<Case> {};

TEST_P(NeighbourSearch, MatchesBruteForceExactly) {
  const Case c = GetParam();
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 5; ++trial) {
    System s(c.box, c.periodic);
    s.cells.skin = c.skin;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < c.n; ++i) {
      Vec3 x(u(rng) * c.box[0], u(rng) * c.box[1], u(rng) * c.box[2]);
      // ids with gaps, to exercise the id -> index map
      s.add_particle(3 * i + trial, x, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
    }
    s.set_nonbonded<SoftSphere>(0, 0, {1.0, 12.0, c.cutoff, 0.0});
    s.compute_forces();
    const auto expected = brute_force(s.particles, s.box, c.cutoff);
    const auto found = from_cells(s, c.cutoff);
    ASSERT_EQ(found.size(), expected.size()) << "trial " << trial;
    for (const auto& [key, count] : found) {
      EXPECT_EQ(count, 1) << "pair found more than once";
      EXPECT_EQ(expected.count(key), 1u) << "pair not within cutoff by brute force";
    }
    // Move particles by less than skin/2: the list must still cover all pairs.
    std::normal_distribution<double> g(0.0, 0.1 * c.skin);
    for (auto& x : s.particles.pos)
      x += Vec3(g(rng), g(rng), g(rng)).cwiseMin(0.2 * c.skin).cwiseMax(-0.2 * c.skin);
    const auto rebuilds = s.cells.n_rebuilds();
    s.compute_forces();
    EXPECT_EQ(s.cells.n_rebuilds(), rebuilds) << "no re-sort expected for moves below skin/2";
    const auto expected2 = brute_force(s.particles, s.box, c.cutoff);
    const auto found2 = from_cells(s, c.cutoff);
    EXPECT_EQ(found2.size(), expected2.size());
    for (const auto& [key, count] : expected2)
      EXPECT_EQ(found2.count(key), 1u) << "pair missed after moves within the skin";
  }
}

INSTANTIATE_TEST_SUITE_P(
    RandomConfigurations, NeighbourSearch,
    ::testing::Values(Case{{10, 10, 10}, {true, true, true}, 300, 1.5, 0.4},
                      Case{{10, 7, 13}, {true, false, true}, 300, 1.2, 0.3},
                      Case{{12, 12, 12}, {false, false, false}, 300, 2.0, 0.5},
                      // small box: range close to L, images of a particle itself
                      Case{{3, 3, 3}, {true, true, true}, 40, 1.4, 0.2},
                      Case{{2.5, 20, 20}, {true, true, false}, 100, 1.5, 0.4}));

TEST(NeighbourSearch, ExclusionsAreHonoured) {
  System s({5, 5, 5}, {true, true, true});
  s.add_particle(0, {1, 1, 1}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.add_particle(1, {1.5, 1, 1}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.add_particle(2, {4.8, 1, 1}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0); // image at -0.2
  s.set_nonbonded<SoftSphere>(0, 0, {1.0, 2.0, 1.5, 0.0});
  s.compute_forces();
  EXPECT_EQ(s.cells.pairs().size(), 3u);
  s.cells.add_exclusion(2, 0);
  s.compute_forces();
  EXPECT_EQ(s.cells.pairs().size(), 2u);
  // either order of the ids, several per particle, removal
  s.cells.add_exclusion(0, 1);
  s.compute_forces();
  ASSERT_EQ(s.cells.pairs().size(), 1u);
  EXPECT_TRUE(s.cells.excluded(1, 0) && s.cells.excluded(0, 2) && !s.cells.excluded(1, 2));
  s.cells.remove_exclusion(0, 2);
  s.compute_forces();
  EXPECT_EQ(s.cells.pairs().size(), 2u);
  EXPECT_FALSE(s.cells.excluded(2, 0));
  EXPECT_FALSE(s.cells.excluded(7, 0)); // an id that has never been seen
  s.cells.remove_exclusions_of(1);
  s.compute_forces();
  EXPECT_EQ(s.cells.pairs().size(), 3u);
  // a pair added twice (either order) is one pair, which one removal takes
  s.cells.add_exclusion(1, 2);
  s.cells.add_exclusion(2, 1);
  s.cells.add_exclusion(0, 2);
  EXPECT_TRUE(s.cells.excluded(2, 1)); // read before any pair build
  EXPECT_EQ(s.cells.exclusion_pairs(), (std::vector<std::array<int, 2>>{{0, 2}, {1, 2}}));
  s.cells.remove_exclusion(1, 2);
  EXPECT_FALSE(s.cells.excluded(1, 2));
  s.compute_forces();
  EXPECT_EQ(s.cells.pairs().size(), 2u);
}

TEST(NeighbourSearch, RangeLargerThanBoxIsAnError) {
  System s({2, 10, 10}, {true, true, true});
  s.add_particle(0, {1, 1, 1}, Vec3::Zero(), 1.0, 0, 0, Vec3::Zero(), 0);
  s.set_nonbonded<SoftSphere>(0, 0, {1.0, 2.0, 2.5, 0.0});
  EXPECT_THROW(s.compute_forces(), InputError);
}
