// The decomposed lattice against a serial one in the same process: every rank
// builds the fluid twice, over MPI_COMM_WORLD (split into subdomains) and over
// MPI_COMM_SELF (whole), runs both the same way and compares every node's
// populations bit for bit. Run on 2, 3 and 4 ranks (label mpi).
#include "communication/domain_grid.hpp"
#include "lb/lb_fluid.hpp"
#include "shapes/cylinder.hpp"
#include "shapes/wall.hpp"
#include "utils/errors.hpp"

#include "mpi_gtest_main.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace pyoif {
namespace {

lb::LBParams params(double kT) {
  lb::LBParams p;
  p.viscosity = 0.3;
  p.ext_force_density = Vec3(1e-4, 2e-5, -1e-5);
  p.kT = kT;
  p.seed = 17;
  return p;
}

/** A nonuniform initial flow, so that every direction of the halo carries
 *  something different. */
void stir(lb::LBFluid& fluid) {
  const Vec3i n = fluid.grid();
  std::vector<double> v;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        v.push_back(0.01 * std::sin(2 * M_PI * j / n[1]) * std::cos(2 * M_PI * k / n[2]));
        v.push_back(0.01 * std::sin(2 * M_PI * i / n[0]));
        v.push_back(0.005 * std::cos(2 * M_PI * (i + j) / n[1]));
      }
  fluid.set_block("velocity", Vec3i::Zero(), n, v);
}

std::vector<lb::BoundarySpec> channel_with_post() {
  std::vector<lb::BoundarySpec> b;
  b.push_back({std::make_shared<shapes::Wall>(Vec3(0, 1, 0), 1.5), Vec3::Zero()});
  b.push_back({std::make_shared<shapes::Wall>(Vec3(0, -1, 0), -10.5), Vec3(0.01, 0, 0)});
  b.push_back(
      {std::make_shared<shapes::Cylinder>(Vec3(12, 6, 5), Vec3(0, 0, 1), 2.5, 20.0), Vec3::Zero()});
  return b;
}

void compare(const Vec3i& node_grid, bool boundaries, double kT) {
  const BoxGeometry box(Vec3(24, 12, 10), {true, true, true});
  lb::LBFluid serial(params(kT), box, MPI_COMM_SELF);
  lb::LBFluid split(params(kT), box, MPI_COMM_WORLD, node_grid, true);
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size > 1) {
    ASSERT_TRUE(split.distributed());
  }
  for (lb::LBFluid* f : {&serial, &split}) {
    stir(*f);
    if (boundaries) {
      f->set_boundaries(channel_with_post());
      f->update_boundaries(); // the explicit collective flagging (System::prepare's)
    }
    for (int s = 0; s < 23; ++s)
      f->step();
  }
  const std::string where = split.domain().describe();
  EXPECT_EQ(serial.n_fluid_nodes(), split.n_fluid_nodes()) << where;
  const std::vector<double> a = serial.get_block("population", Vec3i::Zero(), serial.grid());
  const std::vector<double> b = split.get_block("population", Vec3i::Zero(), split.grid());
  ASSERT_EQ(a.size(), b.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    differing += a[i] != b[i];
  EXPECT_EQ(differing, 0u) << where << ": populations differing from the serial lattice";
  // sums over ranks: equal to round-off
  const Vec3 pa = serial.total_momentum(), pb = split.total_momentum();
  EXPECT_LT((pa - pb).norm(), 1e-12 * pa.norm()) << where;
  if (boundaries) {
    const Vec3 fa = serial.boundary_force(2), fb = split.boundary_force(2);
    EXPECT_LT((fa - fb).norm(), 1e-12 * fa.norm() + 1e-15) << where;
  }
}

TEST(LatticeDecomposition, PeriodicFluidEqualsSerialBitForBit) {
  compare(Vec3i::Zero(), false, 0.0);
}

TEST(LatticeDecomposition, ThermalFluidWithWallsAndPostEqualsSerial) {
  // the noise is keyed by the global node, the boundaries flagged per
  // subdomain from the shapes, the cuts balanced by fluid nodes
  compare(Vec3i::Zero(), true, 1e-4);
}

TEST(LatticeDecomposition, EveryGridOfTheRanksEqualsSerial) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  // every factorisation: splits along y and z, edges and corners between
  // diagonal neighbours (2x2, 2x1x2 ...)
  for (int nx = 1; nx <= size; ++nx)
    for (int ny = 1; nx * ny <= size; ++ny)
      if (size % (nx * ny) == 0)
        compare(Vec3i(nx, ny, size / (nx * ny)), true, 0.0);
}

