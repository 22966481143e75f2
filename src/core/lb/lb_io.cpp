// The lattice's input and output: single nodes (this rank's), blocks of
// nodes (collective: each rank fills its own nodes, the sum over the ranks
// is every value exactly) and the legacy VTK fields written by rank 0.
#include "lb/lb_fluid.hpp"

#include "io/vtk_legacy.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
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
      for (int k = lo[2]; k < hi[2]; ++k, o += nc) {
        const Vec3i node(i, j, k);
        if (!owns(node))
          continue;
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
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, out.data(), static_cast<int>(out.size()), MPI_DOUBLE, MPI_SUM,
                  m_grid.comm());
  return out;
}

void LBFluid::set_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                        const std::vector<double>& values) {
  require_flagged("setting lattice nodes");
  const int nc = block_components(prop);
  if (prop != "velocity" && prop != "density" && prop != "population" &&
      prop != "stored_population" && prop != "coupling_field")
    throw InputError(prop + " is read-only");
  // a checkpoint's raw state: every node, solid ones included
  const bool raw = prop == "stored_population" || prop == "coupling_field";
  check_block(lo, hi);
  const Vec3i n = hi - lo;
  if (values.size() != static_cast<std::size_t>(n.prod()) * nc)
    throw InputError(prop + ": expected " + std::to_string(nc) + " value(s) per node for " +
                     std::to_string(n.prod()) + " node(s), got " + std::to_string(values.size()));
  // the value checks first, on every rank alike (the same values): a refused
  // block changes nothing anywhere
  for (std::size_t v = 0; v < values.size(); ++v) {
    require(std::isfinite(values[v]), prop + ": values must be finite");
    if (prop == "density")
      require(values[v] > 0.0, "density must be a finite number > 0");
  }
  if (n.prod() == 1 && !raw) {
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
      for (int k = lo[2]; k < hi[2]; ++k, v += nc) {
        const Vec3i node(i, j, k);
        const std::size_t own = owned_index(node);
        if (own != npos && prop == "stored_population") {
          for (int q = 0; q < Q; ++q)
            m_pop.set_at(m_pop.slot(q, own), v[q]);
          continue;
        }
        if (own != npos && prop == "coupling_field") {
          if (v[0] != 0.0) {
            open_impulse_field();
            m_field_valid[own >> 6] &= ~(std::uint64_t{1} << (own & 63));
            add_field_impulse(own, Vec3(v[1], v[2], v[3]));
          } else if (!m_field.empty()) {
            m_field_valid[own >> 6] &= ~(std::uint64_t{1} << (own & 63));
          }
          continue;
        }
        // a block spanning boundary nodes sets the fluid nodes only
        if (own == npos || m_flag[own] != 0 || raw)
          continue;
        // written here, not through set_node_*: those count a change on
        // the owner only, and the fluid's state_version must stay the same
        // on every rank (it decides collective recomputations)
        if (prop == "population") {
          for (int q = 0; q < Q; ++q)
            m_pop.set_full(q, m_pop.slot(q, own), v[q]);
          continue;
        }
        const double rho = prop == "density" ? v[0] : node_density(node);
        const Vec3 u = prop == "velocity" ? Vec3(v[0], v[1], v[2]) : node_velocity(node);
        // the stored momentum is rho u - F_ext / 2 so that node_velocity() returns u
        const Vec3 u_lattice = u * m_p.tau / m_p.agrid - 0.5 * m_ext_lattice / rho;
        for (int q = 0; q < Q; ++q)
          m_pop.set_full(q, m_pop.slot(q, own), equilibrium(q, rho, u_lattice));
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
  // (x, y, z) blocks come z fastest; VTK wants x fastest
  const std::vector<double> block = get_block(prop, Vec3i::Zero(), m_global);
  const std::size_t nc = block.size() / static_cast<std::size_t>(m_global.prod());
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
