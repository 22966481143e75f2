// The lattice's input and output: single nodes (this rank's), blocks of
// nodes (collective: each rank fills its own nodes, the sum over the ranks
// is every value exactly), blocks through one rank (gather_block,
// scatter_block: each rank sends or receives only the nodes it owns) and
// the legacy VTK fields written by rank 0.
#include "lb/lb_fluid.hpp"

#include "io/vtk_legacy.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace pyoif::lb {

using namespace d3q19;

std::size_t LBFluid::checked_node(const Vec3i& node) const {
  require_flagged("a lattice node");
  for (int d = 0; d < 3; ++d)
    if (node[d] < 0 || node[d] >= m_global[d])
      throw InputError("lattice node index " + std::to_string(node[d]) + " on axis " +
                       std::to_string(d) + " out of range [0, " + std::to_string(m_global[d]) +
                       ")");
  const std::size_t n = owned_index(node);
  if (n == npos)
    throw InputError("lattice node (" + std::to_string(node[0]) + ", " + std::to_string(node[1]) +
                     ", " + std::to_string(node[2]) + ") is not on MPI rank " +
                     std::to_string(m_grid.rank()) + " (use the collective block access)");
  return n;
}

namespace {
int block_components(const std::string& prop) {
  if (prop == "velocity")
    return 3;
  if (prop == "density" || prop == "boundary")
    return 1;
  if (prop == "population" || prop == "stored_population")
    return Q;
  if (prop == "coupling_field")
    return 4;
  if (prop == "pressure_tensor")
    return 9;
  throw InputError("unknown lattice node property '" + prop + "'");
}
} // namespace

void LBFluid::check_block(const Vec3i& lo, const Vec3i& hi) const {
  for (int d = 0; d < 3; ++d)
    if (lo[d] < 0 || hi[d] > m_global[d] || lo[d] >= hi[d])
      throw InputError("lattice node block [" + std::to_string(lo[d]) + ", " +
                       std::to_string(hi[d]) + ") on axis " + std::to_string(d) +
                       " is empty or outside [0, " + std::to_string(m_global[d]) + ")");
}

void LBFluid::node_values(const std::string& prop, const Vec3i& node, double* o) const {
  if (prop == "velocity") {
    const Vec3 u = node_velocity(node);
    o[0] = u[0], o[1] = u[1], o[2] = u[2];
  } else if (prop == "density") {
    o[0] = node_density(node);
  } else if (prop == "boundary") {
    o[0] = node_boundary(node) + 1;
  } else if (prop == "population") {
    const auto f = node_populations(node);
    std::copy(f.begin(), f.end(), o);
  } else if (prop == "stored_population") {
    const std::size_t own = owned_index(node);
    for (int q = 0; q < Q; ++q)
      o[q] = m_pop.at(m_pop.slot(q, own));
  } else if (prop == "coupling_field") {
    const std::size_t own = owned_index(node);
    if (!m_field.empty() && field_valid(own)) {
      o[0] = 1.0;
      std::copy(m_field.begin() + 3 * own, m_field.begin() + 3 * own + 3, o + 1);
    }
  } else {
    const Mat3 pt = node_pressure_tensor(node);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        o[3 * a + b] = pt(a, b);
  }
}

std::vector<double> LBFluid::get_block(const std::string& prop, const Vec3i& lo,
                                       const Vec3i& hi) const {
  require_flagged("reading lattice nodes");
  const int nc = block_components(prop);
  check_block(lo, hi);
  const Vec3i n = hi - lo;
  // each rank fills the nodes it owns, zeros elsewhere; the sum over the
  // ranks is then every value exactly (x + 0 = x)
  std::vector<double> out(static_cast<std::size_t>(n.prod()) * nc, 0.0);
  double* o = out.data();
  for (int i = lo[0]; i < hi[0]; ++i)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int k = lo[2]; k < hi[2]; ++k, o += nc)
        if (owns(Vec3i(i, j, k)))
          node_values(prop, Vec3i(i, j, k), o);
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, out.data(), static_cast<int>(out.size()), MPI_DOUBLE, MPI_SUM,
                  m_grid.comm());
  return out;
}

