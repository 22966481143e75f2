// OifLocalForces: the OIF membrane moduli that live on a pair of triangles
// sharing an edge, computed in one pass (the paper's angle loop): stretching of
// the shared edge (eq. 3, neo-Hookean ks and linear kslin), bending (eq. 4),
// local area of both triangles (eq. 5) and membrane viscosity on the edge.
//
// Particle order of a bond (ESPResSo/PyOIF's): for PyOIF's Angle(A, B, C, D)
// with shared edge BC, the bond is (B, A, C, D) -- B owns it, A, C, D are the
// partners. Per-bond reference values (r0, phi0, A01, A02): relaxed length of
// BC, relaxed angle (PyOIF's angle_btw_triangles(A, B, C, D)), relaxed areas
// of triangles ABC and BCD. So one interaction serves every bond of a cell type.
//
// Counting: each edge belongs to exactly one triangle pair, so stretching and
// viscosity count every edge once. Each triangle belongs to three pairs (one
// per edge), so its local area force and energy are weighted 1/3 per pair
// (ESPResSo's convention): on a closed mesh every triangle gets eq. 5 once.
#pragma once

#include "interactions/bonded/bond_loop.hpp"
#include "interactions/bonded/oif_area.hpp"
#include "interactions/bonded/oif_bending.hpp"
#include "interactions/bonded/oif_edge_terms.hpp"

#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace pyoif {

struct OifLocalForces {
  static constexpr const char* name = "OifLocalForces";
  static constexpr int n_particles = 4;
  static constexpr int per_bond_stride = 4; ///< r0, phi0, A01, A02
  double ks = 0.0, kslin = 0.0, kb = 0.0, kal = 0.0, kvisc = 0.0;

  /** Analysis terms: "stretching" (ks and kslin), "bending", "local_area",
   *  "visc" (no energy). */
  static std::vector<std::string> terms() {
    return {"stretching", "bending", "local_area", "visc"};
  }
  static std::vector<std::string> energy_terms() { return {"stretching", "bending", "local_area"}; }
  /** A copy with every modulus but `term`'s set to zero. */
  OifLocalForces only(const std::string& term) const {
    OifLocalForces o;
    if (term == "stretching") {
      o.ks = ks;
      o.kslin = kslin;
    } else if (term == "bending")
      o.kb = kb;
    else if (term == "local_area")
      o.kal = kal;
    else if (term == "visc")
      o.kvisc = kvisc;
    else
      throw InputError("term: OifLocalForces has the terms 'stretching', 'bending', "
                       "'local_area' and 'visc', got '" +
                       term + "'");
    return o;
  }

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

  bool forces(const BondInput<4>& in, std::array<Vec3, 4>& f, double& energy) const {
    // in.x = (B, A, C, D); the edge is B-C, the wings A and D
    const Vec3 &b = in.x[0], &a = in.x[1], &c = in.x[2], &d = in.x[3];
    const double* ref = in.reference;
    const double r0 = ref[0], phi0 = ref[1], area1_0 = ref[2], area2_0 = ref[3];
    for (auto& fk : f)
      fk.setZero();
    energy = 0.0;
    // a zero relaxed length or area cannot be a reference (degenerate mesh)
    if (!(r0 > 0.0) || !(area1_0 > 0.0) || !(area2_0 > 0.0) || !((c - b).squaredNorm() > 0.0))
      return false;
    if (ks != 0.0 || kslin != 0.0 || kvisc != 0.0) {
      oif::EdgeResult edge;
      if (ks != 0.0) {
        const auto r = oif::stretching_neo_hookean(b, c, r0, ks, in.want_energy);
        edge.force_a += r.force_a;
        edge.energy += r.energy;
      }
      if (kslin != 0.0) {
        const auto r = oif::stretching_linear(b, c, r0, kslin);
        edge.force_a += r.force_a;
        edge.energy += r.energy;
      }
      if (kvisc != 0.0)
        edge.force_a += oif::edge_viscosity(b, c, in.v[0], in.v[2], kvisc).force_a;
      f[0] += edge.force_a;
      f[2] -= edge.force_a;
      energy += edge.energy;
    }
    if (kb != 0.0) {
      std::array<Vec3, 4> fb; // on (a, b, c, d)
      double eb;
      if (!oif::bending(a, b, c, d, phi0, kb, fb, eb))
        return false;
      f[1] += fb[0];
      f[0] += fb[1];
      f[2] += fb[2];
      f[3] += fb[3];
      energy += eb;
    }
    if (kal != 0.0) {
      const double s1 = oif::triangle_area(a, b, c), s2 = oif::triangle_area(b, c, d);
      if (!(s1 > 0.0) || !(s2 > 0.0))
        return false;
      oif::add_centroid_allocated(a, b, c, oif::local_area_coefficient(s1, area1_0, kal) / 3.0,
                                  f[1], f[0], f[2]);
      oif::add_centroid_allocated(b, c, d, oif::local_area_coefficient(s2, area2_0, kal) / 3.0,
                                  f[0], f[2], f[3]);
      energy +=
          (oif::local_area_energy(s1, area1_0, kal) + oif::local_area_energy(s2, area2_0, kal)) /
          3.0;
    }
    return f[0].allFinite() && f[1].allFinite() && f[2].allFinite() && f[3].allFinite();
  }
};

} // namespace pyoif
