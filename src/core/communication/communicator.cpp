#include "communication/communicator.hpp"

namespace pyoif {

namespace {
void ensure_mpi_initialised() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  }
}
} // namespace

Communicator::Communicator() {
  ensure_mpi_initialised();
  query();
}

Communicator::Communicator(MPI_Comm comm) : m_comm(comm) {
  ensure_mpi_initialised();
  query();
}

void Communicator::query() {
  MPI_Comm_rank(m_comm, &m_rank);
  MPI_Comm_size(m_comm, &m_size);
}

void Communicator::allreduce_sum(double* data, std::size_t n) const {
  if (m_size == 1 || n == 0)
    return;
  ++m_collectives;
  MPI_Allreduce(MPI_IN_PLACE, data, static_cast<int>(n), MPI_DOUBLE, MPI_SUM, m_comm);
}

double Communicator::allreduce_max(double x) const {
  allreduce_max(&x, 1);
  return x;
}

void Communicator::allreduce_max(double* data, std::size_t n) const {
  if (m_size == 1 || n == 0)
    return;
  ++m_collectives;
  MPI_Allreduce(MPI_IN_PLACE, data, static_cast<int>(n), MPI_DOUBLE, MPI_MAX, m_comm);
}

long Communicator::allreduce_sum(long x) const {
  if (m_size > 1) {
    ++m_collectives;
    MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_LONG, MPI_SUM, m_comm);
  }
  return x;
}

bool Communicator::any(bool flag) const {
  int f = flag ? 1 : 0;
  if (m_size > 1) {
    ++m_collectives;
    MPI_Allreduce(MPI_IN_PLACE, &f, 1, MPI_INT, MPI_MAX, m_comm);
  }
  return f != 0;
}

} // namespace pyoif
