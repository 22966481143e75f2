// OIF membrane moduli on closed meshes (issue 4 tests): on a randomly deformed
// and randomly rotated icosphere each modulus gives zero total force and
// torque (to round-off); the relaxed mesh, rotated and moved across the
// periodic boundary, feels no force; the per-cell surface and volume of the
// icosahedron match its analytic values and converge to the sphere's; node
// normals point out of the cell for either triangle orientation; membrane
// collision pushes two cells apart and reverses when the membranes have crossed.
#include "test_oif_mesh.hpp"

#include "interactions/nonbonded/membrane_collision.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <functional>
#include <iostream>
#include <string>

using namespace pyoif;
using oif_test::Mesh;

namespace {

constexpr double R = 3.0; // sphere radius (PyOIF-like lattice units)

/** One modulus switched on; everything else zero. add(system, mesh,
 *  relaxed, first): the bonds of the cell whose nodes are the particles
 *  first .. first + nodes - 1. */
struct Modulus {
  std::string name;
  std::function<void(System&, const Mesh&, const std::vector<Vec3>& relaxed, int first)> add;
};

void add_local(System& s, const Mesh& m, const std::vector<Vec3>& relaxed, OifLocalForces ia,
               int first = 0) {
  const int id = s.add_bonded_interaction(ia);
  s.add_bonds(id, oif_test::local_bond_ids(m, first), oif_test::angle_references(m, relaxed));
}
void add_global(System& s, const Mesh& m, const std::vector<Vec3>& relaxed, double kag, double kv,
                bool flip = false, int first = 0) {
  OifGlobalForces g;
  g.ka_g = kag;
  g.kv = kv;
  // relaxed surface and volume from the same sums the interaction uses
  auto tmp = oif_test::make_system(s.box.length()[0]);
  oif_test::add_cell_particles(*tmp, relaxed, 0);
  const int probe = tmp->add_bonded_interaction(OifOutDirection{});
  tmp->add_bonds(probe, oif_test::triangle_bond_ids(m), {});
  const auto [area, volume] = oif_test::cell_area_volume(*tmp, probe).at(0);
  g.A0_g = area;
  g.V0 = std::abs(volume);
  const int id = s.add_bonded_interaction(g);
  s.add_bonds(id, oif_test::triangle_bond_ids(m, first, flip), {});
}

std::vector<Modulus> moduli() {
  auto local = [](double ks, double kslin, double kb, double kal, double kvisc) {
    return [=](System& s, const Mesh& m, const std::vector<Vec3>& x0, int first) {
      add_local(s, m, x0, OifLocalForces{ks, kslin, kb, kal, kvisc}, first);
    };
  };
  auto global = [](double kag, double kv) {
    return [=](System& s, const Mesh& m, const std::vector<Vec3>& x0, int first) {
      add_global(s, m, x0, kag, kv, false, first);
    };
  };
  return {{"stretching", local(1.0, 0, 0, 0, 0)},
          {"stretching_linear", local(0, 1.0, 0, 0, 0)},
          {"bending", local(0, 0, 1.0, 0, 0)},
          {"local_area", local(0, 0, 0, 1.0, 0)},
          {"visc", local(0, 0, 0, 0, 1.0)},
          {"global_area", global(1.0, 0.0)},
          {"volume", global(0.0, 1.0)}};
}

/** `cells` copies of mesh m placed by place(cell, node) (cell k: mol_id k,
 *  particles k * nodes ...), with velocities v(cell, node), and the modulus'
 *  bonds on each; the membrane pass then takes them one at a time (1 cell)
 *  or as one batch of four vector lanes (4 cells). */
std::shared_ptr<System> cells_with(const Mesh& m, int cells, const Modulus& mod,
                                   const std::function<Vec3(int, std::size_t)>& place,
                                   const std::function<Vec3(int, std::size_t)>& velocity,
                                   double box = 50.0) {
  auto s = oif_test::make_system(box);
  const std::size_t n = m.nodes.size();
  for (int k = 0; k < cells; ++k) {
    std::vector<Vec3> x(n), v(n);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] = place(k, i);
      v[i] = velocity(k, i);
    }
    oif_test::add_cell_particles(*s, x, k, static_cast<int>(k * n), &v);
    mod.add(*s, m, m.nodes, static_cast<int>(k * n));
  }
  return s;
}

/** The relaxed icosphere (level 2: 162 nodes, 320 triangles, 480 angles). */
const Mesh& mesh() {
  static const Mesh m = oif_test::icosphere(2, R);
  return m;
}

} // namespace

TEST(OifMembrane, IcosphereIsClosedAndOutward) {
  const Mesh& m = mesh();
  EXPECT_EQ(m.nodes.size(), 162u);
  EXPECT_EQ(m.triangles.size(), 320u);
  EXPECT_EQ(m.angles.size(), 480u); // = edges: every edge in exactly one pair
  auto s = oif_test::make_system();
  oif_test::add_cell_particles(*s, m.nodes, 0);
  const int id = s->add_bonded_interaction(OifOutDirection{});
  s->add_bonds(id, oif_test::triangle_bond_ids(m), {});
  EXPECT_GT(oif_test::cell_area_volume(*s, id).at(0).second, 0.0);
}

