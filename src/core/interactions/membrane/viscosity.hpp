// Membrane viscosity: dashpots along the edges. On an edge AB the force on A
// is kvisc ((v_B - v_A).e) e, e the unit edge vector, and -that on B: it damps
// the relative velocity of the two nodes along the edge (ESPResSo's OIF
// "variant B"); dissipative, no energy. With dashpots as with springs, the
// membrane's 2-D viscosity is eta_m = sqrt(3) kvisc / 4 (Fedosov, Caswell,
// Karniadakis, Biophys. J. 98, 2215, 2010, with only their central term).
//
// Why implicit. Written as a force of the current velocities, the dashpots
// are stable only while dt kvisc / m stays below about 1/3 (the highest mode
// of a six-neighbour mesh, neighbours moving against each other, has the
// rate 6 kvisc / m, and an explicit damping step overshoots beyond a rate
// of 2 / dt: kvisc 2 at the samples' dt 0.1 and node mass 0.51 blew up in
// the first steps). Where dt times a node's summed kvisc over m stays within
// 1.5 (75 % of that limit) the pass keeps the explicit force
// (Model::explicit_viscosity_limit); beyond it, this solve. A red cell's membrane viscosity
// (Hochmuth, Worthy, Evans, Biophys. J. 26, 101, 1979: 0.6-0.8 uN s/m, kvisc ~ 1400 in um, us,
// 1e-15 kg) is three orders beyond. So the velocities are advanced by
// backward Euler over the time step, which damps every mode and overshoots
// none at any kvisc:
//
//   (M/dt + C) v_new = (M/dt) v + F,   F_visc = -C v_new,
//
// C the dashpots' matrix (sum over edges of kvisc e e^T on the pair's
// velocity difference), v the velocities the forces are computed with (the
// integrator's half-step velocities), M the node masses and F the forces the
// dashpots work against in this step: in the time step every other force
// of the step, solved last (Model::add_deferred_viscosity: membrane,
// contacts, walls, thermostat, coupling, external), in analysis the
// membrane's elastic forces and the external ones (semi-implicit Euler with
// implicit damping, as in cloth simulation: D. Baraff, A. Witkin, SIGGRAPH
// 1998). Without F in it the scheme would balance the elastic forces by M/dt
// instead of C wherever dt C/m >> 1: a stretched cell then relaxed twice as
// fast as eta_m/mu at dt 50 us, and faster at longer steps. A contact's push
// left out of F (as it was until 29 Nov 2026, the contacts being computed
// after the membranes) reached the node in full while the dashpots, solved
// without it, held its neighbours: at kvisc 10 and 51 in a dense tube (D 10,
// H_D 0.45, Ca 10) membranes crossed at strain 14 and 13; solved last, the
// same runs went through 30 and 40 strain units. Applied as the step's
// force, F_visc moves v + dt F/m to v_new over one step; at small
// dt kvisc / m it is the explicit force -C v to first order. It is taken as
// -C v_new, the dashpots' force at the new velocities: opposite forces along
// each edge, so momentum and angular momentum are kept exactly even where
// the solve stops short. The system is
// symmetric positive definite (M > 0, C >= 0), solved cell by cell by
// conjugate gradients with the nodes' 3x3 diagonal blocks as preconditioner,
// started from v + dt F/m, to a relative residual of 1e-6 (the viscous force
// to about that precision).
#pragma once

#include "interactions/membrane/lanes.hpp"

#include <vector>

namespace pyoif::membrane {

struct ViscosityParams {
  double kvisc = 0.0;
};

/** Explicit: the coefficient c of the force c (B - A) on A; dv = v_B - v_A,
 *  e = B - A, inv_l2 = 1 / |e|^2 (the edge pass, where dt kvisc / m is
 *  small enough). */
template <class T>
inline T viscosity_coefficient(const ViscosityParams& p, const T (&e)[3], const T (&dv)[3],
                               T inv_l2) {
  return p.kvisc * (dv[0] * e[0] + dv[1] * e[1] + dv[2] * e[2]) * inv_l2;
}

/** Scratch of the viscous solve, per node of the largest cell. */
struct ViscousSolver {
  /** Relative residual at which the solve stops, and the most iterations
   *  (reached only where the system is badly conditioned; the iterate is
   *  then still a damping, just less accurate). */
  double tolerance = 1e-6;
  int max_iterations = 500;
  /** Iterations of the last solve (diagnostics, tests). */
  int last_iterations = 0;

  /** The viscous forces of one cell added to f (3 doubles per node).
   *  x, v: the cell's node positions (unfolded: edge vectors are plain
   *  differences) and velocities; mass per node; edges b[k]-c[k] with
   *  params[k]; load: the forces F above (3 per node); dt > 0: implicit
   *  as above; dt == 0: the explicit force -C v (analysis: the dashpots'
   *  force at these velocities). */
  void add_forces(int n_nodes, int n_edges, const int* b, const int* c,
                  const ViscosityParams* params, const double* x, const double* v,
                  const double* mass, const double* load, double dt, double* f);

private:
  std::vector<double> m_unit, m_weight;                                    // per edge: e (3), kvisc
  std::vector<double> m_block;                                             // per node: 3x3 inverse
  std::vector<double> m_solution, m_residual, m_direction, m_z, m_product; // per node (3)
  /** product = (M/dt + C) p (dt > 0) or C p (dt == 0). */
  void apply(int n_nodes, int n_edges, const int* b, const int* c, const double* mass, double dt,
             const double* p, double* product) const;
};

} // namespace pyoif::membrane
