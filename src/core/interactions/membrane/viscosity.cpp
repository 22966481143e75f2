// Membrane viscosity, implicit in the velocities (viscosity.hpp).
#include "interactions/membrane/viscosity.hpp"

#include <cmath>

namespace pyoif::membrane {

void ViscousSolver::apply(int n_nodes, int n_edges, const int* b, const int* c, const double* mass,
                          double dt, const double* p, double* product) const {
  if (dt > 0.0) {
    for (int k = 0; k < n_nodes; ++k)
      for (int d = 0; d < 3; ++d)
        product[3 * k + d] = mass[k] / dt * p[3 * k + d];
  } else {
    for (int i = 0; i < 3 * n_nodes; ++i)
      product[i] = 0.0;
  }
  // each dashpot: kvisc e e^T (p_B - p_C) on B, the opposite on C
  for (int k = 0; k < n_edges; ++k) {
    const double* e = &m_unit[3 * k];
    const double* pb = &p[3 * b[k]];
    const double* pc = &p[3 * c[k]];
    const double s =
        m_weight[k] * (e[0] * (pb[0] - pc[0]) + e[1] * (pb[1] - pc[1]) + e[2] * (pb[2] - pc[2]));
    for (int d = 0; d < 3; ++d) {
      product[3 * b[k] + d] += s * e[d];
      product[3 * c[k] + d] -= s * e[d];
    }
  }
}

void ViscousSolver::add_forces(int n_nodes, int n_edges, const int* b, const int* c,
                               const ViscosityParams* params, const double* x, const double* v,
                               const double* mass, const double* load, double dt, double* f) {
  last_iterations = 0;
  const int n3 = 3 * n_nodes;
  m_unit.resize(3 * n_edges);
  m_weight.resize(n_edges);
  for (auto* a : {&m_solution, &m_residual, &m_direction, &m_z, &m_product})
    a->resize(n3);
  m_block.assign(9 * n_nodes, 0.0);
  // the edges' unit vectors; a zero-length edge (the pass reports it) damps nothing
  for (int k = 0; k < n_edges; ++k) {
    double e[3], l2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      e[d] = x[3 * c[k] + d] - x[3 * b[k] + d];
      l2 += e[d] * e[d];
    }
    const double inv_l = l2 > 0.0 ? 1.0 / std::sqrt(l2) : 0.0;
    for (int d = 0; d < 3; ++d)
      m_unit[3 * k + d] = e[d] * inv_l;
    m_weight[k] = params[k].kvisc;
  }
  if (!(dt > 0.0)) { // the explicit force -C v
    apply(n_nodes, n_edges, b, c, mass, 0.0, v, m_product.data());
    for (int i = 0; i < n3; ++i)
      f[i] -= m_product[i];
    return;
  }
  // block-Jacobi preconditioner: per node the inverse of m/dt I + sum kvisc e e^T
  for (int k = 0; k < n_nodes; ++k)
    for (int d = 0; d < 3; ++d)
      m_block[9 * k + 4 * d] = mass[k] / dt;
  for (int k = 0; k < n_edges; ++k) {
    const double* e = &m_unit[3 * k];
    for (const int node : {b[k], c[k]})
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s)
          m_block[9 * node + 3 * r + s] += m_weight[k] * e[r] * e[s];
  }
  for (int k = 0; k < n_nodes; ++k) { // symmetric 3x3 inverse by cofactors
    double* a = &m_block[9 * k];
    const double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8],
                 c02 = a[3] * a[7] - a[4] * a[6];
    const double inv_det = 1.0 / (a[0] * c00 + a[1] * c01 + a[2] * c02);
    const double inverse[9] = {c00 * inv_det,
                               (a[2] * a[7] - a[1] * a[8]) * inv_det,
                               (a[1] * a[5] - a[2] * a[4]) * inv_det,
                               c01 * inv_det,
                               (a[0] * a[8] - a[2] * a[6]) * inv_det,
                               (a[2] * a[3] - a[0] * a[5]) * inv_det,
                               c02 * inv_det,
                               (a[1] * a[6] - a[0] * a[7]) * inv_det,
                               (a[0] * a[4] - a[1] * a[3]) * inv_det};
    for (int i = 0; i < 9; ++i)
      a[i] = inverse[i];
  }
  auto precondition = [&](const double* r, double* z) {
    for (int k = 0; k < n_nodes; ++k) {
      const double* a = &m_block[9 * k];
      for (int d = 0; d < 3; ++d)
        z[3 * k + d] =
            a[3 * d] * r[3 * k] + a[3 * d + 1] * r[3 * k + 1] + a[3 * d + 2] * r[3 * k + 2];
    }
  };
  auto dot = [n3](const double* p, const double* q) {
    double s = 0.0;
    for (int i = 0; i < n3; ++i)
      s += p[i] * q[i];
    return s;
  };
  double *const sol = m_solution.data(), *const r = m_residual.data(),
                *const dir = m_direction.data(), *const z = m_z.data(), *const q = m_product.data();
  // from the explicit prediction v + dt F / m: the residual is -C of it
  for (int k = 0; k < n_nodes; ++k)
    for (int d = 0; d < 3; ++d)
      sol[3 * k + d] = v[3 * k + d] + dt / mass[k] * load[3 * k + d];
  apply(n_nodes, n_edges, b, c, mass, 0.0, sol, q);
  for (int i = 0; i < n3; ++i)
    r[i] = -q[i];
  precondition(r, z);
  for (int i = 0; i < n3; ++i)
    dir[i] = z[i];
  double rz = dot(r, z);
  const double stop = tolerance * tolerance * rz;
  while (rz > stop && rz > 0.0 && last_iterations < max_iterations) {
    apply(n_nodes, n_edges, b, c, mass, dt, dir, q);
    const double alpha = rz / dot(dir, q);
    for (int i = 0; i < n3; ++i) {
      sol[i] += alpha * dir[i];
      r[i] -= alpha * q[i];
    }
    precondition(r, z);
    const double rz_next = dot(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (int i = 0; i < n3; ++i)
      dir[i] = z[i] + beta * dir[i];
    ++last_iterations;
  }
  // At the solution (M/dt)(v_new - v) = -C v_new: written as the dashpots'
  // force at v_new, pairs of opposite forces along the edges, it conserves
  // momentum and angular momentum exactly, converged or not.
  apply(n_nodes, n_edges, b, c, mass, 0.0, sol, q);
  for (int i = 0; i < n3; ++i)
    f[i] -= q[i];
}

} // namespace pyoif::membrane
