// The System's reductions: on one rank they are no-ops. The decomposition's
// point-to-point exchanges (the lattice's halo: DomainGrid and LBFluid; the
// particles' copies: system_parallel.cpp) use the communicator directly.
#pragma once

#include <mpi.h>

#include <cstddef>
#include <vector>

namespace pyoif {

class Communicator {
public:
  /** Wraps MPI_COMM_WORLD (MPI is initialised by the Python package via mpi4py,
   *  or here if nobody has done it yet). */
  Communicator();
  explicit Communicator(MPI_Comm comm);

  int rank() const { return m_rank; }
  int size() const { return m_size; }
  bool is_root() const { return m_rank == 0; }
  MPI_Comm comm() const { return m_comm; }

  /** In-place sum over ranks; one call for a whole array (e.g. all cells' area
   *  and volume together), so the per-step cost is one reduction. */
  void allreduce_sum(double* data, std::size_t n) const;
  void allreduce_sum(std::vector<double>& v) const { allreduce_sum(v.data(), v.size()); }
  double allreduce_sum(double x) const {
    allreduce_sum(&x, 1);
    return x;
  }
  double allreduce_max(double x) const;
  /** In-place maximum over ranks of a whole array, in one call. */
  void allreduce_max(double* data, std::size_t n) const;
  void allreduce_max(std::vector<double>& v) const { allreduce_max(v.data(), v.size()); }
  long allreduce_sum(long x) const;
  /** True on every rank when it is true on any rank (for error agreement). */
  bool any(bool flag) const;
  /** Collective calls made over more than one rank so far (tests count the
   *  reductions per step with it). */
  std::size_t collectives() const { return m_collectives; }

private:
  void query();
  MPI_Comm m_comm = MPI_COMM_WORLD;
  int m_rank = 0;
  int m_size = 1;
  mutable std::size_t m_collectives = 0;
};

} // namespace pyoif
