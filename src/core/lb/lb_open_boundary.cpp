// Open faces of the lattice: velocity inlets and pressure outlets by the
// non-equilibrium extrapolation scheme of Guo, Zheng & Shi, "Non-equilibrium
// extrapolation method for velocity and pressure boundary conditions in the
// lattice Boltzmann method", Chin. Phys. 11, 366 (2002): at a boundary node b
// with its first fluid neighbour n inward,
//     f_q(b) = f_q^eq(rho_b, u_b) + [f_q(n) - f_q^eq(rho_n, u_n)],
// second-order accurate; a velocity inlet sets u_b and takes rho_b = rho_n, a
// pressure outlet sets rho_b (p = c_s^2 rho) and takes u_b = u_n.
//
// The lattice is periodic, so the two faces of an open axis are neighbours
// across the periodic edge: either both are open, and both face planes are
// rewritten after every update (after the halo and the bounce-back), which
// cuts the periodic coupling: what the inlet plane streams inward comes from
// the boundary values alone; or the opposite face is closed by walls where
// it meets the open one (open_seam_leaks checks it), so what the open face
// streams across the edge is bounced back into it and rewritten. The planes
// are read and written through population_slot, so the in-place update's
// layout does not matter.
#include "lb/lb_fluid.hpp"
#include "utils/errors.hpp"

#include <mpi.h>

#include <array>
#include <cmath>
#include <string>
#include <utility>

namespace pyoif::lb {

using namespace d3q19;

namespace {
/** The two axes of a face plane of `axis`, in increasing order. */
std::array<int, 2> plane_axes(int axis) {
  return axis == 0 ? std::array<int, 2>{1, 2}
                   : (axis == 1 ? std::array<int, 2>{0, 2} : std::array<int, 2>{0, 1});
}
} // namespace

template <class Body>
void LBFluid::for_each_open_node(const OpenBoundarySpec& face, Body&& body) const {
  const auto [a, b] = plane_axes(face.axis);
  const int layer = face.high ? m_global[face.axis] - 1 : 0;
  Vec3i g;
  g[face.axis] = layer;
  // only this rank's part of the plane: its subdomain's range on a and b
  if (layer < m_origin[face.axis] || layer >= m_origin[face.axis] + m_n[face.axis])
    return;
  for (int i = m_origin[a]; i < m_origin[a] + m_n[a]; ++i)
    for (int j = m_origin[b]; j < m_origin[b] + m_n[b]; ++j) {
      g[a] = i;
      g[b] = j;
      const std::size_t n = owned_index(g);
      if (n == npos || m_flag[n] != 0)
        continue;
      body(n, g, static_cast<std::size_t>(i) * m_global[b] + j);
    }
}

void LBFluid::set_open_boundaries(const std::vector<OpenBoundarySpec>& faces) {
  for (const auto& f : faces) {
    require(f.axis >= 0 && f.axis < 3, "open boundary: axis must be 0, 1 or 2");
    const auto [a, b] = plane_axes(f.axis);
    const std::size_t plane = static_cast<std::size_t>(m_global[a]) * m_global[b];
    if (f.pressure) {
      require(std::isfinite(f.density) && f.density > 0.0,
              "pressure outlet: the density must be a finite number > 0");
    } else {
      require(f.velocity.size() == 3 * plane,
              "velocity inlet: expected 3 velocity components for each of the " +
                  std::to_string(plane) + " nodes of the face, got " +
                  std::to_string(f.velocity.size()) + " values");
      for (const double v : f.velocity)
        require(std::isfinite(v), "velocity inlet: the velocities must be finite");
    }
    require(m_global[f.axis] >= 4, "open boundary: the lattice needs at least 4 nodes along the "
                                   "open axis");
    // the face and its inward neighbour on one rank
    require(m_grid.extent()[f.axis] >= 2,
            "open boundary: a subdomain is a single node thick along the open axis; use fewer "
            "ranks along it (cell_system.node_grid)");
  }
  m_open = faces;
  ++m_state_version;
}

std::vector<long> LBFluid::open_seam_leaks() const {
  require_flagged("the open faces' check");
  std::vector<long> leaks(m_open.size(), 0);
  for (std::size_t i = 0; i < m_open.size(); ++i) {
    const OpenBoundarySpec& face = m_open[i];
    bool opposite_open = false;
    for (const auto& other : m_open)
      opposite_open |= other.axis == face.axis && other.high != face.high;
    if (opposite_open)
      continue;
    // the closed face: the plane at the other end of the axis; its fluid
    // nodes must not meet a fluid node of the open face across the periodic
    // edge (the ghost layer holds the open face's flags there), diagonal
    // neighbours included
    const auto [a, b] = plane_axes(face.axis);
    const std::ptrdiff_t across = (face.high ? -1 : 1) * padded_axis_stride(face.axis);
    OpenBoundarySpec closed; // the opposite plane, walked as a face
    closed.axis = face.axis;
    closed.high = !face.high;
    for_each_open_node(closed, [&](std::size_t n, const Vec3i&, std::size_t) {
      bool meets = false;
      for (int da = -1; da <= 1; ++da)
        for (int db = -1; db <= 1; ++db) {
          const std::ptrdiff_t m = static_cast<std::ptrdiff_t>(n) + across +
                                   da * padded_axis_stride(a) + db * padded_axis_stride(b);
          meets |= m_flag[static_cast<std::size_t>(m)] == 0;
        }
      leaks[i] += meets;
    });
  }
  if (m_grid.size() > 1 && !leaks.empty())
    MPI_Allreduce(MPI_IN_PLACE, leaks.data(), static_cast<int>(leaks.size()), MPI_LONG, MPI_SUM,
                  m_grid.comm());
  return leaks;
}

void LBFluid::apply_open_boundaries() {
  const double to_lattice = m_p.tau / m_p.agrid;
  for (auto& face : m_open) {
    if (!face.pressure && face.flow_rate > 0.0) {
      // The scheme alone delivers a little less than the face's velocities
      // say where the face meets walls (the populations a face node sends
      // into a wall come back to the face, which is rewritten: 3.7 % for a
      // duct 10 nodes high, falling with the width). A slow integral
      // controller scales the face's velocities until the flow through the
      // next plane is the flow rate asked; 1 % of the relative error per
      // update: smooth against the sound waves, converged in a few
      // thousand updates, in a steady flow exact.
      const double measured = open_boundary_fluxes(face).second;
      if (measured > 0.0)
        face.gain *= 1.0 + 0.01 * (face.flow_rate / measured - 1.0);
    }
    const int inward = face.high ? -1 : 1;
    const std::ptrdiff_t step = inward * padded_axis_stride(face.axis);
    for_each_open_node(face, [&](std::size_t n, const Vec3i&, std::size_t k) {
      const std::size_t nb = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(n) + step);
      double rho_n;
      Vec3 j_n;
      moments(nb, rho_n, j_n);
      // the stored momentum is rho u - F_ext / 2 (Guo forcing): the
      // equilibria are taken at that "stored" velocity on both nodes
      const Vec3 u_n = j_n / rho_n;
      double rho_b;
      Vec3 u_b;
      if (face.pressure) {
        rho_b = face.density;
        u_b = u_n;
      } else {
        rho_b = rho_n;
        const Vec3 u = face.gain * Vec3(face.velocity[3 * k], face.velocity[3 * k + 1],
                                        face.velocity[3 * k + 2]);
        u_b = u * to_lattice - 0.5 * m_ext_lattice / rho_b;
      }
      for (int q = 0; q < Q; ++q) {
        const double non_equilibrium =
            m_pop.full(q, m_pop.slot(q, nb)) - equilibrium(q, rho_n, u_n);
        m_pop.set_full(q, m_pop.slot(q, n), equilibrium(q, rho_b, u_b) + non_equilibrium);
      }
    });
  }
}

