// LBFluid: parameters, the boundary flagging step (flags, runs and links from
// boundary_links.cpp), the load balance and repartition, the totals. The
// update loop is in lb_kernel.cpp (its sweep in collide_stream.cpp), the
// halo in lb_halo.cpp, node and block access and VTK output in lb_io.cpp.
#include "lb/lb_fluid.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#ifdef PYOIF_WITH_OPENMP
#include <omp.h>
#endif

namespace pyoif::lb {

using namespace d3q19;

namespace {

/** lambda = 1 - omega, with omega checked to lie in (0, 2). */
double lambda_of(double omega, const std::string& what) {
  require(std::isfinite(omega) && omega > 0.0 && omega < 2.0,
          what + ": the relaxation rate " + format_number(omega) +
              " lies outside the open range (0, 2); choose another value");
  return 1.0 - omega;
}

} // namespace

LBFluid::LBFluid(const LBParams& p, const BoxGeometry& box, MPI_Comm comm, const Vec3i& node_grid,
                 bool balance_fluid)
    : m_p(p), m_box(box.length()), m_grid(Vec3i::Ones()), m_balance(balance_fluid) {
  auto finite_positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  require(finite_positive(p.agrid),
          "agrid must be a finite number > 0, got " + format_number(p.agrid));
  require(finite_positive(p.tau), "tau must be a finite number > 0, got " + format_number(p.tau));
  require(finite_positive(p.density),
          "dens must be a finite number > 0, got " + format_number(p.density));
  require(finite_positive(p.viscosity),
          "visc must be a finite number > 0, got " + format_number(p.viscosity));
  require(finite_positive(p.bulk_viscosity),
          "bulk_visc must be a finite number > 0, got " + format_number(p.bulk_viscosity));
  require(std::isfinite(p.kT) && p.kT >= 0.0,
          "kT must be a finite number >= 0, got " + format_number(p.kT));
  require(p.ext_force_density.allFinite(), "ext_force_density must be finite");
  require(p.n_threads >= 0, "n_threads must be >= 0 (0: OMP_NUM_THREADS or 1)");

  for (int d = 0; d < 3; ++d) {
    const double cells = m_box[d] / p.agrid;
    const double rounded = std::round(cells);
    require(rounded >= 1.0 && std::abs(cells - rounded) <= 1e-9 * std::max(1.0, rounded),
            "agrid " + format_number(p.agrid) + " does not divide the box length " +
                format_number(m_box[d]) + " on axis " + std::to_string(d) +
                " (box_l / agrid = " + format_number(cells) + " must be a positive integer)");
    // a padded axis must fit an int (the indices and offsets are ints)
    require(rounded <= 1e8, "agrid " + format_number(p.agrid) + " gives " + format_number(rounded) +
                                " lattice nodes on axis " + std::to_string(d) +
                                "; a lattice that fine cannot be stored");
    m_global[d] = static_cast<int>(rounded);
  }
  {
    // 19 populations + flags per padded node: refused (instead of an
    // allocation whose size wrapped around) when it exceeds 2^50 bytes
    const double padded = double(m_global[0] + 2) * (m_global[1] + 2) * (m_global[2] + 2);
    const double bytes = p.single_precision ? sizeof(float) : sizeof(double);
    require(padded * (Q * bytes + 2) < std::ldexp(1.0, 50),
            "the lattice of " + format_number(double(m_global[0]) * m_global[1] * m_global[2]) +
                " nodes (box / agrid) needs more than 2^50 bytes; use a larger agrid");
  }
  m_grid = DomainGrid(comm, m_global, node_grid);

  // Relaxation (Duenweg, Schiller & Ladd 2007, eqs. 40-41, in lattice units):
  // nu = (1/omega_s - 1/2) / 3, nu_bulk = 2 (1/omega_b - 1/2) / 9.
  const double nu = p.viscosity * p.tau / (p.agrid * p.agrid);
  const double nu_b = p.bulk_viscosity * p.tau / (p.agrid * p.agrid);
  const double omega_s = 1.0 / (3.0 * nu + 0.5);
  m_relax.shear =
      lambda_of(omega_s, "visc (shear relaxation, visc * tau / agrid^2 = " + format_number(nu) +
                             " in lattice units)");
  // magic parameter Lambda = (1/omega+ - 1/2)(1/omega- - 1/2) = 3/16 puts the
  // halfway bounce-back wall exactly midway for Poiseuille flow, whatever
  // the viscosity (Ginzburg, Verhaeghe & d'Humieres, Commun. Comput. Phys. 3,
  // 427 (2008)); omega+ the shear rate, omega- the odd (ghost) modes' rate
  const double omega_magic_odd = 1.0 / (0.5 + (3.0 / 16.0) / (1.0 / omega_s - 0.5));
  switch (p.collision) {
  case Collision::mrt:
  case Collision::mrt_espresso:
    m_relax.bulk = lambda_of(2.0 / (9.0 * nu_b + 1.0), "bulk_visc (bulk relaxation)");
    // even ghost modes relaxed to equilibrium in one update (omega = 1); the
    // odd ghost modes at the magic rate, or at 1 as ESPResSo 4.2 does (its
    // wall then moves with viscosity: a Poiseuille error of 1.75e-2 at
    // nu = 1 lattice unit against 8.4e-4 at 1/6, H = 20)
    m_relax.even = 0.0;
    m_relax.odd =
        p.collision == Collision::mrt
            ? lambda_of(omega_magic_odd, "visc (MRT odd ghost relaxation, magic parameter)")
            : 0.0;
    break;
  case Collision::trt:
    m_relax.bulk = m_relax.even = m_relax.shear;
    m_relax.odd = lambda_of(omega_magic_odd, "visc (TRT odd relaxation from the magic parameter)");
    break;
  case Collision::bgk:
    m_relax.bulk = m_relax.even = m_relax.odd = m_relax.shear;
    break;
  }

  m_ext_lattice = p.ext_force_density * p.tau * p.tau / p.agrid;
  m_kT_lattice = p.kT * p.tau * p.tau / std::pow(p.agrid, 5);

  // Orthogonal moment basis of Duenweg, Schiller & Ladd (2007), table I,
  // Gram-Schmidt orthogonalised in the w-weighted scalar product: used for
  // the thermal noise of the stress and ghost modes.
  for (int q = 0; q < Q; ++q) {
    const double x = c[q][0], y = c[q][1], z = c[q][2];
    const double c2 = x * x + y * y + z * z;
    const double e[Q] = {1.0,
                         x,
                         y,
                         z,
                         c2 - 1.0,
                         x * x - y * y,
                         c2 - 3.0 * z * z,
                         x * y,
                         x * z,
                         y * z,
                         (3.0 * c2 - 5.0) * x,
                         (3.0 * c2 - 5.0) * y,
                         (3.0 * c2 - 5.0) * z,
                         (y * y - z * z) * x,
                         (z * z - x * x) * y,
                         (x * x - y * y) * z,
                         3.0 * c2 * c2 - 6.0 * c2 + 1.0,
                         (2.0 * c2 - 3.0) * (x * x - y * y),
                         (2.0 * c2 - 3.0) * (c2 - 3.0 * z * z)};
    for (int m = 0; m < Q; ++m)
      m_basis[m][q] = e[m];
  }
  auto dot = [&](int a, int b) {
    double s = 0.0;
    for (int q = 0; q < Q; ++q)
      s += w[q] * m_basis[a][q] * m_basis[b][q];
    return s;
  };
  for (int m = 0; m < Q; ++m) {
    for (int k = 0; k < m; ++k) {
      const double proj = dot(m, k) / dot(k, k);
      for (int q = 0; q < Q; ++q)
        m_basis[m][q] -= proj * m_basis[k][q];
    }
    if (!(dot(m, m) > 1e-12))
      throw std::logic_error("D3Q19 moment basis is degenerate");
  }
  for (int m = 4; m < Q; ++m) {
    const double lambda = m == 4    ? m_relax.bulk
                          : m <= 9  ? m_relax.shear
                          : m <= 15 ? m_relax.odd
                                    : m_relax.even;
    // DSL eq. 66: variance mu b_m (1 - lambda^2), mu = rho kT / c_s^2 (lattice)
    m_noise_factor[m] = 3.0 * m_kT_lattice * (1.0 - lambda * lambda) / dot(m, m);
  }

  set_n_threads(p.n_threads);
  allocate_subdomain();
  rebuild_geometry();
}

void LBFluid::allocate_subdomain() {
  m_origin = m_grid.lower();
  m_n = m_grid.extent();
  m_pad = m_n + Vec3i::Constant(2);
  for (int q = 0; q < Q; ++q)
    m_offset[q] = (static_cast<std::ptrdiff_t>(c[q][2]) * m_pad[1] + c[q][1]) * m_pad[0] + c[q][0];
  const std::size_t nodes = static_cast<std::size_t>(m_pad[0]) * m_pad[1] * m_pad[2];
  m_pop.allocate(nodes, m_offset, m_p.single_precision, m_p.density);
  m_flag.assign(nodes, 0);
  m_field.clear();
  m_field_valid.clear();
  m_field_used = false;
  ++m_layout_generation;      // the coupling's padded indices are stale
  for (int q = 0; q < Q; ++q) // in memory order
    for (int z = 1; z <= m_n[2]; ++z)
      for (int y = 1; y <= m_n[1]; ++y)
        for (int x = 1; x <= m_n[0]; ++x)
          m_pop.set_full(q, q * m_pop.stride() + index(x, y, z), w[q] * m_p.density);
}

void LBFluid::repartition(const DomainGrid& old_grid) {
  // Every rank sends the nodes of its old subdomain that lie in another
  // rank's new one (all 19 populations, normal layout, x fastest over the
  // overlap box); the boxes are known to all, so are the counts. They travel
  // as double in either precision (a float goes through double unchanged):
  // a rare step, run when the boundaries are set.
  normalize_layout();
  const int size = m_grid.size();
  auto overlap = [](const Vec3i& lo_a, const Vec3i& n_a, const Vec3i& lo_b, const Vec3i& n_b,
                    Vec3i& lo, Vec3i& n) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::max(lo_a[d], lo_b[d]);
      n[d] = std::max(0, std::min(lo_a[d] + n_a[d], lo_b[d] + n_b[d]) - lo[d]);
    }
    return n.prod();
  };
  const Vec3i old_lo = old_grid.lower(), old_n = old_grid.extent();
  const Vec3i old_pad = old_n + Vec3i::Constant(2);
  auto old_index = [&](const Vec3i& g) {
    const Vec3i l = g - old_lo + Vec3i::Ones();
    return (static_cast<std::size_t>(l[2]) * old_pad[1] + l[1]) * old_pad[0] + l[0];
  };
  std::vector<int> send_counts(size), recv_counts(size), send_displs(size), recv_displs(size);
  std::vector<double> send;
  for (int r = 0; r < size; ++r) {
    const Vec3i c = m_grid.coords_of(r);
    Vec3i lo, n;
    send_displs[r] = static_cast<int>(send.size());
    if (overlap(old_lo, old_n, m_grid.lower(c), m_grid.extent(c), lo, n) > 0)
      for (int z = lo[2]; z < lo[2] + n[2]; ++z)
        for (int y = lo[1]; y < lo[1] + n[1]; ++y)
          for (int x = lo[0]; x < lo[0] + n[0]; ++x) {
            const std::size_t i = old_index(Vec3i(x, y, z));
            for (int q = 0; q < Q; ++q)
              send.push_back(m_pop.at(q * m_pop.stride() + i));
          }
    send_counts[r] = static_cast<int>(send.size()) - send_displs[r];
  }
  const Vec3i new_lo = m_grid.lower(), new_n = m_grid.extent();
  int total = 0;
  for (int r = 0; r < size; ++r) {
    const Vec3i c = old_grid.coords_of(r);
    Vec3i lo, n;
    recv_displs[r] = total;
    recv_counts[r] = Q * overlap(old_grid.lower(c), old_grid.extent(c), new_lo, new_n, lo, n);
    total += recv_counts[r];
  }
  std::vector<double> recv(static_cast<std::size_t>(total));
  MPI_Alltoallv(send.data(), send_counts.data(), send_displs.data(), MPI_DOUBLE, recv.data(),
                recv_counts.data(), recv_displs.data(), MPI_DOUBLE, m_grid.comm());
  allocate_subdomain();
  std::size_t k = 0;
  for (int r = 0; r < size; ++r) {
    const Vec3i c = old_grid.coords_of(r);
    Vec3i lo, n;
    if (overlap(old_grid.lower(c), old_grid.extent(c), new_lo, new_n, lo, n) == 0)
      continue;
    for (int z = lo[2]; z < lo[2] + n[2]; ++z)
      for (int y = lo[1]; y < lo[1] + n[1]; ++y)
        for (int x = lo[0]; x < lo[0] + n[0]; ++x) {
          const std::size_t i = domain_index(Vec3i(x, y, z));
          for (int q = 0; q < Q; ++q)
            m_pop.set_at(q * m_pop.stride() + i, recv[k++]);
        }
  }
}

