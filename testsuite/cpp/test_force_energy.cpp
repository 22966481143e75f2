// Force = -grad(energy), checked numerically for every interaction that has an
// energy, by one table-driven test (HOOMD's test_force_energy_relationship):
// random configurations, central differences with step h = 1e-5 (in units of
// the configuration's length scale), along every coordinate, and the
// requirement |F_fd - F| <= 1e-6 * max|F| (+1e-13): the central-difference
// truncation error is O(h^2) ~ 1e-10 and the round-off O(eps E / h) ~ 1e-11.
//
// The OIF membrane terms run through the membrane component's driver, the
// one the time step uses: forces from System::compute_forces(), energies from
// System::compute_energies(), on one cell (the one-cell path, T = double) and
// on four cells of one type (one batch in vector lanes).
// The OIF area terms (eqs. 5, 6) allocate their force towards the triangle's
// centroid (Jancigova & Cimrak 2016), which is not the gradient of any function
// of the area; their reported energies are the work along a dilation, so for
// them the check runs along dilation directions only (of the bond's points
// for local area, of each cell for global area).
#include "test_oif_mesh.hpp"

#include "interactions/bonded/harmonic.hpp"
#include "interactions/nonbonded/membrane_collision.hpp"
#include "interactions/nonbonded/morse.hpp"
#include "interactions/nonbonded/soft_sphere.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <iostream>
#include <memory>
#include <string>

using namespace pyoif;