namespace {
/** A block of prop's properties that set_block may write. */
void require_settable(const std::string& prop) {
  if (prop != "velocity" && prop != "density" && prop != "population" &&
      prop != "stored_population" && prop != "coupling_field")
    throw InputError(prop + " is read-only");
}

/** a checkpoint's raw state: every node, solid ones included */
bool raw_property(const std::string& prop) {
  return prop == "stored_population" || prop == "coupling_field";
}

/** The count and value checks of a block to set, "" when it is good. */
std::string block_values_error(const std::string& prop, int nc, const Vec3i& n,
                               const double* values, std::size_t count) {
  if (count != static_cast<std::size_t>(n.prod()) * nc)
    return prop + ": expected " + std::to_string(nc) + " value(s) per node for " +
           std::to_string(n.prod()) + " node(s), got " + std::to_string(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double v = values[i];
    if (!std::isfinite(v))
      return prop + ": values must be finite";
    if (prop == "density" && !(v > 0.0))
      return "density must be a finite number > 0";
  }
  return {};
}
} // namespace

void LBFluid::set_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                        const std::vector<double>& values) {
  require_flagged("setting lattice nodes");
  const int nc = block_components(prop);
  require_settable(prop);
  check_block(lo, hi);
  const Vec3i n = hi - lo;
  // the value checks first, on every rank alike (the same values): a refused
  // block changes nothing anywhere
  const std::string error = block_values_error(prop, nc, n, values.data(), values.size());
  if (!error.empty())
    throw InputError(error);
  if (n.prod() == 1 && !raw_property(prop)) {
    // a single boundary node is an error on every rank (its owner knows it)
    const std::size_t own = owned_index(lo);
    double solid = own != npos && m_flag[own] != 0 ? 1.0 : 0.0;
    if (m_grid.size() > 1)
      MPI_Allreduce(MPI_IN_PLACE, &solid, 1, MPI_DOUBLE, MPI_MAX, m_grid.comm());
    require(solid == 0.0, prop == "population"
                              ? "cannot set the populations of a boundary node"
                              : "cannot set the density or velocity of a boundary node");
  }
  ++m_state_version;
  const double* v = values.data();
  for (int i = lo[0]; i < hi[0]; ++i)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int k = lo[2]; k < hi[2]; ++k, v += nc)
        set_node_values(prop, Vec3i(i, j, k), v);
}

void LBFluid::set_node_values(const std::string& prop, const Vec3i& node, const double* v) {
  const std::size_t own = owned_index(node);
  if (own == npos)
    return;
  if (prop == "stored_population") {
    for (int q = 0; q < Q; ++q)
      m_pop.set_at(m_pop.slot(q, own), v[q]);
    return;
  }
  if (prop == "coupling_field") {
    if (v[0] != 0.0) {
      open_impulse_field();
      m_field_valid[own >> 6] &= ~(std::uint64_t{1} << (own & 63));
      add_field_impulse(own, Vec3(v[1], v[2], v[3]));
    } else if (!m_field.empty()) {
      m_field_valid[own >> 6] &= ~(std::uint64_t{1} << (own & 63));
    }
    return;
  }
  // a block spanning boundary nodes sets the fluid nodes only
  if (m_flag[own] != 0)
    return;
  // written here, not through set_node_*: those count a change on the owner
  // only, and the fluid's state_version must stay the same on every rank
  // (it decides collective recomputations)
  if (prop == "population") {
    for (int q = 0; q < Q; ++q)
      m_pop.set_full(q, m_pop.slot(q, own), v[q]);
    return;
  }
  const double rho = prop == "density" ? v[0] : node_density(node);
  const Vec3 u = prop == "velocity" ? Vec3(v[0], v[1], v[2]) : node_velocity(node);
  // the stored momentum is rho u - F_ext / 2 so that node_velocity() returns u
  const Vec3 u_lattice = u * m_p.tau / m_p.agrid - 0.5 * m_ext_lattice / rho;
  for (int q = 0; q < Q; ++q)
    m_pop.set_full(q, m_pop.slot(q, own), equilibrium(q, rho, u_lattice));
}

