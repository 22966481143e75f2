// One round of point-to-point messages between neighbouring ranks: every
// exchange of the engine is one (the lattice halo, the fluid velocities of
// the ghost layer, the coupling's ghost velocities, the shared-memory offers,
// the particles' current state, coupling forces back to their owners,
// particles moving to new owners). The caller says what travels, from and to
// which buffers; this component moves it. Receives are posted first, then the
// sends, then one wait for all (no message can block another). A message to
// this rank itself is copied in place (the local transport); the others go
// as MPI messages. (The lattice halo's shared-memory transport, where both
// ranks map each other's segment, is set up by the lattice itself and
// signalled through an empty message of such a round: lb_halo.cpp.)
#pragma once

#include <mpi.h>

#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace pyoif {

/** The MPI datatype of T (the element types the engine exchanges). */
template <class T> MPI_Datatype mpi_datatype() {
  if constexpr (std::is_same_v<T, double>)
    return MPI_DOUBLE;
  else if constexpr (std::is_same_v<T, float>)
    return MPI_FLOAT;
  else if constexpr (std::is_same_v<T, int>)
    return MPI_INT;
  else if constexpr (std::is_same_v<T, std::uint64_t>)
    return MPI_UINT64_T;
  else
    static_assert(sizeof(T) == 0, "mpi_datatype: no MPI datatype for this element type");
}

class NeighbourExchange {
public:
  /** A round on comm whose messages carry this tag (each exchange its own). */
  NeighbourExchange(MPI_Comm comm, int tag) : m_comm(comm), m_tag(tag) {
    MPI_Comm_rank(comm, &m_rank);
  }
  NeighbourExchange(const NeighbourExchange&) = delete;
  NeighbourExchange& operator=(const NeighbourExchange&) = delete;
  ~NeighbourExchange() {
    // an exception between post and wait: the messages must still complete
    // before their buffers go (MPI would write into freed memory)
    if (!m_requests.empty())
      MPI_Waitall(static_cast<int>(m_requests.size()), m_requests.data(), MPI_STATUSES_IGNORE);
  }

  /** Posts the receive of at most `count` elements from `rank` into data;
   *  returns its number for received(). */
  template <class T> std::size_t receive(int rank, T* data, std::size_t count) {
    const std::size_t k = m_received.size();
    m_received.push_back(0);
    if (rank == m_rank) {
      m_local.push_back({data, count * sizeof(T), sizeof(T), k});
      return k;
    }
    m_receive_of_request.push_back(static_cast<long>(k));
    m_receive_type.push_back(mpi_datatype<T>());
    m_requests.emplace_back();
    MPI_Irecv(data, checked_count(count), mpi_datatype<T>(), rank, m_tag, m_comm,
              &m_requests.back());
    return k;
  }

  /** Posts the send of `count` elements of data to `rank` (data must stay
   *  unchanged until wait()). */
  template <class T> void send(int rank, const T* data, std::size_t count) {
    if (rank == m_rank) {
      // local transport: the receive this rank posted first, in order
      if (m_local_next >= m_local.size())
        throw std::logic_error("NeighbourExchange: a message to this rank without its receive");
      Local& l = m_local[m_local_next++];
      const std::size_t bytes = count * sizeof(T);
      if (bytes > l.capacity)
        throw std::logic_error("NeighbourExchange: a local message larger than its receive");
      if (bytes)
        std::memcpy(l.data, data, bytes);
      m_received[l.index] = count;
      return;
    }
    m_receive_of_request.push_back(-1);
    m_requests.emplace_back();
    MPI_Isend(data, checked_count(count), mpi_datatype<T>(), rank, m_tag, m_comm,
              &m_requests.back());
  }

  /** Completes every message posted. */
  void wait() {
    std::vector<MPI_Status> status(m_requests.size());
    if (!m_requests.empty())
      MPI_Waitall(static_cast<int>(m_requests.size()), m_requests.data(), status.data());
    std::size_t r = 0;
    for (std::size_t q = 0; q < m_requests.size(); ++q) {
      if (m_receive_of_request[q] < 0)
        continue;
      int count = 0;
      MPI_Get_count(&status[q], m_receive_type[r++], &count);
      m_received[static_cast<std::size_t>(m_receive_of_request[q])] =
          static_cast<std::size_t>(count);
    }
    m_requests.clear();
    m_receive_of_request.clear();
    m_receive_type.clear();
    if (m_local_next != m_local.size())
      throw std::logic_error("NeighbourExchange: a receive from this rank without its message");
  }

  /** Elements the k-th receive got (after wait()). */
  std::size_t received(std::size_t k) const { return m_received.at(k); }

private:
  struct Local {
    void* data;
    std::size_t capacity, element, index;
  };
  static int checked_count(std::size_t count) {
    if (count > static_cast<std::size_t>(INT_MAX))
      throw std::length_error("NeighbourExchange: a message of " + std::to_string(count) +
                              " elements is more than MPI counts in an int");
    return static_cast<int>(count);
  }
  MPI_Comm m_comm;
  int m_tag, m_rank = 0;
  std::vector<MPI_Request> m_requests;
  std::vector<long> m_receive_of_request; ///< per request: its receive's number, -1 a send
  std::vector<MPI_Datatype> m_receive_type;
  std::vector<std::size_t> m_received;
  std::vector<Local> m_local;
  std::size_t m_local_next = 0;
};

} // namespace pyoif