std::size_t LBFluid::domain_index(const Vec3i& g) const {
  int l[3];
  for (int d = 0; d < 3; ++d)
    l[d] = ((g[d] - m_origin[d]) % m_global[d] + m_global[d]) % m_global[d] + 1;
  return index(l[0], l[1], l[2]);
}

std::size_t LBFluid::owned_index(const Vec3i& node) const {
  for (int d = 0; d < 3; ++d)
    if (node[d] < m_origin[d] || node[d] >= m_origin[d] + m_n[d])
      return npos;
  return index(node[0] - m_origin[0] + 1, node[1] - m_origin[1] + 1, node[2] - m_origin[2] + 1);
}

void LBFluid::normalize_layout() {
  m_pop.normalize([this](auto&& body) {
    for (const Run& r : m_geometry.runs)
      for (int i = 0; i < r.length; ++i)
        body(r.start + i);
  });
}

void LBFluid::set_n_threads(int n) {
  require(n >= 0, "n_threads must be >= 0, got " + std::to_string(n));
  m_p.n_threads = n;
#ifdef PYOIF_WITH_OPENMP
  // Never oversubscribe by default (mpirun ranks share the cores): one thread
  // unless the user asked for more via OMP_NUM_THREADS or n_threads.
  if (n > 0)
    m_threads = n;
  else
    m_threads = std::getenv("OMP_NUM_THREADS") ? omp_get_max_threads() : 1;
#else
  m_threads = 1;
#endif
}