// --- blocks through one rank: each rank sends or receives its own nodes ---
// The part of block [lo, hi) that rank r owns, as its first node and
// extent (empty: some extent 0); its values travel i slowest, k fastest,
// the block's own order.
void LBFluid::block_part(int r, const Vec3i& lo, const Vec3i& hi, Vec3i& first,
                         Vec3i& extent) const {
  const Vec3i c = m_grid.coords_of(r);
  const Vec3i sub_lo = m_grid.lower(c), sub_n = m_grid.extent(c);
  for (int d = 0; d < 3; ++d) {
    first[d] = std::max(lo[d], sub_lo[d]);
    extent[d] = std::max(0, std::min(hi[d], sub_lo[d] + sub_n[d]) - first[d]);
  }
}

namespace {
/** MPI counts are int: a block part past that is refused, not truncated. */
int mpi_count(std::size_t n, const char* what) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError(std::string(what) +
                     ": the block is too large for one transfer; read or write it in parts");
  return static_cast<int>(n);
}

/** Calls body(block offset, node) for the nodes of part (first, extent) of
 *  the block [lo, lo + n), in the block's order. */
template <class Body>
void for_each_part_node(const Vec3i& lo, const Vec3i& n, const Vec3i& first, const Vec3i& extent,
                        Body&& body) {
  for (int i = first[0]; i < first[0] + extent[0]; ++i)
    for (int j = first[1]; j < first[1] + extent[1]; ++j)
      for (int k = first[2]; k < first[2] + extent[2]; ++k)
        body((static_cast<std::size_t>(i - lo[0]) * n[1] + (j - lo[1])) * n[2] + (k - lo[2]),
             Vec3i(i, j, k));
}
} // namespace

std::vector<double> LBFluid::gather_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                                          int root) const {
  require_flagged("reading lattice nodes");
  const int nc = block_components(prop);
  check_block(lo, hi);
  require(root >= 0 && root < m_grid.size(),
          "gather_block: root rank " + std::to_string(root) + " out of range");
  if (m_grid.size() == 1)
    return get_block(prop, lo, hi);
  const Vec3i n = hi - lo;
  constexpr int tag = 76;
  Vec3i first, extent;
  if (m_grid.rank() != root) { // this rank's nodes, in the block's order
    block_part(m_grid.rank(), lo, hi, first, extent);
    std::vector<double> part(static_cast<std::size_t>(extent.prod()) * nc);
    double* o = part.data();
    for_each_part_node(lo, n, first, extent, [&](std::size_t, const Vec3i& node) {
      node_values(prop, node, o);
      o += nc;
    });
    MPI_Send(part.data(), mpi_count(part.size(), "gather_block"), MPI_DOUBLE, root, tag,
             m_grid.comm());
    return {};
  }
  // the root writes its own nodes in place and takes the others' parts one
  // by one into one buffer: it holds the block and one part, no more
  std::vector<double> out(static_cast<std::size_t>(n.prod()) * nc), received;
  for (int r = 0; r < m_grid.size(); ++r) {
    block_part(r, lo, hi, first, extent);
    if (r == root) {
      for_each_part_node(lo, n, first, extent, [&](std::size_t at, const Vec3i& node) {
        node_values(prop, node, out.data() + at * nc);
      });
      continue;
    }
    received.resize(static_cast<std::size_t>(extent.prod()) * nc);
    MPI_Recv(received.data(), mpi_count(received.size(), "gather_block"), MPI_DOUBLE, r, tag,
             m_grid.comm(), MPI_STATUS_IGNORE);
    const double* in = received.data();
    for_each_part_node(lo, n, first, extent, [&](std::size_t at, const Vec3i&) {
      std::copy(in, in + nc, out.data() + at * nc);
      in += nc;
    });
  }
  return out;
}