std::pair<double, double> LBFluid::open_boundary_fluxes(const OpenBoundarySpec& face) const {
  // the momentum density's normal component (with the Guo half force) on
  // the plane next to the face: mass per time, and over the density, volume
  // per time. Not on the face plane itself: its nodes also stream across the
  // periodic edge, into the opposite face, which the boundary rewrites (that
  // half-link flux is not the fluid's); the next plane's momentum is the
  // mean of the two interior link fluxes beside it, equal in a steady flow.
  const std::ptrdiff_t step = (face.high ? -1 : 1) * padded_axis_stride(face.axis);
  std::array<double, 2> flux{0.0, 0.0};
  for_each_open_node(face, [&](std::size_t n, const Vec3i&, std::size_t) {
    double rho;
    Vec3 j;
    moments(static_cast<std::size_t>(static_cast<std::ptrdiff_t>(n) + step), rho, j);
    const double normal = j[face.axis] + 0.5 * m_ext_lattice[face.axis];
    flux[0] += normal;
    flux[1] += normal / rho;
  });
  if (m_grid.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, flux.data(), 2, MPI_DOUBLE, MPI_SUM, m_grid.comm());
  // lattice momentum density (mass / agrid^3 * agrid / tau) times agrid^2
  const double scale = (face.high ? -1.0 : 1.0) * m_p.agrid * m_p.agrid * m_p.agrid / m_p.tau;
  return {flux[0] * scale, flux[1] * scale};
}

std::vector<double> LBFluid::open_boundary_gains() const {
  std::vector<double> out;
  for (const auto& face : m_open)
    out.push_back(face.gain);
  return out;
}

void LBFluid::set_open_boundary_gains(const std::vector<double>& gains) {
  require(gains.size() == m_open.size(), "open boundary gains: one per open face expected");
  for (std::size_t i = 0; i < gains.size(); ++i)
    m_open[i].gain = gains[i];
}

double LBFluid::open_boundary_mass_flux(std::size_t i) const {
  require_flagged("an open face's mass flux");
  require(i < m_open.size(), "open boundary " + std::to_string(i) + " does not exist");
  return open_boundary_fluxes(m_open[i]).first;
}

} // namespace pyoif::lb
