// The per-cell surface and volume sums over ranks (model eqs. 6, 7 need them
// before any global-area or volume force). Each rank holds every particle
// but only its share of the triangles, as a domain decomposition gives it;
// CellSums::compute_all over two bond groups (two cell types) must give the
// sums of the whole meshes, as one rank computes them, with ONE reduction
// per call for all cells together once the mol_id ranges are agreed (the
// issue's requirement; upstream PyOIF looped over all particles per cell).
// Runs under mpiexec with 2 or more ranks (CTest: mpi_cpp_mpi_test_cell_sums_2).
#include "test_oif_mesh.hpp"

#include "interactions/bonded/oif_cell_sums.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <random>

using namespace pyoif;

namespace {

/** The triangle bonds of the cells `mols` (particle ids mol * n + node). */
BondGroup triangles_of(const oif_test::Mesh& m, const std::vector<int>& mols, int rank = 0,
                       int share = 1) {
  BondGroup g;
  g.n_particles = 3;
  const int n = static_cast<int>(m.nodes.size());
  int counter = 0;
  for (const int mol : mols)
    for (const auto& t : m.triangles)
      if (counter++ % share == rank)
        for (const int k : t)
          g.ids.push_back(mol * n + k);
  return g;
}

void expect_same_sums(const oif::CellSums& parallel, const oif::CellSums& serial) {
  ASSERT_EQ(parallel.mol_ids, serial.mol_ids);
  for (std::size_t k = 0; k < serial.mol_ids.size(); ++k) {
    EXPECT_NEAR(parallel.area[k], serial.area[k], 1e-12 * serial.area[k]);
    EXPECT_NEAR(parallel.volume[k], serial.volume[k], 1e-12 * std::abs(serial.volume[k]));
    EXPECT_EQ(parallel.n_triangles[k], serial.n_triangles[k]);
  }
}

} // namespace

TEST(CellSumsMpi, OneReductionForAllCellTypes) {
  const Communicator world(MPI_COMM_WORLD), self(MPI_COMM_SELF);
  ASSERT_GE(world.size(), 2) << "run under mpiexec -np 2";
  const int rank = world.rank(), size = world.size();
  const auto mesh = oif_test::icosphere(1, 2.0);
  const int n = static_cast<int>(mesh.nodes.size());
  auto system = oif_test::make_system(50.0);
  std::mt19937 rng(7); // the same cells on every rank
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto add_cell = [&](int mol) {
    std::vector<Vec3> x(mesh.nodes);
    for (auto& xi : x)
      xi = Vec3(1.0 + 0.2 * u(rng), 1.0, 1.0 + 0.1 * mol).cwiseProduct(xi) +
           0.1 * Vec3(u(rng), u(rng), u(rng)) + Vec3(8.0 * mol + 5.0, 20.0, 20.0);
    oif_test::add_cell_particles(*system, x, mol, mol * n);
  };
  for (int mol : {0, 1, 2})
    add_cell(mol);
  // type A: cells 0 and 1, its triangles dealt round the ranks; type B: cell
  // 2, all of its triangles on the last rank (the others have none)
  BondGroup a_all = triangles_of(mesh, {0, 1}), b_all = triangles_of(mesh, {2});
  BondGroup a_mine = triangles_of(mesh, {0, 1}, rank, size);
  BondGroup b_mine = rank == size - 1 ? b_all : BondGroup{3, 0, {}, {}};
  oif::CellSums a, b, a_serial, b_serial;
  auto check = [&](std::size_t reductions, const char* when) {
    const std::size_t before = world.collectives();
    oif::CellSums::compute_all({{&a_mine, &a}, {&b_mine, &b}}, system->particles, system->box,
                               world);
    EXPECT_EQ(world.collectives() - before, reductions) << when;
    a_serial.compute(a_all, system->particles, system->box, self);
    b_serial.compute(b_all, system->particles, system->box, self);
    SCOPED_TRACE(when);
    expect_same_sums(a, a_serial);
    expect_same_sums(b, b_serial);
    // every local bond knows its cell's slot
    for (std::size_t k = 0; k < a_mine.size(); ++k)
      EXPECT_EQ(a.mol_ids[a.bond_cell[k]], a_mine.bond(k)[0] / n);
  };
  // first call: the sums, a reduction agreeing on the mol_id ranges, the sums again
  check(3, "first call");
  ASSERT_EQ(a.mol_ids, (std::vector<int>{0, 1}));
  // the next steps: moved nodes, one reduction for both cell types
  for (int step = 0; step < 3; ++step) {
    for (std::size_t i = 0; i < system->particles.n_local(); ++i)
      system->particles.pos[i] += 0.05 * Vec3(u(rng), u(rng), u(rng));
    check(1, "a later step");
  }
  // a new cell of type A (mol 3, outside the agreed range): the ranges are agreed anew
  add_cell(3);
  a_all = triangles_of(mesh, {0, 1, 3});
  a_mine = triangles_of(mesh, {0, 1, 3}, rank, size);
  check(3, "after a cell was added");
  EXPECT_EQ(a.mol_ids, (std::vector<int>{0, 1, 3}));
  check(1, "the step after");
}

// A particle of a triangle missing on one rank only (a decomposition's
// rank-local event): every rank throws, none waits in a reduction for it.
TEST(CellSumsMpi, MissingParticleThrowsOnEveryRank) {
  const Communicator world(MPI_COMM_WORLD);
  ASSERT_GE(world.size(), 2) << "run under mpiexec -np 2";
  const auto mesh = oif_test::icosphere(1, 2.0);
  auto system = oif_test::make_system(50.0);
  oif_test::add_cell_particles(*system, mesh.nodes, 0);
  BondGroup all = triangles_of(mesh, {0});
  oif::CellSums sums;
  oif::CellSums::compute_all({{&all, &sums}}, system->particles, system->box, world);
  if (world.rank() == 1)
    system->remove_particle(5);
  EXPECT_THROW(oif::CellSums::compute_all({{&all, &sums}}, system->particles, system->box, world),
               SimulationInstability);
  // and the ranks still agree afterwards: one more collective goes through
  EXPECT_TRUE(world.any(world.rank() == 0));
}

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int failed = RUN_ALL_TESTS();
  int any_failed = 0;
  MPI_Allreduce(&failed, &any_failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any_failed;
}