void LBFluid::scatter_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                            const double* values, std::size_t count, int root) {
  require_flagged("setting lattice nodes");
  const int nc = block_components(prop);
  require_settable(prop);
  require(raw_property(prop),
          "scatter_block: only a checkpoint's raw state (stored_population, coupling_field)");
  check_block(lo, hi);
  require(root >= 0 && root < m_grid.size(),
          "scatter_block: root rank " + std::to_string(root) + " out of range");
  if (m_grid.size() == 1) {
    set_block(prop, lo, hi, std::vector<double>(values, values + count));
    return;
  }
  const Vec3i n = hi - lo;
  const bool is_root = m_grid.rank() == root;
  // the root's checks, told to every rank: a refused block changes nothing
  std::string error = is_root ? block_values_error(prop, nc, n, values, count) : std::string();
  int length = static_cast<int>(error.size());
  MPI_Bcast(&length, 1, MPI_INT, root, m_grid.comm());
  if (length > 0) {
    error.resize(static_cast<std::size_t>(length));
    MPI_Bcast(error.data(), length, MPI_CHAR, root, m_grid.comm());
    throw InputError(error);
  }
  constexpr int tag = 77;
  Vec3i first, extent;
  std::vector<double> part;
  ++m_state_version;
  if (!is_root) { // this rank's nodes, in the block's order
    block_part(m_grid.rank(), lo, hi, first, extent);
    part.resize(static_cast<std::size_t>(extent.prod()) * nc);
    MPI_Recv(part.data(), mpi_count(part.size(), "scatter_block"), MPI_DOUBLE, root, tag,
             m_grid.comm(), MPI_STATUS_IGNORE);
    const double* v = part.data();
    for_each_part_node(lo, n, first, extent, [&](std::size_t, const Vec3i& node) {
      set_node_values(prop, node, v);
      v += nc;
    });
    return;
  }
  // the root packs and sends the others' parts one by one through one
  // buffer, and sets its own nodes straight from the values
  for (int r = 0; r < m_grid.size(); ++r) {
    block_part(r, lo, hi, first, extent);
    if (r == root) {
      for_each_part_node(lo, n, first, extent, [&](std::size_t at, const Vec3i& node) {
        set_node_values(prop, node, values + at * nc);
      });
      continue;
    }
    part.clear();
    for_each_part_node(lo, n, first, extent, [&](std::size_t at, const Vec3i&) {
      part.insert(part.end(), values + at * nc, values + (at + 1) * nc);
    });
    MPI_Send(part.data(), mpi_count(part.size(), "scatter_block"), MPI_DOUBLE, r, tag,
             m_grid.comm());
  }
}

int LBFluid::node_boundary(const Vec3i& node) const {
  return static_cast<int>(m_flag[checked_node(node)]) - 1;
}

double LBFluid::node_density(const Vec3i& node) const {
  const std::size_t n = checked_node(node);
  if (m_flag[n])
    return m_p.density;
  double rho;
  Vec3 j;
  moments(n, rho, j);
  return rho;
}

Vec3 LBFluid::node_velocity(const Vec3i& node) const {
  return velocity_at_index(checked_node(node));
}

Populations LBFluid::node_populations(const Vec3i& node) const {
  const std::size_t n = checked_node(node);
  Populations f;
  if (m_flag[n]) {
    // a solid node holds no fluid: report the equilibrium of the values its
    // density and velocity accessors give (dens, the boundary's velocity)
    const Vec3 u = m_boundaries[m_flag[n] - 1].velocity * m_p.tau / m_p.agrid;
    for (int q = 0; q < Q; ++q)
      f[q] = equilibrium(q, m_p.density, u);
    return f;
  }
  for (int q = 0; q < Q; ++q)
    f[q] = m_pop.full(q, m_pop.slot(q, n));
  return f;
}