// Every modulus on randomly deformed, randomly rotated meshes: each cell's
// total force and torque vanish, for one cell (the one-cell path) and four
// (one batch of vector lanes). Tolerance 1e-12 relative to sum |F_i| (and R
// sum |F_i| for the torque): round-off of ~1e3 additions of O(1) terms is
// ~1e-13.
TEST(OifMembrane, ForceAndTorqueFree) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  for (const int cells : {1, 4})
    for (const auto& mod : moduli())
      for (int trial = 0; trial < 3; ++trial) {
        std::vector<Eigen::Matrix3d> rot;
        std::vector<Vec3> stretch, shift;
        for (int k = 0; k < cells; ++k) {
          rot.push_back(oif_test::random_rotation(rng));
          stretch.emplace_back(1.0 + 0.2 * u(rng), 1.0 + 0.2 * u(rng), 1.0 + 0.2 * u(rng));
          shift.emplace_back(12.0 + 25.0 * (k % 2) + 3 * u(rng), 12.0 + 25.0 * (k / 2) + 3 * u(rng),
                             25.0 + 5 * u(rng));
        }
        auto s = cells_with(
            m, cells, mod,
            [&](int k, std::size_t i) {
              const Vec3 noise(u(rng), u(rng), u(rng));
              return Vec3(rot[k] * (stretch[k].cwiseProduct(m.nodes[i]) + 0.1 * noise) + shift[k]);
            },
            [&](int, std::size_t) { return Vec3(u(rng), u(rng), u(rng)); });
        const auto before = s->membranes.counts;
        const auto x = oif_test::positions_of(*s, cells * n);
        const auto f = oif_test::forces_of(*s, cells * n);
        EXPECT_EQ(s->membranes.counts.lane_batches - before.lane_batches, cells > 1 ? 1u : 0u);
        for (int k = 0; k < cells; ++k) {
          Vec3 total = Vec3::Zero(), torque = Vec3::Zero();
          double scale = 0.0;
          for (std::size_t i = k * n; i < (k + 1) * n; ++i) {
            total += f[i];
            torque += (x[i] - shift[k]).cross(f[i]);
            scale += f[i].norm();
          }
          ASSERT_GT(scale, 1e-3) << mod.name << ": the deformation must load the modulus";
          if (k == 0)
            std::cout << "[ figure ] " << mod.name << " (" << cells << " cells) trial " << trial
                      << ": |sum F| / sum|F| = " << total.norm() / scale
                      << ", |torque| / (R sum|F|) = " << torque.norm() / (scale * R) << "\n";
          EXPECT_LT(total.norm(), 1e-12 * scale) << mod.name << " trial " << trial << " cell " << k;
          EXPECT_LT(torque.norm(), 1e-12 * scale * R)
              << mod.name << " trial " << trial << " cell " << k;
        }
      }
}