void LBFluid::set_ext_force_density(const Vec3& f) {
  require(f.allFinite(), "ext_force_density must be finite");
  m_p.ext_force_density = f;
  m_ext_lattice = f * m_p.tau * m_p.tau / m_p.agrid;
  ++m_state_version;
}

void LBFluid::validate(const BoxGeometry& box, double time_step) const {
  for (int d = 0; d < 3; ++d) {
    const double cells = box.length()[d] / m_p.agrid;
    require(std::abs(cells - std::round(cells)) <= 1e-9 * std::max(1.0, cells) && cells >= 0.5,
            "agrid " + format_number(m_p.agrid) + " does not divide the box length " +
                format_number(box.length()[d]) + " on axis " + std::to_string(d));
    require(static_cast<int>(std::round(cells)) == m_global[d],
            "box_l changed after the fluid was created (axis " + std::to_string(d) + ": " +
                std::to_string(m_global[d]) + " nodes); remove and re-add the fluid");
  }
  require(std::isfinite(time_step) && time_step > 0.0,
          "time_step must be > 0, got " + format_number(time_step));
  const double ratio = m_p.tau / time_step;
  require(std::round(ratio) >= 1.0 && std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio,
          "tau " + format_number(m_p.tau) + " must be an integer multiple of the time_step " +
              format_number(time_step) + " (tau / time_step = " + format_number(ratio) + ")");
}

