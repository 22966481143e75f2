// Membrane viscosity on an edge AB: F(A) = kvisc ((v_B - v_A).e) e, e the
// unit edge vector, F(B) = -F(A): it damps the relative velocity of the two
// nodes along the edge (ESPResSo's OIF "variant B"); dissipative, no energy.
#pragma once

#include "interactions/membrane/lanes.hpp"

namespace pyoif::membrane {

struct ViscosityParams {
  double kvisc = 0.0;
};

/** The coefficient c of the force c (B - A) on A; dv = v_B - v_A, e = B - A,
 *  inv_l2 = 1 / |e|^2. */
template <class T>
inline T viscosity_coefficient(const ViscosityParams& p, const T (&e)[3], const T (&dv)[3],
                               T inv_l2) {
  return p.kvisc * (dv[0] * e[0] + dv[1] * e[1] + dv[2] * e[2]) * inv_l2;
}

} // namespace pyoif::membrane
