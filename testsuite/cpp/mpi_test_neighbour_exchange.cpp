// NeighbourExchange, the one component every exchange of the engine goes
// through: on 2, 3 and 4 ranks (label mpi) each rank sends to its ring
// neighbours and to itself (the local transport) messages of its own length
// and content, in three element types, and checks what arrives, how much,
// and that a receive larger than its message reports the true count.
#include "communication/neighbour_exchange.hpp"

#include "mpi_gtest_main.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

namespace pyoif {
namespace {

int rank_of(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}
int size_of(MPI_Comm comm) {
  int s = 0;
  MPI_Comm_size(comm, &s);
  return s;
}

/** The message rank `from` sends to rank `to`: its length and values say
 *  who sent it to whom. */
template <class T> std::vector<T> message(int from, int to) {
  std::vector<T> m(static_cast<std::size_t>(3 + from + 2 * to));
  for (std::size_t i = 0; i < m.size(); ++i)
    m[i] = static_cast<T>(1000 * from + 10 * to + static_cast<int>(i));
  return m;
}

template <class T> void ring_round() {
  const MPI_Comm comm = MPI_COMM_WORLD;
  const int me = rank_of(comm), n = size_of(comm);
  // neighbours (left, right; one rank: itself twice) and itself
  std::vector<int> peers = {(me + n - 1) % n, (me + 1) % n, me};
  if (n == 2)
    peers = {1 - me, me};
  NeighbourExchange round(comm, 90);
  std::vector<std::vector<T>> in(peers.size(), std::vector<T>(64, T{}));
  std::vector<std::size_t> slot;
  for (std::size_t k = 0; k < peers.size(); ++k)
    slot.push_back(round.receive(peers[k], in[k].data(), in[k].size()));
  std::vector<std::vector<T>> out;
  for (const int p : peers)
    out.push_back(message<T>(me, p));
  for (std::size_t k = 0; k < peers.size(); ++k)
    round.send(peers[k], out[k].data(), out[k].size());
  round.wait();
  for (std::size_t k = 0; k < peers.size(); ++k) {
    const std::vector<T> expected = message<T>(peers[k], me);
    ASSERT_EQ(round.received(slot[k]), expected.size()) << "from rank " << peers[k];
    for (std::size_t i = 0; i < expected.size(); ++i)
      EXPECT_EQ(in[k][i], expected[i]);
    EXPECT_EQ(in[k][expected.size()], T{}); // nothing beyond the message
  }
}

TEST(NeighbourExchange, RingAndSelfInEveryElementType) {
  ring_round<double>();
  ring_round<float>();
  ring_round<int>();
  ring_round<std::uint64_t>();
}

TEST(NeighbourExchange, EmptyMessagesAndNoPeers) {
  NeighbourExchange none(MPI_COMM_WORLD, 91);
  none.wait(); // nothing posted: nothing to wait for
  const int me = rank_of(MPI_COMM_WORLD), n = size_of(MPI_COMM_WORLD);
  NeighbourExchange round(MPI_COMM_WORLD, 92);
  double in = 7.0, out = 3.0;
  const std::size_t k = round.receive((me + 1) % n, &in, 1);
  round.send((me + n - 1) % n, &out, 0);
  round.wait();
  EXPECT_EQ(round.received(k), 0u);
  EXPECT_EQ(in, 7.0);
}

TEST(NeighbourExchange, LocalMessageWithoutItsReceiveIsRefused) {
  NeighbourExchange round(MPI_COMM_WORLD, 93);
  const double x = 1.0;
  EXPECT_THROW(round.send(rank_of(MPI_COMM_WORLD), &x, 1), std::logic_error);
  double y = 0.0;
  round.receive(rank_of(MPI_COMM_WORLD), &y, 1);
  EXPECT_THROW(round.wait(), std::logic_error); // its message never came
}

} // namespace
} // namespace pyoif

int main(int argc, char** argv) {
  return run_tests_under_mpi(argc, argv);
}