// Each modulus as composed by the bonds equals the model's equation evaluated
// directly, per node: eq. 3 on every edge once (stretching lives on the one
// triangle pair that owns the edge), eq. 5 on every triangle once (a third in
// each of its three pairs), eqs. 6 and 7 with the cell's surface and volume.
// Tolerance 1e-12 relative to max |F|.
TEST(OifMembrane, ModuliMatchModelEquations) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = Vec3(1.2, 0.9, 1.0).cwiseProduct(m.nodes[i]) + 0.1 * Vec3(u(rng), u(rng), u(rng));
  const double k = 0.7;
  // relaxed and current cell surface and volume, directly
  auto surface_volume = [&](const std::vector<Vec3>& y) {
    double s = 0.0, v = 0.0;
    for (const auto& t : m.triangles) {
      s += 0.5 * (y[t[1]] - y[t[0]]).cross(y[t[2]] - y[t[0]]).norm();
      v += y[t[0]].dot(y[t[1]].cross(y[t[2]])) / 6.0;
    }
    return std::make_pair(s, v);
  };
  const auto [S0, V0] = surface_volume(m.nodes);
  const auto [S, V] = surface_volume(x);
  auto centroid_term = [&](std::vector<Vec3>& f, const std::array<int, 3>& t, double c) {
    const Vec3 T = (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
    double sum = 0.0;
    for (int i : t)
      sum += (T - x[i]).squaredNorm();
    for (int i : t)
      f[i] += c / sum * (T - x[i]);
  };
  auto area = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return 0.5 * (b - a).cross(c - a).norm();
  };
  struct Expect {
    std::string name;
    std::function<void(System&)> add;
    std::vector<Vec3> f;
  };
  std::vector<Expect> expected;
  { // eq. 3, neo-Hookean
    std::vector<Vec3> f(n, Vec3::Zero());
    for (const auto& e : m.edges) {
      const double l0 = (m.nodes[e[1]] - m.nodes[e[0]]).norm();
      const Vec3 ab = x[e[1]] - x[e[0]];
      const double l = ab.norm(), lam = l / l0;
      const double kappa = (std::sqrt(lam) + std::pow(lam, -2.5)) / (lam + std::pow(lam, -3.0));
      f[e[0]] += k * kappa * (l - l0) * ab / l;
      f[e[1]] -= k * kappa * (l - l0) * ab / l;
    }
    expected.push_back({"stretching",
                        [&](System& s) {
                          add_local(s, m, m.nodes, OifLocalForces{k, 0, 0, 0, 0});
                        },
                        f});
  }
  { // eq. 5
    std::vector<Vec3> f(n, Vec3::Zero());
    for (const auto& t : m.triangles)
      centroid_term(f, t,
                    k * (area(x[t[0]], x[t[1]], x[t[2]]) -
                         area(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]])));
    expected.push_back({"local_area",
                        [&](System& s) {
                          add_local(s, m, m.nodes, OifLocalForces{0, 0, 0, k, 0});
                        },
                        f});
  }
  { // eq. 6
    std::vector<Vec3> f(n, Vec3::Zero());
    for (const auto& t : m.triangles)
      centroid_term(f, t, k * (S - S0) * area(x[t[0]], x[t[1]], x[t[2]]) / S0);
    expected.push_back({"global_area", [&](System& s) { add_global(s, m, m.nodes, k, 0.0); }, f});
  }
  // membrane viscosity (ESPResSo's variant B): per edge AB, on A
  // kvisc ((v_B - v_A) . e) e, e = AB/|AB|, and the opposite on B (explicit
  // at this dt kvisc / m, 0.04; the implicit solve: the test below)
  std::vector<Vec3> v(n);
  for (auto& vi : v)
    vi = Vec3(u(rng), u(rng), u(rng));
  {
    std::vector<Vec3> f(n, Vec3::Zero());
    for (const auto& e : m.edges) {
      const Vec3 unit = (x[e[1]] - x[e[0]]).normalized();
      const Vec3 fa = k * (v[e[1]] - v[e[0]]).dot(unit) * unit;
      f[e[0]] += fa;
      f[e[1]] -= fa;
    }
    expected.push_back({"viscosity",
                        [&](System& s) {
                          add_local(s, m, m.nodes, OifLocalForces{0, 0, 0, 0, k});
                        },
                        f});
  }
  for (const bool flip : {false, true}) { // eq. 7, outward (and inward) triangle order
    std::vector<Vec3> f(n, Vec3::Zero());
    for (const auto& t : m.triangles) {
      const Vec3 n2 = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]); // 2 S n_out
      for (int i : t)
        f[i] += -k * (V - V0) / V0 * n2 / 6.0;
    }
    expected.push_back({flip ? "volume_inward" : "volume",
                        [&, flip](System& s) { add_global(s, m, m.nodes, 0.0, k, flip); }, f});
  }
  for (const auto& e : expected) {
    auto s = oif_test::make_system();
    oif_test::add_cell_particles(*s, x, 0, 0, &v); // velocities: only the viscosity uses them
    e.add(*s);
    const auto f = oif_test::forces_of(*s, n);
    if (e.name == "viscosity") { // it damps: its power sum f.v = -kvisc sum (dv . e)^2 < 0
      double power = 0.0;
      for (std::size_t i = 0; i < n; ++i)
        power += f[i].dot(v[i]);
      EXPECT_LT(power, 0.0);
    }
    double fmax = 0.0, err = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      fmax = std::max(fmax, e.f[i].norm());
      err = std::max(err, (f[i] - e.f[i]).norm());
    }
    ASSERT_GT(fmax, 1e-3) << e.name;
    EXPECT_LT(err, 1e-12 * fmax) << e.name;
    std::cout << "[ figure ] " << e.name
              << " vs model equation: max error / max|F| = " << err / fmax << "\n";
  }
}