void LBFluid::set_boundaries(const std::vector<BoundarySpec>& boundaries) {
  require(boundaries.size() < 65535, "too many lattice-Boltzmann boundaries");
  for (const auto& b : boundaries) {
    require(b.shape != nullptr, "LBBoundary: shape must be set");
    require(b.velocity.allFinite(), "LBBoundary: velocity must be finite");
  }
  ++m_state_version;
  // no boundaries where there were none (a fresh fluid, a clear() of an
  // empty list): the flags stand, nothing waits for system.prepare()
  if (boundaries.empty() && m_boundaries.empty() && !m_boundaries_pending)
    return;
  // flagged by the explicit collective step (update_boundaries, System::prepare)
  m_pending_boundaries = boundaries;
  m_boundaries_pending = true;
}

void LBFluid::require_flagged(const char* what) const {
  if (m_boundaries_pending)
    throw InputError(std::string("LBFluid: ") + what +
                     " needs the lattice flagged for its boundaries, and system.lbboundaries "
                     "changed since the last system.prepare() or run: call system.prepare() "
                     "first (collective: on every rank)");
}

void LBFluid::update_boundaries() {
  if (!m_boundaries_pending)
    return;
  ++m_n_flaggings;
  const std::vector<BoundarySpec>& boundaries = m_pending_boundaries;
  normalize_layout();
  std::vector<std::uint16_t> flag = flags_for(boundaries);
  long any_fluid = 0;
  for (int z = 1; z <= m_n[2]; ++z)
    for (int y = 1; y <= m_n[1]; ++y)
      for (int x = 1; x <= m_n[0]; ++x)
        any_fluid |= flag[index(x, y, z)] == 0;
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, &any_fluid, 1, MPI_LONG, MPI_MAX, m_grid.comm());
  // no fluid left: refused (nothing changed)
  if (!any_fluid && !boundaries.empty()) {
    std::string names;
    for (std::size_t b = 0; b < boundaries.size() && b < 20; ++b)
      names += (b ? ", " : "") + std::to_string(b) + ": " + boundaries[b].shape->name();
    if (boundaries.size() > 20)
      names += ", ...";
    throw InputError("LBBoundary: the " + std::to_string(boundaries.size()) +
                     " boundaries of system.lbboundaries (" + names +
                     ") cover every lattice node, no fluid is left; remove or change one "
                     "before the fluid is used");
  }
  // Load balance: while no particle has coupled yet (the coupling's records
  // hold this rank's node indices), the cuts move so that every rank holds
  // about as many fluid nodes (the solid ones cost nothing in the update).
  if (m_balance && m_grid.size() > 1 && !m_coupled) {
    std::array<std::vector<double>, 3> planes;
    for (int d = 0; d < 3; ++d)
      planes[d].assign(m_global[d], 0.0);
    for (int z = 1; z <= m_n[2]; ++z)
      for (int y = 1; y <= m_n[1]; ++y)
        for (int x = 1; x <= m_n[0]; ++x)
          if (flag[index(x, y, z)] == 0) {
            planes[0][m_origin[0] + x - 1] += 1.0;
            planes[1][m_origin[1] + y - 1] += 1.0;
            planes[2][m_origin[2] + z - 1] += 1.0;
          }
    for (auto& v : planes)
      MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), MPI_DOUBLE, MPI_SUM,
                    m_grid.comm());
    DomainGrid balanced = m_grid;
    if (balanced.balance(planes)) {
      const DomainGrid old = m_grid;
      m_grid = balanced;
      repartition(old);
      // the old boundaries' flags on the new subdomain
      m_flag = flags_for(m_boundaries);
      flag = flags_for(boundaries);
    }
  }
  const std::vector<std::uint16_t> old_flag = std::move(m_flag);
  m_flag = std::move(flag);
  m_boundaries = std::move(m_pending_boundaries);
  m_pending_boundaries.clear();
  m_boundaries_pending = false;
  // nodes that became fluid start at rest at the reference density
  for (int z = 1; z <= m_n[2]; ++z) // (in memory order)
    for (int y = 1; y <= m_n[1]; ++y)
      for (int x = 1; x <= m_n[0]; ++x) {
        const std::size_t n = index(x, y, z);
        if (old_flag[n] != 0 && m_flag[n] == 0)
          for (int q = 0; q < Q; ++q)
            m_pop.set_full(q, q * m_pop.stride() + n, w[q] * m_p.density);
        if (m_flag[n] != 0)
          for (int q = 0; q < Q; ++q)
            m_pop.set_at(q * m_pop.stride() + n, 0.0);
        // Coupling impulses waiting for the next update (a run that stopped
        // between updates, tau > time_step) stay with the nodes that remain
        // fluid; on a node turned solid they are dropped (the wall takes
        // them, as it takes every deposit on a solid node). A node that was
        // solid may hold such old deposits, which no update read: dropped.
        if (!m_field_valid.empty() && (old_flag[n] != 0 || m_flag[n] != 0))
          m_field_valid[n >> 6] &= ~(std::uint64_t{1} << (n & 63));
      }
  rebuild_geometry();
}