Mat3 LBFluid::node_pressure_tensor(const Vec3i& node) const {
  const Populations f = node_populations(node);
  Mat3 pi = Mat3::Zero();
  for (int q = 0; q < Q; ++q)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        pi(a, b) += c[q][a] * c[q][b] * f[q];
  const double scale = m_p.agrid * m_p.agrid / (m_p.tau * m_p.tau);
  return pi * scale;
}

void LBFluid::set_node_populations(const Vec3i& node, const Populations& f) {
  const std::size_t n = checked_node(node);
  require(m_flag[n] == 0, "cannot set the populations of a boundary node");
  for (int q = 0; q < Q; ++q)
    require(std::isfinite(f[q]), "population: values must be finite");
  ++m_state_version; // after the checks: a refused call changes nothing
  for (int q = 0; q < Q; ++q)
    m_pop.set_full(q, m_pop.slot(q, n), f[q]);
}

void LBFluid::set_node_density_velocity(const Vec3i& node, double rho, const Vec3& u) {
  const std::size_t n = checked_node(node);
  require(m_flag[n] == 0, "cannot set the density or velocity of a boundary node");
  require(std::isfinite(rho) && rho > 0.0, "density must be a finite number > 0");
  require(u.allFinite(), "velocity must be finite");
  // the stored momentum is rho u - F_ext / 2 so that node_velocity() returns u
  const Vec3 u_lattice = u * m_p.tau / m_p.agrid - 0.5 * m_ext_lattice / rho;
  ++m_state_version;
  for (int q = 0; q < Q; ++q)
    m_pop.set_full(q, m_pop.slot(q, n), equilibrium(q, rho, u_lattice));
}

namespace {
/** Rank 0 runs write(); its error, if any, is raised on every rank. */
template <class Write> void write_on_root(MPI_Comm comm, int size, int rank, Write&& write) {
  std::string error;
  if (rank == 0) {
    try {
      write();
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  if (size > 1) {
    int length = static_cast<int>(error.size());
    MPI_Bcast(&length, 1, MPI_INT, 0, comm);
    error.resize(static_cast<std::size_t>(length));
    MPI_Bcast(error.data(), length, MPI_CHAR, 0, comm);
  }
  if (!error.empty())
    throw InputError(error);
}
} // namespace

void LBFluid::write_vtk_field(const std::string& path, const std::string& prop) const {
  require_flagged("the fluid's VTK output");
  // (x, y, z) blocks come z fastest; VTK wants x fastest. Gathered on the
  // writing rank only: the others hold their own part, no more.
  const std::vector<double> block = gather_block(prop, Vec3i::Zero(), m_global, 0);
  const std::size_t nc = static_cast<std::size_t>(block_components(prop));
  write_on_root(m_grid.comm(), m_grid.size(), m_grid.rank(), [&] {
    std::vector<double> data;
    data.reserve(block.size());
    for (int k = 0; k < m_global[2]; ++k)
      for (int j = 0; j < m_global[1]; ++j)
        for (int i = 0; i < m_global[0]; ++i) {
          const double* v =
              block.data() +
              nc * ((static_cast<std::size_t>(i) * m_global[1] + j) * m_global[2] + k);
          data.insert(data.end(), v, v + nc);
        }
    io::write_vtk_structured_points(path, m_global, Vec3::Constant(0.5 * m_p.agrid), m_p.agrid,
                                    prop, static_cast<int>(nc), data);
  });
}

void LBFluid::write_vtk_velocity(const std::string& path) const {
  write_vtk_field(path, "velocity");
}

void LBFluid::write_vtk_boundary(const std::string& path) const {
  write_vtk_field(path, "boundary");
}

} // namespace pyoif::lb