TEST(LatticeDecomposition, BlocksThroughOneRankEqualTheCollectiveBlock) {
  // gather_block gives the root what get_block gives every rank, and the
  // others nothing; scatter_block sets what set_block would; a bad value
  // on the root is refused on every rank, changing nothing
  const BoxGeometry box(Vec3(24, 12, 10), {true, true, true});
  lb::LBFluid fluid(params(0.0), box, MPI_COMM_WORLD, Vec3i::Zero(), true);
  stir(fluid);
  fluid.set_boundaries(channel_with_post());
  fluid.update_boundaries();
  for (int s = 0; s < 5; ++s) // (an odd count: the swapped layout)
    fluid.step();
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int root = size - 1;              // not rank 0, so that the root is not special
  const Vec3i lo(3, 2, 1), hi(21, 11, 9); // across every cut, not the whole lattice
  for (const char* prop : {"stored_population", "velocity", "boundary", "coupling_field"}) {
    const std::vector<double> all = fluid.get_block(prop, lo, hi);
    const std::vector<double> gathered = fluid.gather_block(prop, lo, hi, root);
    if (rank == root) {
      EXPECT_EQ(gathered, all) << prop; // bit for bit
    } else {
      EXPECT_TRUE(gathered.empty()) << prop;
    }
  }
  std::vector<double> changed = fluid.get_block("stored_population", lo, hi);
  for (std::size_t i = 0; i < changed.size(); ++i)
    changed[i] += 1e-3 * static_cast<double>(i % 7);
  const std::vector<double> before = fluid.get_block("stored_population", lo, hi);
  std::vector<double> bad = changed;
  bad[bad.size() / 2] = std::nan("");
  const std::vector<double> none;
  const std::vector<double>& bad_here = rank == root ? bad : none;
  EXPECT_THROW(
      fluid.scatter_block("stored_population", lo, hi, bad_here.data(), bad_here.size(), root),
      InputError);
  EXPECT_EQ(fluid.get_block("stored_population", lo, hi), before);
  const std::vector<double>& changed_here = rank == root ? changed : none;
  fluid.scatter_block("stored_population", lo, hi, changed_here.data(), changed_here.size(), root);
  EXPECT_EQ(fluid.get_block("stored_population", lo, hi), changed);
}

TEST(DomainGrid, ChoiceCutsAndOwners) {
  // least halo: a long channel is cut across its length
  EXPECT_EQ(DomainGrid::choose_dims(4, Vec3i(160, 40, 22)), Vec3i(4, 1, 1));
  EXPECT_EQ(DomainGrid::choose_dims(27, Vec3i(90, 90, 90)), Vec3i(3, 3, 3));
  EXPECT_EQ(DomainGrid::choose_dims(3, Vec3i(2, 30, 30)), Vec3i(1, 3, 1));
  // balance: twice the weight in the first half moves the cut left
  DomainGrid grid(MPI_COMM_SELF, Vec3i(12, 4, 4), Vec3i(1, 1, 1));
  std::array<std::vector<double>, 3> w;
  EXPECT_FALSE(grid.balance(w)); // one rank: nothing to move
  EXPECT_EQ(grid.owner_of(Vec3i(-1, 4, 9)), 0);
  EXPECT_THROW(DomainGrid(MPI_COMM_SELF, Vec3i(12, 4, 4), Vec3i(2, 1, 1)), InputError);
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2 || size > 4)
    return;
  // twice the weight in the first half: the cuts move towards it, each
  // where the running sum is nearest its share (ties to the later plane)
  DomainGrid split(MPI_COMM_WORLD, Vec3i(12, 4, 4), Vec3i(size, 1, 1));
  for (int k = 0; k < 12; ++k)
    w[0].push_back(k < 6 ? 2.0 : 1.0);
  w[1].assign(4, 1.0);
  w[2].assign(4, 1.0);
  EXPECT_TRUE(split.balance(w));
  const std::vector<std::vector<int>> expected = {{0, 5, 12}, {0, 3, 6, 12}, {0, 2, 5, 8, 12}};
  EXPECT_EQ(split.cuts()[0], expected[size - 2]);
  EXPECT_EQ(split.owner_of(Vec3i(4, 0, 0)), size == 2 ? 0 : 1);
  EXPECT_EQ(split.owner_of(Vec3i(-1, 0, 0)), size - 1); // periodic
}

} // namespace
} // namespace pyoif

int main(int argc, char** argv) {
  return run_tests_under_mpi(argc, argv);
}