// The membrane viscosity (viscosity.hpp): (1) at a tiny time step it is the
// explicit dashpot force -C v (relative 1e-5); (2) beyond the explicit limit
// it is backward Euler's (a dense solve); (3) at dt kvisc / m =
// 1000, six thousand times the explicit limit of about 1/6, a stretched cell
// with random velocities runs 200 steps without blowing up, its kinetic energy
// falls, its momentum is kept to 1e-12 relative and the edges' relative
// velocities are damped to below 1 % of their start.
TEST(OifMembrane, ViscosityImplicitStableAndExplicitInTheLimit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  std::vector<Vec3> x(n), v(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = Vec3(1.2, 0.9, 1.0).cwiseProduct(m.nodes[i]) + Vec3(25, 25, 25);
    v[i] = Vec3(u(rng), u(rng), u(rng));
  }
  auto edge_speed = [&](const System& s) { // rms relative velocity along the edges
    double sum = 0.0;
    for (const auto& e : m.edges) {
      const std::size_t a = s.particles.index(e[0]), b = s.particles.index(e[1]);
      const Vec3 unit = (s.particles.pos[b] - s.particles.pos[a]).normalized();
      sum += std::pow((s.particles.vel[b] - s.particles.vel[a]).dot(unit), 2);
    }
    return std::sqrt(sum / m.edges.size());
  };
  { // (1) the explicit limit
    const double kvisc = 0.7;
    auto s = oif_test::make_system();
    s->set_time_step(1e-8);
    oif_test::add_cell_particles(*s, x, 0, 0, &v);
    add_local(*s, m, x, OifLocalForces{0, 0, 0, 0, kvisc});
    const auto f = oif_test::forces_of(*s, n);
    std::vector<Vec3> explicit_force(n, Vec3::Zero());
    for (const auto& e : m.edges) {
      const Vec3 unit = (x[e[1]] - x[e[0]]).normalized();
      const Vec3 fa = kvisc * (v[e[1]] - v[e[0]]).dot(unit) * unit;
      explicit_force[e[0]] += fa;
      explicit_force[e[1]] -= fa;
    }
    double fmax = 0.0, err = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      fmax = std::max(fmax, explicit_force[i].norm());
      err = std::max(err, (f[i] - explicit_force[i]).norm());
    }
    std::cout << "[ figure ] viscosity at dt 1e-8 vs explicit: max error / max|F| = " << err / fmax
              << "\n";
    EXPECT_LT(err, 1e-5 * fmax);
  }
  { // (2) at dt kvisc / m = 10, a cell alone: the backward-Euler force
    // -C v_new, (M/dt + C) v_new = (M/dt) v (no elastic load), solved densely;
    // the solve stops at a relative residual of 1e-6; times the system's
    // condition number (about 1 + 6 dt kvisc / m = 61): relative 1e-4
    const double kvisc = 100.0, dt = 0.1, mass = 1.0;
    auto s = oif_test::make_system();
    s->set_time_step(dt);
    oif_test::add_cell_particles(*s, x, 0, 0, &v);
    add_local(*s, m, x, OifLocalForces{0, 0, 0, 0, kvisc});
    const auto f = oif_test::forces_of(*s, n);
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (const auto& e : m.edges) {
      const Vec3 unit = (x[e[1]] - x[e[0]]).normalized();
      const Eigen::Matrix3d block = kvisc * unit * unit.transpose();
      const int a = 3 * e[0], b = 3 * e[1];
      C.block<3, 3>(a, a) += block;
      C.block<3, 3>(b, b) += block;
      C.block<3, 3>(a, b) -= block;
      C.block<3, 3>(b, a) -= block;
    }
    Eigen::VectorXd v_flat(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      v_flat.segment<3>(3 * i) = v[i];
    const Eigen::MatrixXd A = mass / dt * Eigen::MatrixXd::Identity(3 * n, 3 * n) + C;
    const Eigen::VectorXd expected = -C * A.ldlt().solve(mass / dt * v_flat);
    double fmax = 0.0, err = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      fmax = std::max(fmax, expected.segment<3>(3 * i).norm());
      err = std::max(err, (f[i] - expected.segment<3>(3 * i)).norm());
    }
    std::cout << "[ figure ] implicit viscosity at dt kvisc / m 10 vs dense solve: max error / "
                 "max|F| = "
              << err / fmax << "\n";
    EXPECT_LT(err, 1e-4 * fmax);
  }
  { // (3) far beyond the explicit limit
    auto s = oif_test::make_system();
    s->set_time_step(0.1);
    oif_test::add_cell_particles(*s, x, 0, 0, &v);
    std::vector<Vec3> relaxed(n);
    for (std::size_t i = 0; i < n; ++i)
      relaxed[i] = m.nodes[i] + Vec3(25, 25, 25);
    add_local(*s, m, relaxed, OifLocalForces{1.0, 0, 0, 0, 1e4}); // dt kvisc / m = 1000
    auto momentum = [&] {
      Vec3 p = Vec3::Zero();
      for (std::size_t i = 0; i < n; ++i)
        p += s->particles.vel[i];
      return p;
    };
    double kinetic0 = 0.0;
    for (const auto& vi : v)
      kinetic0 += 0.5 * vi.squaredNorm();
    const Vec3 p0 = momentum();
    const double speed0 = edge_speed(*s);
    ASSERT_NO_THROW(s->integrate(200));
    double kinetic = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      kinetic += 0.5 * s->particles.vel[i].squaredNorm();
    std::cout << "[ figure ] dt kvisc / m 1000, 200 steps: kinetic energy " << kinetic0 << " -> "
              << kinetic << ", edge speed " << speed0 << " -> " << edge_speed(*s)
              << ", |dp| = " << (momentum() - p0).norm() << "\n";
    EXPECT_LT(kinetic, kinetic0);
    EXPECT_LT((momentum() - p0).norm(), 1e-12 * std::sqrt(2.0 * kinetic0 * n));
    EXPECT_LT(edge_speed(*s), 0.01 * speed0);
  }
}

