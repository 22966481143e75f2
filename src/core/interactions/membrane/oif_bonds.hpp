// The OIF membrane bonds of the ESPResSo/PyOIF API: descriptions of a
// membrane, compiled into the membrane component (membrane_model.hpp), not
// evaluated bond by bond. They are registered and bonded like any bond
// (system.bonded_inter.add, part.add_bond, part.add_bonds), so that PyOIF
// scripts port unchanged and bonds may be added by hand.
//
//  - OifLocalForces, a 4-particle bond per pair of triangles sharing an edge:
//    stretching of the edge (eq. 3), bending of the pair (eq. 4), local area
//    of both triangles (eq. 5, a third each) and membrane viscosity. Particle
//    order (ESPResSo/PyOIF's): for PyOIF's Angle(A, B, C, D) with shared edge
//    BC the bond is (B, A, C, D). Per-bond reference values (r0, phi0, A01,
//    A02): relaxed |BC|, relaxed angle (PyOIF's angle_btw_triangles(A, B, C,
//    D)), relaxed areas of ABC and BCD; one interaction serves a cell type.
//  - OifGlobalForces, a 3-particle bond per triangle: global area (eq. 6) and
//    volume (eq. 7) of the cell (the mol_id of the triangle's first particle).
//  - OifOutDirection, a 3-particle bond per triangle: the nodes' outward
//    normals for membrane collision (eq. 9).
#pragma once

#include "utils/errors.hpp"

#include <cmath>
#include <string>

namespace pyoif {

struct OifLocalForces {
  static constexpr const char* name = "OifLocalForces";
  static constexpr int n_particles = 4;
  static constexpr int per_bond_stride = 4; ///< r0, phi0, A01, A02
  static constexpr bool membrane = true;    ///< compiled into the membrane component
  double ks = 0.0, kslin = 0.0, kb = 0.0, kal = 0.0, kvisc = 0.0;

  /** Checks one bond's reference values when bonds are added (InputError). */
  static void check_reference(const double* ref, std::size_t bond) {
    static const char* names[4] = {"r0", "phi0", "A01", "A02"};
    for (int k = 0; k < 4; ++k) {
      const bool ok = std::isfinite(ref[k]) &&
                      (k == 1 ? (ref[k] >= -2.0 * M_PI && ref[k] <= 4.0 * M_PI) : ref[k] > 0.0);
      if (!ok)
        throw InputError(
            std::string("OifLocalForces per-bond value '") + names[k] + "' of bond " +
            std::to_string(bond) + " must be " +
            (k == 1 ? "in [-2 pi, 4 pi] (it is taken modulo 2 pi)" : "a finite number > 0") +
            ", got " + std::to_string(ref[k]));
    }
  }
};

struct OifGlobalForces {
  static constexpr const char* name = "OifGlobalForces";
  static constexpr int n_particles = 3;
  static constexpr int per_bond_stride = 0;
  static constexpr bool membrane = true;
  double A0_g = 0.0, ka_g = 0.0, V0 = 0.0, kv = 0.0;
};

struct OifOutDirection {
  static constexpr const char* name = "OifOutDirection";
  static constexpr int n_particles = 3;
  static constexpr int per_bond_stride = 0;
  static constexpr bool membrane = true;
};

} // namespace pyoif
