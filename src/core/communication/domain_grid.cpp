#include "communication/domain_grid.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <limits>
#include <sstream>

namespace pyoif {

DomainGrid::DomainGrid(const Vec3i& nodes) : m_nodes(nodes) {
  even_cuts();
}

DomainGrid::DomainGrid(MPI_Comm comm, const Vec3i& nodes, const Vec3i& requested)
    : m_comm(comm), m_nodes(nodes) {
  MPI_Comm_rank(comm, &m_rank);
  MPI_Comm_size(comm, &m_size);
  if ((requested.array() == 0).all()) {
    m_dims = choose_dims(m_size, nodes);
  } else {
    if ((requested.array() <= 0).any() || requested.prod() != m_size)
      throw InputError("cell_system.node_grid: the ranks per axis [" +
                       std::to_string(requested[0]) + ", " + std::to_string(requested[1]) + ", " +
                       std::to_string(requested[2]) + "] must be positive with product " +
                       std::to_string(m_size) + " (the number of MPI ranks)");
    m_dims = requested;
  }
  for (int d = 0; d < 3; ++d)
    if (m_dims[d] > nodes[d])
      throw InputError("cell_system.node_grid: " + std::to_string(m_dims[d]) +
                       " ranks along axis " + std::to_string(d) + " but the lattice has only " +
                       std::to_string(nodes[d]) +
                       " nodes there; choose another node_grid or fewer ranks");
  m_coords = coords_of(m_rank);
  even_cuts();
}

Vec3i DomainGrid::choose_dims(int ranks, const Vec3i& nodes) {
  // The halo a subdomain exchanges grows with its faces on the decomposed
  // axes: minimise sum over split axes of the face area n_e * n_f / (d_e d_f)
  Vec3i best = Vec3i(ranks, 1, 1);
  double best_surface = std::numeric_limits<double>::infinity();
  for (int dx = ranks; dx >= 1; --dx) {
    if (ranks % dx)
      continue;
    for (int dy = ranks / dx; dy >= 1; --dy) {
      if ((ranks / dx) % dy)
        continue;
      const Vec3i d(dx, dy, ranks / dx / dy);
      if ((d.array() > nodes.array()).any())
        continue;
      double surface = 0.0;
      for (int a = 0; a < 3; ++a)
        if (d[a] > 1)
          surface +=
              double(nodes[(a + 1) % 3]) / d[(a + 1) % 3] * nodes[(a + 2) % 3] / d[(a + 2) % 3];
      if (surface < best_surface * (1.0 - 1e-12)) {
        best_surface = surface;
        best = d;
      }
    }
  }
  return best;
}

void DomainGrid::even_cuts() {
  for (int d = 0; d < 3; ++d) {
    m_cuts[d].resize(m_dims[d] + 1);
    for (int k = 0; k <= m_dims[d]; ++k)
      m_cuts[d][k] = static_cast<int>((static_cast<long>(m_nodes[d]) * k) / m_dims[d]);
  }
}

bool DomainGrid::balance(const std::array<std::vector<double>, 3>& weights) {
  bool moved = false;
  for (int d = 0; d < 3; ++d) {
    if (m_dims[d] == 1 || static_cast<int>(weights[d].size()) != m_nodes[d])
      continue;
    std::vector<double> prefix(m_nodes[d] + 1, 0.0);
    for (int k = 0; k < m_nodes[d]; ++k)
      prefix[k + 1] = prefix[k] + weights[d][k];
    const double total = prefix.back();
    if (!(total > 0.0))
      continue;
    std::vector<int> cuts(m_dims[d] + 1);
    cuts[0] = 0;
    cuts[m_dims[d]] = m_nodes[d];
    for (int j = 1; j < m_dims[d]; ++j) {
      const double target = total * j / m_dims[d];
      // the plane whose prefix is nearest the target, leaving at least one
      // plane for each slab before and after
      int k =
          static_cast<int>(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
      if (k > 0 && target - prefix[k - 1] < prefix[k] - target)
        --k;
      k = std::max(k, cuts[j - 1] + 1);
      k = std::min(k, m_nodes[d] - (m_dims[d] - j));
      cuts[j] = k;
    }
    moved |= cuts != m_cuts[d];
    m_cuts[d] = cuts;
  }
  return moved;
}

int DomainGrid::rank_of(Vec3i c) const {
  for (int d = 0; d < 3; ++d)
    c[d] = ((c[d] % m_dims[d]) + m_dims[d]) % m_dims[d];
  // x fastest: ranks next to each other (one node of a cluster) split x
  return (c[2] * m_dims[1] + c[1]) * m_dims[0] + c[0];
}

Vec3i DomainGrid::coords_of(int rank) const {
  return Vec3i(rank % m_dims[0], (rank / m_dims[0]) % m_dims[1], rank / (m_dims[0] * m_dims[1]));
}

Vec3i DomainGrid::lower(const Vec3i& c) const {
  return Vec3i(m_cuts[0][c[0]], m_cuts[1][c[1]], m_cuts[2][c[2]]);
}

Vec3i DomainGrid::extent(const Vec3i& c) const {
  return Vec3i(m_cuts[0][c[0] + 1] - m_cuts[0][c[0]], m_cuts[1][c[1] + 1] - m_cuts[1][c[1]],
               m_cuts[2][c[2] + 1] - m_cuts[2][c[2]]);
}

int DomainGrid::owner_of(Vec3i g) const {
  Vec3i c;
  for (int d = 0; d < 3; ++d) {
    g[d] = ((g[d] % m_nodes[d]) + m_nodes[d]) % m_nodes[d];
    c[d] = static_cast<int>(std::upper_bound(m_cuts[d].begin(), m_cuts[d].end(), g[d]) -
                            m_cuts[d].begin()) -
           1;
  }
  return rank_of(c);
}

std::string DomainGrid::describe() const {
  std::ostringstream s;
  s << m_dims[0] << "x" << m_dims[1] << "x" << m_dims[2];
  const char* axis = "xyz";
  for (int d = 0; d < 3; ++d)
    if (m_dims[d] > 1) {
      s << ", cuts " << axis[d] << ":";
      for (int c : m_cuts[d])
        s << " " << c;
    }
  return s.str();
}

} // namespace pyoif