// The relaxed mesh, rotated and moved so that it straddles the periodic box
// corner, feels no force from any modulus (reference values from the unmoved
// mesh), alone and as four cells (one batch of vector lanes). Tolerance 1e-10
// (unit moduli, forces O(1) at 10% strain).
TEST(OifMembrane, RelaxedMeshIsForceFree) {
  std::mt19937 rng(7);
  const Mesh& m = mesh();
  const double box = 20.0;
  for (const int cells : {1, 4})
    for (const auto& mod : moduli()) {
      if (mod.name == "visc")
        continue; // dissipative: zero at rest trivially
      std::vector<Eigen::Matrix3d> rot;
      for (int k = 0; k < cells; ++k)
        rot.push_back(oif_test::random_rotation(rng));
      auto s = cells_with(
          m, cells, mod,
          [&](int k, std::size_t i) {
            // the first across three periodic faces, the others beside it
            return Vec3(rot[k] * m.nodes[i] + Vec3(0.3 + 5.0 * k, box - 0.2, 0.1 + 5.0 * k));
          },
          [](int, std::size_t) { return Vec3::Zero(); }, box);
      const auto f = oif_test::forces_of(*s, cells * m.nodes.size());
      double fmax = 0.0;
      for (const auto& fi : f)
        fmax = std::max(fmax, fi.norm());
      EXPECT_LT(fmax, 1e-10) << mod.name << ", " << cells << " cells";
      std::cout << "[ figure ] relaxed " << mod.name << " (" << cells
                << " cells): max |F| = " << fmax << "\n";
    }
}

// The membrane pass evaluates four cells of a type at once, one per vector
// lane (the last two or three of a type padded), and a lone cell alone, by
// the same driver: forces and node normals equal bit for bit those of every
// cell alone. Seven deformed, rotated and moving cells with every modulus and
// normals; some dihedral deviations beyond the polynomial arctangent's 14
// degrees (strongly deformed cells), one across the box corner.
TEST(OifMembrane, LanesEqualOneCellAtATimeBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  const Modulus all{"all",
                    [](System& s, const Mesh& mesh_, const std::vector<Vec3>& x0, int first) {
                      add_local(s, mesh_, x0, OifLocalForces{0.5, 0.2, 0.8, 0.6, 0.3}, first);
                      add_global(s, mesh_, x0, 0.7, 0.9, false, first);
                      const int id = s.add_bonded_interaction(OifOutDirection{});
                      s.add_bonds(id, oif_test::triangle_bond_ids(mesh_, first), {});
                    }};
  const double noise[7] = {0.02, 0.1, 0.4, 0.05, 0.3, 0.01, 0.2};
  auto s = cells_with(
      m, 7, all,
      [&](int k, std::size_t i) {
        return Vec3(m.nodes[i] + noise[k] * Vec3(u(rng), u(rng), u(rng)) +
                    Vec3(0.5 + 7.0 * k, 49.8, 0.3));
      },
      [&](int, std::size_t) { return Vec3(u(rng), u(rng), u(rng)); });
  const std::size_t all_nodes = 7 * n;
  auto normals = [&](System& sys) {
    std::vector<Vec3> out(all_nodes);
    for (std::size_t i = 0; i < all_nodes; ++i)
      out[i] = sys.particles.normal[sys.particles.index(static_cast<int>(i))];
    return out;
  };
  const auto f_lanes = oif_test::forces_of(*s, all_nodes);
  const auto n_lanes = normals(*s);
  EXPECT_EQ(s->membranes.counts.lane_batches, 2u); // four, and three padded to four
  EXPECT_EQ(s->membranes.counts.padded_lanes, 1u);
  EXPECT_EQ(s->membranes.counts.plain_cells, 0u);
  s->membranes.lanes = false;
  const auto f_plain = oif_test::forces_of(*s, all_nodes);
  const auto n_plain = normals(*s);
  EXPECT_EQ(s->membranes.counts.plain_cells, 7u);
  double fmax = 0.0;
  for (std::size_t i = 0; i < all_nodes; ++i) {
    fmax = std::max(fmax, f_lanes[i].norm());
    EXPECT_EQ(f_lanes[i], f_plain[i]) << "node " << i;
    EXPECT_EQ(n_lanes[i], n_plain[i]) << "node " << i;
  }
  EXPECT_GT(fmax, 1e-2);
}

