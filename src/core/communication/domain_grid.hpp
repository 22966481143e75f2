// The Cartesian grid of subdomains over the ranks (the lattice's domain
// decomposition): ranks per axis, the cut planes per axis (in lattice nodes,
// not necessarily even: a weighted split puts as many fluid nodes on every
// rank as it can), each rank's box of nodes and its 26 neighbours (periodic).
// A tensor grid: the cuts along an axis are shared by all ranks, so two ranks
// that touch share the extent of the face, edge or corner between them, and
// both can list the nodes of that region in the same order from their own
// data (the halo exchange relies on it).
#pragma once

#include "utils/vector.hpp"

#include <mpi.h>

#include <array>
#include <string>
#include <vector>

namespace pyoif {

class DomainGrid {
public:
  /** One rank, the whole lattice of `nodes`. */
  explicit DomainGrid(const Vec3i& nodes);
  /** The ranks of comm over a lattice of `nodes`: dims as requested (every
   *  entry > 0: their product must be the number of ranks; all zero: chosen
   *  for the least halo surface per rank). Even cuts. Throws InputError for
   *  a request that does not fit (product, more ranks than nodes on an axis). */
  DomainGrid(MPI_Comm comm, const Vec3i& nodes, const Vec3i& requested_dims);

  /** The grid chosen automatically for `ranks` ranks: the one with the least
   *  halo surface of a subdomain, ties to more ranks along x, then y. */
  static Vec3i choose_dims(int ranks, const Vec3i& nodes);

  /** Moves the cuts so that every slab along each decomposed axis holds the
   *  same weight as nearly as it can (weights[d][k]: the weight of lattice
   *  plane k normal to axis d, e.g. its fluid nodes), every slab at least
   *  one plane thick. Returns whether a cut moved. */
  bool balance(const std::array<std::vector<double>, 3>& plane_weights);

  MPI_Comm comm() const { return m_comm; }
  int rank() const { return m_rank; }
  int size() const { return m_size; }
  const Vec3i& dims() const { return m_dims; }
  const Vec3i& coords() const { return m_coords; }
  const Vec3i& nodes() const { return m_nodes; }
  const std::array<std::vector<int>, 3>& cuts() const { return m_cuts; }

  /** Rank of grid coordinates c (wrapped periodically). */
  int rank_of(Vec3i c) const;
  Vec3i coords_of(int rank) const;
  /** First node and extent of the subdomain at grid coordinates c. */
  Vec3i lower(const Vec3i& c) const;
  Vec3i extent(const Vec3i& c) const;
  Vec3i lower() const { return lower(m_coords); }
  Vec3i extent() const { return extent(m_coords); }
  /** Rank of the neighbour at offset o (each entry -1, 0 or 1). */
  int neighbour(const Vec3i& o) const { return rank_of(m_coords + o); }
  /** Rank owning global node g (wrapped periodically). */
  int owner_of(Vec3i g) const;
  /** "2x1x1, cuts x: 0 80 160" */
  std::string describe() const;

private:
  void even_cuts();
  MPI_Comm m_comm = MPI_COMM_SELF;
  int m_rank = 0, m_size = 1;
  Vec3i m_nodes, m_dims = Vec3i::Ones(), m_coords = Vec3i::Zero();
  std::array<std::vector<int>, 3> m_cuts;
};

} // namespace pyoif