namespace {

using Config = std::vector<Vec3>;

/** One interaction as seen by the test: energy and forces of a configuration,
 *  random configurations, and the directions to differentiate along (empty:
 *  every coordinate). */
struct Case {
  std::string name;
  std::function<Config(std::mt19937&)> random_config;
  std::function<double(const Config&)> energy;
  std::function<Config(const Config&)> forces;
  std::function<std::vector<Config>(const Config&)> directions = nullptr;
  double length_scale = 1.0;
};

std::uniform_real_distribution<double> uniform(-1.0, 1.0);

Vec3 random_vec(std::mt19937& rng) {
  return Vec3(uniform(rng), uniform(rng), uniform(rng));
}

/** A bonded interaction with K particles, through its forces(). */
template <class IA, int K>
Case bonded_case(const std::string& name, IA ia, std::vector<double> reference,
                 std::function<Config(std::mt19937&)> config) {
  auto input = [ia, reference](const Config& x) {
    BondInput<K> in;
    for (int k = 0; k < K; ++k) {
      in.x[k] = x[k];
      in.v[k] = Vec3::Zero();
    }
    in.reference = reference.empty() ? nullptr : reference.data();
    return in;
  };
  Case c;
  c.name = name;
  c.random_config = config;
  c.energy = [ia, input](const Config& x) {
    const auto in = input(x);
    std::array<Vec3, K> f;
    double e = 0.0;
    EXPECT_TRUE(ia.forces(in, f, e));
    return e;
  };
  c.forces = [ia, input](const Config& x) {
    const auto in = input(x);
    std::array<Vec3, K> f;
    double e = 0.0;
    EXPECT_TRUE(ia.forces(in, f, e));
    return Config(f.begin(), f.end());
  };
  return c;
}

/** A non-bonded model between two particles with fixed per-particle data. */
template <class Model>
Case pair_case(const std::string& name, typename Model::Params params, PairContext base,
               std::function<Config(std::mt19937&)> config) {
  auto context = [base](const Config& x) {
    PairContext c = base;
    c.d = x[0] - x[1];
    c.dist = c.d.norm();
    return c;
  };
  Case c;
  c.name = name;
  c.random_config = config;
  c.energy = [params, context](const Config& x) { return Model::energy(params, context(x)); };
  c.forces = [params, context](const Config& x) {
    const Vec3 f = Model::force(params, context(x));
    return Config{f, -f};
  };
  return c;
}

/** Two particles at a distance uniform in [lo, hi], random direction. */
std::function<Config(std::mt19937&)> pair_at(double lo, double hi) {
  return [lo, hi](std::mt19937& rng) {
    const Vec3 x0 = random_vec(rng);
    const double r = lo + (hi - lo) * 0.5 * (1.0 + uniform(rng));
    return Config{x0, x0 + r * random_vec(rng).normalized()};
  };
}

/** Membrane bonds in a System (added by `add` to n particles with ids 0 ..
 *  n - 1): forces from compute_forces(), the energy the total bonded energy,
 *  both through the membrane component's driver. */
Case system_case(const std::string& name, std::size_t n,
                 std::function<Config(std::mt19937&)> config,
                 std::function<void(pyoif::System&)> add,
                 std::function<std::vector<Config>(const Config&)> directions = nullptr,
                 double length_scale = 1.0, bool in_lanes = false) {
  auto sys = oif_test::make_system(20.0);
  oif_test::add_cell_particles(*sys, std::vector<Vec3>(n, Vec3(1, 1, 1)), 0);
  add(*sys);
  Case c;
  c.name = name;
  c.length_scale = length_scale;
  c.random_config = config;
  c.energy = [sys](const Config& x) {
    oif_test::set_positions(*sys, x);
    return sys->compute_energies().bonded;
  };
  c.forces = [sys, in_lanes, name](const Config& x) {
    oif_test::set_positions(*sys, x);
    const pyoif::membrane::PassCounts before = sys->membranes.counts;
    Config f = oif_test::forces_of(*sys, x.size());
    // the path meant: four cells in vector lanes, or one cell alone
    const pyoif::membrane::PassCounts& after = sys->membranes.counts;
    EXPECT_EQ(after.lane_batches - before.lane_batches, in_lanes ? 1u : 0u) << name;
    EXPECT_EQ(after.plain_cells - before.plain_cells, in_lanes ? 0u : 1u) << name;
    return f;
  };
  c.directions = directions;
  return c;
}

constexpr int kCells = 4; ///< cells of the batch cases: one group of four vector lanes

/** The unit-cell mesh (radius 2, 42 nodes), shared by the cases. */
std::shared_ptr<const oif_test::Mesh> cell_mesh() {
  static const auto mesh = std::make_shared<const oif_test::Mesh>(oif_test::icosphere(1, 2.0));
  return mesh;
}

/** `cells` copies of the cell mesh, each stretched, rough and randomly
 *  rotated, the first across the periodic face z = L. */
std::function<Config(std::mt19937&)> deformed_cells(int cells) {
  return [cells](std::mt19937& rng) {
    const auto& nodes = cell_mesh()->nodes;
    Config x;
    for (int k = 0; k < cells; ++k) {
      const Vec3 stretch(1.0 + 0.2 * uniform(rng), 1.0 + 0.2 * uniform(rng), 1.0);
      const Eigen::Matrix3d rotation = oif_test::random_rotation(rng);
      const Vec3 centre(5.0 + 10.0 * (k % 2), 5.0 + 10.0 * (k / 2 % 2), k == 0 ? 19.5 : 10.0);
      for (const auto& xi : nodes)
        x.push_back(rotation * (stretch.cwiseProduct(xi) + 0.15 * random_vec(rng)) + centre);
    }
    return x;
  };
}

/** An OIF membrane on `cells` cells of the cell mesh (mol_id k, ids k * 42
 *  ...), its bonds added by add(system, mesh, first id) per cell. */
Case cell_case(const std::string& name, int cells,
               std::function<void(pyoif::System&, const oif_test::Mesh&, int)> add,
               std::function<std::vector<Config>(const Config&)> directions = nullptr) {
  const std::size_t per_cell = cell_mesh()->nodes.size();
  return system_case(
      name + (cells > 1 ? "_lanes" : ""), cells * per_cell, deformed_cells(cells),
      [=](pyoif::System& s) {
        for (int k = 0; k < cells; ++k) {
          for (std::size_t i = 0; i < per_cell; ++i)
            s.particles.mol_id[s.particles.index(static_cast<int>(k * per_cell + i))] = k;
          ++s.particles.mol_version;
          add(s, *cell_mesh(), static_cast<int>(k * per_cell));
        }
      },
      directions, 2.0, cells > 1);
}

/** Relaxed reference values of the cell mesh. */
std::vector<double> cell_references(const oif_test::Mesh& m) {
  return oif_test::angle_references(m, m.nodes);
}

/** One OifLocalForces bond (B, A, C, D) = particles (1, 0, 2, 3) on a pair
 *  of triangles bent by a random angle, randomly placed. */
Case pair_bond_case(const std::string& name, OifLocalForces ia,
                    std::function<Config(std::mt19937&)> config,
                    std::function<std::vector<Config>(const Config&)> directions = nullptr) {
  return system_case(
      name, 4, config,
      [ia](pyoif::System& s) {
        const int id = s.add_bonded_interaction(ia);
        s.add_bonds(id, {1, 0, 2, 3}, {1.1, 2.9, 0.45, 0.5}); // r0, phi0, A01, A02
      },
      directions);
}

/** Dilation directions: of all points about their centroid, per group of
 *  `size` consecutive points (a cell). */
std::function<std::vector<Config>(const Config&)> dilations(std::size_t size) {
  return [size](const Config& x) {
    std::vector<Config> out;
    for (std::size_t first = 0; first < x.size(); first += size) {
      Vec3 c = Vec3::Zero();
      for (std::size_t i = first; i < first + size; ++i)
        c += x[i];
      c /= static_cast<double>(size);
      Config d(x.size(), Vec3::Zero());
      for (std::size_t i = first; i < first + size; ++i)
        d[i] = x[i] - c;
      out.push_back(d);
    }
    return out;
  };
}

std::vector<Case> cases() {
  std::vector<Case> out;
  const auto four_points = [](std::mt19937& rng) {
    // two triangles on a common edge, bent by a random angle, randomly placed
    Config x = {Vec3(0.1, 0.9, 0.0), Vec3(0, 0, 0), Vec3(1.0, 0.1, 0.0), Vec3(0.6, -0.8, 0.0)};
    for (auto& xi : x)
      xi += 0.3 * random_vec(rng) + Vec3(5, 5, 5);
    return x;
  };
  const auto edge = [](std::mt19937& rng) {
    const Vec3 x0 = random_vec(rng);
    return Config{x0, x0 + (0.5 + 0.3 * (1.0 + uniform(rng))) * random_vec(rng).normalized()};
  };
  // ---- generic interactions
  out.push_back(bonded_case<HarmonicBond, 2>("harmonic", HarmonicBond{2.5, 0.8, 0.0}, {}, edge));
  PairContext plain;
  plain.d = plain.normal_i = plain.normal_j = Vec3::Zero();
  plain.dist = 0.0;
  plain.mol_i = 0;
  plain.mol_j = 1;
  out.push_back(
      pair_case<SoftSphere>("soft_sphere", {0.3, 2.5, 1.2, 0.1}, plain, pair_at(0.3, 1.25)));
  // Morse on both sides of its minimum (rmin = 1), up to just below the cutoff
  out.push_back(
      pair_case<Morse>("morse", Morse::make(1.3, 2.0, 1.0, 2.2), plain, pair_at(0.5, 2.1)));
  PairContext facing = plain;
  facing.normal_i = Vec3(0.3, 0.9, -0.2).normalized();
  facing.normal_j = Vec3(-0.5, -0.7, 0.4).normalized();
  // membrane collision with fixed normals, on both sides of the crossing:
  // x_i - x_j along -u (not crossed) or +u (crossed), u = n_i - n_j
  const Vec3 u = (facing.normal_i - facing.normal_j).normalized();
  for (const double side : {-1.0, 1.0})
    out.push_back(pair_case<MembraneCollision>(
        side < 0 ? "membrane_collision" : "membrane_collision_crossed", {0.05, 8.0, 0.6, 0.05},
        facing, [u, side](std::mt19937& rng) {
          const Vec3 x0 = random_vec(rng);
          const Vec3 dir = (side * u + 0.5 * random_vec(rng)).normalized();
          return Config{x0 + (0.1 + 0.25 * (1.0 + uniform(rng))) * dir, x0};
        }));
  // ---- OIF terms, each on its own, on one bond (one triangle pair)
  out.push_back(pair_bond_case("oif_stretching", OifLocalForces{0.7, 0, 0, 0, 0}, four_points));
  out.push_back(
      pair_bond_case("oif_stretching_linear", OifLocalForces{0, 0.7, 0, 0, 0}, four_points));
  out.push_back(pair_bond_case("oif_bending", OifLocalForces{0, 0, 0.7, 0, 0}, four_points));
  // neo-Hookean edge over a wide strain range (lambda 0.3 .. 3)
  out.push_back(pair_bond_case(
      "oif_stretching_large_strain", OifLocalForces{0.7, 0, 0, 0, 0}, [](std::mt19937& rng) {
        Config x = {Vec3(0.1, 0.9, 0.0), Vec3(0, 0, 0), Vec3(1.0, 0.1, 0.0), Vec3(0.6, -0.8, 0.0)};
        x[2] = x[1] + (0.3 + 1.35 * (1.0 + uniform(rng))) * 1.1 * random_vec(rng).normalized();
        for (auto& xi : x)
          xi += Vec3(5, 5, 5);
        return x;
      }));
  // local area (eq. 5, a third on each of the bond's two triangles) along the
  // dilation of the four points: it dilates each triangle about a moving
  // point, and a triangle's centroid-allocated forces do no work in a translation
  out.push_back(pair_bond_case("oif_local_area_pair", OifLocalForces{0, 0, 0, 0.9, 0}, four_points,
                               dilations(4)));
  // ---- whole cells: one (the one-cell path) and four (one batch in vector lanes)
  const std::size_t per_cell = cell_mesh()->nodes.size();
  const auto local = [](OifLocalForces ia) {
    return [ia](pyoif::System& s, const oif_test::Mesh& m, int first) {
      const int id = s.add_bonded_interaction(ia);
      s.add_bonds(id, oif_test::local_bond_ids(m, first), cell_references(m));
    };
  };
  const auto global = [](double area0, double kag, double volume0, double kv) {
    return [=](pyoif::System& s, const oif_test::Mesh& m, int first) {
      OifGlobalForces g;
      g.A0_g = area0;
      g.ka_g = kag;
      g.V0 = volume0;
      g.kv = kv;
      const int id = s.add_bonded_interaction(g);
      s.add_bonds(id, oif_test::triangle_bond_ids(m, first), {});
    };
  };
  for (const int cells : {1, kCells}) {
    out.push_back(cell_case("oif_volume", cells, global(1.0, 0.0, 30.0, 0.8)));
    out.push_back(cell_case("oif_bending_cell", cells, local(OifLocalForces{0, 0, 0.6, 0, 0})));
    out.push_back(
        cell_case("oif_stretching_cell", cells, local(OifLocalForces{0.5, 0.2, 0, 0, 0})));
    out.push_back(
        cell_case("oif_stretching_linear_cell", cells, local(OifLocalForces{0, 0.4, 0, 0, 0})));
    // the area terms along each cell's dilation (see above)
    out.push_back(cell_case("oif_local_area_cell", cells, local(OifLocalForces{0, 0, 0, 0.6, 0}),
                            dilations(per_cell)));
    out.push_back(
        cell_case("oif_global_area", cells, global(40.0, 0.9, 1.0, 0.0), dilations(per_cell)));
  }
  return out;
}

class ForceEnergy : public ::testing::TestWithParam<int> {};

} // namespace