// The time step runs the vector lanes: eight cells of a type are two batches
// in every force calculation of a run, none alone, and the tables are
// compiled once; a cell added later is compiled in, and the ninth goes alone.
TEST(OifMembrane, TimeStepRunsTheLanes) {
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  const Modulus local{"local",
                      [](System& s, const Mesh& mesh_, const std::vector<Vec3>& x0, int first) {
                        add_local(s, mesh_, x0, OifLocalForces{0.5, 0, 0.8, 0.6, 0}, first);
                      }};
  auto s = cells_with(
      m, 8, local,
      [&](int k, std::size_t i) { return Vec3(m.nodes[i] * 1.05 + Vec3(5.0 + 7.0 * k, 25, 25)); },
      [](int, std::size_t) { return Vec3::Zero(); }, 60.0);
  s->set_time_step(0.01);
  s->integrate(10); // its first force calculation, then one per step
  EXPECT_EQ(s->membranes.counts.compiles, 1u);
  EXPECT_EQ(s->membranes.counts.lane_batches, 2u * 11u);
  EXPECT_EQ(s->membranes.counts.plain_cells, 0u);
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = m.nodes[i] + Vec3(30, 45, 25);
  oif_test::add_cell_particles(*s, x, 8, static_cast<int>(8 * n));
  local.add(*s, m, m.nodes, static_cast<int>(8 * n));
  s->integrate(10);
  EXPECT_EQ(s->membranes.counts.compiles, 2u);
  EXPECT_EQ(s->membranes.counts.lane_batches, 2u * 22u);
  EXPECT_EQ(s->membranes.counts.plain_cells, 11u);
}

// Surface and volume of the icosahedron (level 0) against the analytic values
// of that polyhedron (circumradius R: edge a = R / sin(2 pi / 5)), in a
// periodic box with the cell across the boundary and with both triangle
// orientations; finer icospheres approach 4 pi R^2 and 4/3 pi R^3.
TEST(OifMembrane, CellSumsAnalytic) {
  const double a = R / std::sin(2.0 * M_PI / 5.0);
  const double area_ico = 5.0 * std::sqrt(3.0) * a * a;
  const double vol_ico = 5.0 / 12.0 * (3.0 + std::sqrt(5.0)) * a * a * a;
  double previous_area_error = 1.0, previous_volume_error = 1.0;
  for (int level = 0; level <= 4; ++level) {
    const Mesh m = oif_test::icosphere(level, R);
    for (const bool flip : {false, true}) {
      auto s = oif_test::make_system(10.0);
      std::vector<Vec3> x(m.nodes);
      for (auto& xi : x)
        xi += Vec3(9.5, 0.5, 5.0); // straddles the x and y faces of a 10^3 box
      oif_test::add_cell_particles(*s, x, 3);
      const int id = s->add_bonded_interaction(OifOutDirection{});
      s->add_bonds(id, oif_test::triangle_bond_ids(m, 0, flip), {});
      s->compute_forces(); // folds the positions into the box
      membrane::Selection select;
      select.bond_id = id;
      const auto cells =
          membrane::analyse(s->bonded, select, s->particles, s->box, s->time, nullptr);
      ASSERT_EQ(cells.size(), 1u);
      EXPECT_EQ(cells[0].mol_id, 3);
      EXPECT_EQ(cells[0].volume > 0.0, !flip);
      const double area = cells[0].area, volume = std::abs(cells[0].volume);
      if (level == 0) {
        EXPECT_NEAR(area, area_ico, 1e-13 * area_ico);
        EXPECT_NEAR(volume, vol_ico, 1e-13 * vol_ico);
      }
      const double area_error = std::abs(area / (4.0 * M_PI * R * R) - 1.0);
      const double volume_error = std::abs(volume / (4.0 / 3.0 * M_PI * R * R * R) - 1.0);
      if (!flip) {
        // inscribed polyhedra: error falls about 4x per level (h^2), 3.1x from level 0 to 1
        EXPECT_LT(area_error, 0.4 * previous_area_error) << "level " << level;
        EXPECT_LT(volume_error, 0.4 * previous_volume_error) << "level " << level;
        previous_area_error = area_error;
        previous_volume_error = volume_error;
      }
      if (!flip)
        std::cout << "[ figure ] icosphere level " << level << " (" << m.nodes.size()
                  << " nodes): area/(4 pi R^2) - 1 = " << area / (4.0 * M_PI * R * R) - 1.0
                  << ", volume/(4/3 pi R^3) - 1 = " << volume / (4.0 / 3.0 * M_PI * R * R * R) - 1.0
                  << "\n";
      if (level == 4) {
        EXPECT_LT(area_error, 2e-3);
        EXPECT_LT(volume_error, 3e-3);
      }
    }
  }
}

// OifOutDirection: on a sphere every node normal is within a few degrees of
// the radial direction, for either triangle orientation and across the
// periodic boundary.
TEST(OifMembrane, OutwardNormals) {
  const Mesh& m = mesh();
  for (const bool flip : {false, true}) {
    auto s = oif_test::make_system(10.0);
    const Vec3 centre(9.0, 1.0, 5.0);
    std::vector<Vec3> x(m.nodes);
    for (auto& xi : x)
      xi += centre;
    oif_test::add_cell_particles(*s, x, 0);
    const int id = s->add_bonded_interaction(OifOutDirection{});
    s->add_bonds(id, oif_test::triangle_bond_ids(m, 0, flip), {});
    s->compute_forces();
    double worst = 1.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Vec3 n = s->particles.normal[s->particles.index(static_cast<int>(i))];
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      worst = std::min(worst, n.dot(m.nodes[i].normalized()));
    }
    EXPECT_GT(worst, std::cos(2.0 * M_PI / 180.0)) << "flip " << flip;
  }
}