void LBFluid::rebuild_geometry() {
  ++m_state_version;
  m_geometry = fluid_geometry(m_flag, padded_box(), m_offset, m_boundaries, m_p.tau, m_p.agrid,
                              m_p.density, m_pop.stride());
  long counts[2] = {static_cast<long>(m_geometry.n_fluid),
                    static_cast<long>(m_geometry.links.size())};
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_LONG, MPI_SUM, m_grid.comm());
  m_n_fluid_global = static_cast<std::size_t>(counts[0]);
  m_n_links_global = static_cast<std::size_t>(counts[1]);
  build_halo_pairs();
}

Vec3 LBFluid::boundary_force(int b) const {
  require_flagged("a boundary's force");
  require(b >= 0 && b < static_cast<int>(m_boundaries.size()),
          "boundary index " + std::to_string(b) + " out of range");
  // Momentum exchange of the last streaming (Ladd 1994): the population
  // f_q* sent towards the wall came back as f_{-q} = f_q* - wall_term, so the
  // wall received c_q (f_q* + f_{-q}) = c_q (2 f_{-q} + wall_term).
  Vec3 sum = Vec3::Zero();
  for (const BoundaryLink& l : m_geometry.links) {
    if (l.boundary != b)
      continue;
    const double back = m_pop.full(opposite(l.q), m_pop.slot(opposite(l.q), l.node));
    const double transfer = 2.0 * back + l.wall_term;
    for (int d = 0; d < 3; ++d)
      sum[d] += c[l.q][d] * transfer;
  }
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, sum.data(), 3, MPI_DOUBLE, MPI_SUM, m_grid.comm());
  return sum * std::pow(m_p.agrid, 4) / (m_p.tau * m_p.tau);
}