TEST_P(ForceEnergy, ForceIsMinusGradient) {
  static const std::vector<Case> all = cases();
  const Case& c = all[GetParam()];
  std::mt19937 rng(1234 + GetParam());
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    const Config x = c.random_config(rng);
    const Config f = c.forces(x);
    double fmax = 0.0;
    for (const auto& fi : f)
      fmax = std::max(fmax, fi.norm());
    ASSERT_GT(fmax, 1e-8) << c.name << ": the configuration must load the interaction";
    std::vector<Config> dirs;
    if (c.directions) {
      dirs = c.directions(x);
    } else {
      for (std::size_t i = 0; i < x.size(); ++i)
        for (int d = 0; d < 3; ++d) {
          Config e(x.size(), Vec3::Zero());
          e[i][d] = 1.0;
          dirs.push_back(e);
        }
    }
    const double h = 1e-5 * c.length_scale;
    for (const Config& dir : dirs) {
      double norm2 = 0.0, f_along = 0.0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        norm2 += dir[i].squaredNorm();
        f_along += f[i].dot(dir[i]);
      }
      const double scale = 1.0 / std::sqrt(norm2);
      Config xp(x), xm(x);
      for (std::size_t i = 0; i < x.size(); ++i) {
        xp[i] += h * scale * dir[i];
        xm[i] -= h * scale * dir[i];
      }
      const double fd = -(c.energy(xp) - c.energy(xm)) / (2.0 * h);
      const double err = std::abs(fd - f_along * scale);
      worst = std::max(worst, err / fmax);
      EXPECT_LE(err, 1e-6 * fmax + 1e-13) << c.name << " trial " << trial;
    }
  }
  std::cout << "[ figure ] " << c.name << ": max |F_fd - F| / max|F| = " << worst << "\n";
}

INSTANTIATE_TEST_SUITE_P(AllInteractions, ForceEnergy,
                         ::testing::Range(0, static_cast<int>(cases().size())),
                         [](const ::testing::TestParamInfo<int>& param_info) {
                           static const std::vector<Case> all = cases();
                           return all[param_info.param].name;
                         });