// Normals from other triangles than the closed surface (an OifOutDirection
// group over half of the triangles, OifGlobalForces over all): the volume
// force is that of the whole surface, bit for bit the force without the
// normals, and each node's normal is the outward unit sum of N over its
// normals' triangles only (computed here directly).
TEST(OifMembrane, NormalsOfOtherTrianglesThanTheSurface) {
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = Vec3(1.1, 0.95, 1.0).cwiseProduct(m.nodes[i]) + 0.05 * Vec3(u(rng), u(rng), u(rng)) +
           Vec3(25, 25, 25);
  std::vector<std::array<int, 3>> half; // the upper half
  for (const auto& tr : m.triangles)
    if (m.nodes[tr[0]][2] + m.nodes[tr[1]][2] + m.nodes[tr[2]][2] > 0.0)
      half.push_back(tr);
  std::vector<int> half_ids;
  for (const auto& tr : half)
    half_ids.insert(half_ids.end(), tr.begin(), tr.end());
  auto with = [&](bool normals) {
    auto s = oif_test::make_system();
    oif_test::add_cell_particles(*s, x, 0);
    add_global(*s, m, m.nodes, 0.7, 0.9);
    if (normals) {
      const int id = s->add_bonded_interaction(OifOutDirection{});
      s->add_bonds(id, half_ids, {});
    }
    return s;
  };
  auto plain = with(false), both = with(true);
  const auto f_plain = oif_test::forces_of(*plain, n), f_both = oif_test::forces_of(*both, n);
  std::vector<Vec3> sum(n, Vec3::Zero());
  std::vector<char> has(n, 0);
  for (const auto& tr : half) {
    const Vec3 nq = (x[tr[1]] - x[tr[0]]).cross(x[tr[2]] - x[tr[0]]); // outward order
    for (const int i : tr) {
      sum[i] += nq;
      has[i] = 1;
    }
  }
  std::size_t with_normal = 0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(f_both[i], f_plain[i]) << "node " << i;
    const Vec3 normal = both->particles.normal[both->particles.index(static_cast<int>(i))];
    if (has[i]) {
      ++with_normal;
      EXPECT_LT((normal - sum[i].normalized()).norm(), 1e-14) << "node " << i;
    } else {
      EXPECT_EQ(normal, Vec3::Zero()) << "node " << i << " is in no normals triangle";
    }
  }
  EXPECT_GT(with_normal, n / 2);
  EXPECT_LT(with_normal, n);
}

// A particle that is a node of two cells (two tetrahedra, mol_ids 0 and 1,
// sharing one vertex): its normal is
// the outward unit sum over both cells, each cell's triangles oriented by
// that cell's volume (computed here directly); every normal has length 1.
TEST(OifMembrane, NormalOfANodeOfTwoCells) {
  auto s = oif_test::make_system(20.0);
  const std::vector<Vec3> x = {{5, 5, 5},     {6.2, 5, 5.1}, {5.1, 6.1, 5},  {5.2, 5.1, 6.3},
                               {6.1, 6.3, 7}, {7.4, 6.1, 7}, {6.6, 7.5, 7.2}};
  for (std::size_t i = 0; i < x.size(); ++i)
    s->add_particle(static_cast<int>(i), x[i], Vec3::Zero(), 1.0, 0, i < 3 ? 0 : (i == 3 ? 0 : 1),
                    Vec3::Zero(), 0);
  // cell 0: nodes 0 1 2 3; cell 1: nodes 3 4 5 6 (the first particle of each
  // of its triangles in cell 1)
  const std::vector<std::array<int, 3>> t0 = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  const std::vector<std::array<int, 3>> t1 = {{4, 5, 6}, {4, 3, 5}, {5, 3, 6}, {6, 3, 4}};
  const int id = s->add_bonded_interaction(OifOutDirection{});
  std::vector<int> ids;
  for (const auto* cell : {&t0, &t1})
    for (const auto& tr : *cell)
      ids.insert(ids.end(), tr.begin(), tr.end());
  s->add_bonds(id, ids, {});
  s->compute_forces();
  auto oriented_sum = [&](const std::vector<std::array<int, 3>>& tris, int node) -> Vec3 {
    double volume = 0.0;
    Vec3 sum = Vec3::Zero();
    for (const auto& tr : tris) {
      const Vec3 nq = (x[tr[1]] - x[tr[0]]).cross(x[tr[2]] - x[tr[0]]);
      volume += (x[tr[0]] - x[3]).dot(nq);
      if (tr[0] == node || tr[1] == node || tr[2] == node)
        sum += nq;
    }
    return (volume < 0.0 ? -1.0 : 1.0) * sum;
  };
  for (int i = 0; i < 7; ++i) {
    const Vec3 normal = s->particles.normal[s->particles.index(i)];
    EXPECT_NEAR(normal.norm(), 1.0, 1e-14) << "node " << i;
    const Vec3 expected = (oriented_sum(t0, i) + oriented_sum(t1, i)).normalized();
    EXPECT_LT((normal - expected).norm(), 1e-14) << "node " << i;
  }
}