void LBFluid::open_impulse_field() {
  if (m_field.empty()) {
    m_field.assign(3 * m_pop.stride(), 0.0);
    m_field_valid.assign((m_pop.stride() >> 6) + 2, 0); // + 1 spare: field_valid_bits32
  }
  m_field_used = true;
}

void LBFluid::velocities_at(CouplingNodes& list) {
  // The 19 populations of a node lie in 19 streams far apart; the hardware
  // prefetchers do not follow a sparse walk through them, so the node
  // `ahead` places down the list is requested while this one is summed.
  constexpr std::size_t ahead = 16;
  const std::ptrdiff_t* off = m_pop.read_offset();
  const std::size_t* nodes = list.node.data();
  const std::size_t count = list.n_nodes;
  list.node_coupling.resize(count);
  auto* out = list.node_coupling.data();
  const std::uint32_t* entry = list.compact.data();
  // a fluid ghost's velocity comes from its owner: NaN until then, so that
  // a ghost the owner did not send could not pass unnoticed
  const Vec3 not_yet = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  m_pop.visit([&](const auto* populations) {
    for (std::size_t i = 0; i < count; ++i) {
      if (i + ahead < count) {
        const auto* f = populations + nodes[i + ahead];
        for (int q = 0; q < Q; ++q)
          __builtin_prefetch(f + off[q], 0, 1);
      }
      const std::size_t n = nodes[i];
      out[entry[n]] = {is_fluid_ghost(n) ? not_yet : velocity_at_index(n), Vec3::Zero()};
    }
  });
  if (list.ghosts_pending)
    exchange_coupling_ghosts(list, true);
}

double LBFluid::total_mass() const {
  require_flagged("the fluid's total mass");
  double mass = 0.0; // summed in double in either precision
  m_pop.visit([&](const auto* populations) {
    for (const Run& r : m_geometry.runs)
      for (int q = 0; q < Q; ++q) {
        const auto* f = populations + m_pop.slot(q, r.start);
        for (int i = 0; i < r.length; ++i)
          mass += f[i];
      }
    // deviation storage (single precision): each fluid node holds rho0 more
    if constexpr (std::is_same_v<std::remove_const_t<std::remove_pointer_t<decltype(populations)>>,
                                 float>)
      mass += m_p.density * static_cast<double>(m_geometry.n_fluid);
  });
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, &mass, 1, MPI_DOUBLE, MPI_SUM, m_grid.comm());
  return mass * std::pow(m_p.agrid, 3);
}

Vec3 LBFluid::total_momentum() const {
  require_flagged("the fluid's total momentum");
  Vec3 j = Vec3::Zero();
  m_pop.visit([&](const auto* populations) {
    for (const Run& r : m_geometry.runs) {
      for (int q = 1; q < Q; ++q) {
        const auto* f = populations + m_pop.slot(q, r.start);
        double s = 0.0;
        for (int i = 0; i < r.length; ++i)
          s += f[i];
        for (int d = 0; d < 3; ++d)
          j[d] += c[q][d] * s;
      }
      if (m_field_used)
        for (int i = 0; i < r.length; ++i)
          if (field_valid(r.start + i))
            for (int d = 0; d < 3; ++d)
              j[d] += m_field[3 * (r.start + i) + d];
    }
  });
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, j.data(), 3, MPI_DOUBLE, MPI_SUM, m_grid.comm());
  return j * std::pow(m_p.agrid, 4) / m_p.tau;
}

} // namespace pyoif::lb