// Membrane collision, pure evaluator: facing membranes repel along the
// separation; once node i has passed through j's membrane the force reverses
// and pulls it back. In both cases the force on i points into i's own cell
// (F_i . n_i < 0). Same cell, walls and parallel normals: no force.
TEST(OifMembrane, CollisionDirectionFlipsWhenCrossed) {
  MembraneCollision::Params p{0.01, 10.0, 0.5, 0.0};
  PairContext c;
  c.mol_i = 0;
  c.mol_j = 1;
  c.normal_i = Vec3(1, 0, 0);  // cell 0 to the left, its surface facing +x
  c.normal_j = Vec3(-1, 0, 0); // cell 1 to the right, facing -x
  // not crossed: i left of j
  c.d = Vec3(-0.2, 0.05, 0.0);
  c.dist = c.d.norm();
  const Vec3 f_apart = MembraneCollision::force(p, c);
  EXPECT_GT(f_apart.dot(c.d), 0.0);
  EXPECT_LT(f_apart.dot(c.normal_i), 0.0);
  // crossed: i has moved past j
  c.d = Vec3(0.2, 0.05, 0.0);
  c.dist = c.d.norm();
  const Vec3 f_crossed = MembraneCollision::force(p, c);
  EXPECT_LT(f_crossed.dot(c.d), 0.0);
  EXPECT_LT(f_crossed.dot(c.normal_i), 0.0);
  EXPECT_NEAR(f_crossed.norm(), f_apart.norm(), 1e-15);
  // eq. 9 magnitude: -V'(d) = a n e^(n d) / (1 + e^(n d))^2
  const double d = c.dist, e = std::exp(p.n * d);
  EXPECT_NEAR(f_apart.norm(), p.a * p.n * e / ((1 + e) * (1 + e)), 1e-15);
  // no force within one cell, against walls, or with parallel normals
  PairContext same = c;
  same.mol_j = 0;
  EXPECT_EQ(MembraneCollision::force(p, same).norm(), 0.0);
  PairContext wall = c;
  wall.wall = true;
  EXPECT_EQ(MembraneCollision::force(p, wall).norm(), 0.0);
  PairContext parallel = c;
  parallel.normal_j = parallel.normal_i;
  EXPECT_EQ(MembraneCollision::force(p, parallel).norm(), 0.0);
  // a membrane node without a normal is a set-up error
  PairContext unset = c;
  unset.normal_j = Vec3::Zero();
  EXPECT_THROW(MembraneCollision::force(p, unset), InputError);
}

// Two spheres of one particle type (cells told apart by mol_id), overlapping by
// 0.2: with OifOutDirection normals the membrane collision pushes the cells
// apart along the line of centres, and after one is pushed through the other
// far enough that nodes have crossed, the crossed pairs pull back (the net
// force still separates the cells).
TEST(OifMembrane, CollisionPushesCellsApart) {
  const Mesh& m = mesh();
  const std::size_t n = m.nodes.size();
  for (const double gap : {-0.2, 0.1}) {
    auto s = oif_test::make_system(30.0);
    const Vec3 c1(10, 15, 15), c2(10 + 2 * R + gap, 15, 15);
    std::vector<Vec3> x1(m.nodes), x2(m.nodes);
    for (auto& xi : x1)
      xi += c1;
    for (auto& xi : x2)
      xi += c2;
    oif_test::add_cell_particles(*s, x1, 0, 0);
    oif_test::add_cell_particles(*s, x2, 1, static_cast<int>(n));
    const int id = s->add_bonded_interaction(OifOutDirection{});
    s->add_bonds(id, oif_test::triangle_bond_ids(m, 0), {});
    s->add_bonds(id, oif_test::triangle_bond_ids(m, static_cast<int>(n)), {});
    s->set_nonbonded<MembraneCollision>(0, 0, {0.01, 10.0, 0.5, 0.0});
    const auto f1 = oif_test::forces_of(*s, n, 0);
    const auto f2 = oif_test::forces_of(*s, n, static_cast<int>(n));
    Vec3 total1 = Vec3::Zero(), total2 = Vec3::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      total1 += f1[i];
      total2 += f2[i];
    }
    EXPECT_LT(total1[0], 0.0) << "gap " << gap;        // cell 1 pushed to -x
    EXPECT_NEAR((total1 + total2).norm(), 0.0, 1e-14); // action = reaction
    EXPECT_LT(std::abs(total1[1]) + std::abs(total1[2]), 1e-3 * std::abs(total1[0]));
  }
}
