#include "interactions/bonded/oif_fast_path.hpp"

#include "interactions/bonded/oif_edge_terms.hpp"

#include <Eigen/Geometry>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <unordered_map>
#include <unordered_set>

// The per-cell arrays of the triangle passes are disjoint slices of one
// buffer: tell the compiler their iterations are independent (vectorise).
#if defined(__clang__)
#define PYOIF_INDEPENDENT_ITERATIONS _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define PYOIF_INDEPENDENT_ITERATIONS _Pragma("GCC ivdep")
#else
#define PYOIF_INDEPENDENT_ITERATIONS
#endif

namespace pyoif::oif {

namespace {

constexpr int kind_local = 0, kind_global = 1, kind_out_direction = 2;

/** Local-area force (eq. 5) of the triangle (p0, p1, p2), allocated through
 *  its centroid T as in oif_area.hpp: vertex i gets scale (T - p_i), scale =
 *  kal (weight A - A0) / sum_i |T - p_i|^2; weight 0 for a triangle another
 *  bond owns. Vertices relative to the bond's owner (one of them is zero). */
__attribute__((always_inline)) inline void
centroid_area_force(const double (&p0)[3], const double (&p1)[3], const double (&p2)[3],
                    double area, double weight, double area0, double kal, double* const (&f0)[3],
                    double* const (&f1)[3], double* const (&f2)[3]) {
  double m0[3], m1[3], m2[3], norm2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double t = (p0[d] + p1[d] + p2[d]) / 3.0;
    m0[d] = t - p0[d];
    m1[d] = t - p1[d];
    m2[d] = t - p2[d];
  }
  for (int d = 0; d < 3; ++d)
    norm2 += m0[d] * m0[d] + m1[d] * m1[d] + m2[d] * m2[d];
  const double scale = kal * (weight * area - area0) / norm2;
  for (int d = 0; d < 3; ++d) {
    *f0[d] += scale * m0[d];
    *f1[d] += scale * m1[d];
    *f2[d] += scale * m2[d];
  }
}

/** Vectors of doubles (GCC/Clang vector extension: Lanes, BatchLanes):
 *  their comparisons give masks (-1 where true). */
template <class V> using MaskOf = decltype(V{} > V{});
template <class V> constexpr int lanes_of = static_cast<int>(sizeof(V) / sizeof(double));
template <class M> inline bool any_lane(M m) {
  long long any = 0;
  for (int j = 0; j < lanes_of<M>; ++j)
    any |= m[j];
  return any != 0;
}
/** x in every lane (T = double: x itself). */
template <class V> inline V splat(double x) {
  return V{} + x;
}
/** Lane-wise square root, correctly rounded as std::sqrt. */
template <class V> inline V sqrt_lanes(V a) {
#if defined(__AVX__)
  if constexpr (sizeof(V) == 32)
    return reinterpret_cast<V>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(a)));
#endif
  for (int j = 0; j < lanes_of<V>; ++j)
    a[j] = std::sqrt(a[j]);
  return a;
}

/** atan(t) for |t| <= 1/4 (dihedral deviations below 14 degrees, most of a
 *  membrane's): t P(t^2), P the Chebyshev economisation on [0, 1/16] of the
 *  Taylor series of atan(sqrt s)/sqrt s, derived in exact rational arithmetic
 *  (dropped terms < 5e-18; largest relative error against libm's atan on 2e5
 *  random points 2.2e-16). Branch-free, so a block of bonds vectorises; T:
 *  double or a vector of them. */
template <class T> inline T atan_small(T t) {
  const T s = t * t;
  T pz = splat<T>(0.04599761088928747);
  pz = pz * s - 0.06523656687585018;
  pz = pz * s + 0.07683492919828101;
  pz = pz * s - 0.09090589248444612;
  pz = pz * s + 0.11111104259672454;
  pz = pz * s - 0.1428571420303533;
  pz = pz * s + 0.19999999999499324;
  pz = pz * s - 0.33333333333332166;
  pz = pz * s + 1.0;
  return t * pz;
}

/** The minimum image of box_geometry.hpp on n separations along one periodic
 *  axis of length L, as a loop over an array that vectorises (no branch per
 *  vector component in the gather): where |d| > L/2, d - L n with n the
 *  nearest integer to d/L (as BoxGeometry::minimum_image; only a separation
 *  of exactly a half-integer number of boxes, ambiguous anyway, can round the
 *  other way). */
inline void minimum_image_axis(double* d, int n, double L) {
  const double half = 0.5 * L, inv_L = 1.0 / L;
  for (int k = 0; k < n; ++k) {
    const double x = d[k];
    d[k] = std::abs(x) > half ? x - L * std::nearbyint(x * inv_L) : x;
  }
}

/** Whether any of n separations along one periodic axis of length L is
 *  longer than L/2 (then minimum_image_axis is needed). */
inline bool beyond_half(const double* d, int n, double L) {
  const double half = 0.5 * L;
  int beyond = 0;
  for (int k = 0; k < n; ++k)
    beyond |= std::abs(d[k]) > half;
  return beyond;
}

constexpr int kBlock = 64; ///< bonds or triangles per block (arrays stay in L1)

/** The x, y, z lanes of four vectors into component arrays, x[0..3] etc.: a
 *  4 x 4 transpose in registers (seven shuffles, three stores) instead of
 *  twelve lane extractions, each a store. The gathers of the membrane passes
 *  turn vectors into the component arrays that their arithmetic vectorises
 *  over; done lane by lane they were bound by the stores. */
inline void store_components(const Lanes& v0, const Lanes& v1, const Lanes& v2, const Lanes& v3,
                             double* x, double* y, double* z) {
#if defined(__clang__)
  const Lanes t0 = __builtin_shufflevector(v0, v1, 0, 4, 2, 6);
  const Lanes t1 = __builtin_shufflevector(v0, v1, 1, 5, 3, 7);
  const Lanes t2 = __builtin_shufflevector(v2, v3, 0, 4, 2, 6);
  const Lanes t3 = __builtin_shufflevector(v2, v3, 1, 5, 3, 7);
  const Lanes cx = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  const Lanes cy = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  const Lanes cz = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
#else
  using Mask = long long __attribute__((vector_size(32)));
  const Lanes t0 = __builtin_shuffle(v0, v1, Mask{0, 4, 2, 6}); // x0 x1 z0 z1
  const Lanes t1 = __builtin_shuffle(v0, v1, Mask{1, 5, 3, 7}); // y0 y1 -  -
  const Lanes t2 = __builtin_shuffle(v2, v3, Mask{0, 4, 2, 6}); // x2 x3 z2 z3
  const Lanes t3 = __builtin_shuffle(v2, v3, Mask{1, 5, 3, 7}); // y2 y3 -  -
  const Lanes cx = __builtin_shuffle(t0, t2, Mask{0, 1, 4, 5});
  const Lanes cy = __builtin_shuffle(t1, t3, Mask{0, 1, 4, 5});
  const Lanes cz = __builtin_shuffle(t0, t2, Mask{2, 3, 6, 7});
#endif
  std::memcpy(x, &cx, sizeof cx);
  std::memcpy(y, &cy, sizeof cy);
  std::memcpy(z, &cz, sizeof cz);
}

/** Per-block arrays of the edge pass (structure of arrays). */
struct EdgeBlock {
  double e[3][kBlock], u[3][kBlock], w[3][kBlock], dv[3][kBlock];
  double l[kBlock], inv_l2[kBlock], coefficient[kBlock];
  double n1[3][kBlock], n2[3][kBlock], n1_2[kBlock], n2_2[kBlock];
  double sine[kBlock], cosine[kBlock], dphi[kBlock], inv_n1n2[kBlock];
  double fa[3][kBlock], fb[3][kBlock], fc[3][kBlock], fd[3][kBlock];
};

/** A cell's area (sum of its triangles' areas) and volume (eqs. 6, 7: sum of
 *  a.N / 6) from per-triangle values: four partial sums over k mod 4, so
 *  that there is no loop-carried chain of additions, the last n mod 4 terms
 *  into the first. Fed in order, whole, block by block (blocks starting at
 *  multiples of 4) or one triangle at a time, the sums are the same bit for
 *  bit. T: double, or Lanes for four cells at once (one per lane). */
template <class T = double> class AreaVolumeSums {
public:
  explicit AreaVolumeSums(int n) : m_n4(n - n % 4) {}
  /** Triangles first .. first + nb - 1: area[k], vol[k] for first + k. */
  void add(const T* area, const T* vol, int first, int nb) {
    const int full = std::max(0, std::min(nb, m_n4 - first));
    for (int k = 0; k < full; k += 4)
      for (int j = 0; j < 4; ++j) {
        m_area[j] += area[k + j];
        m_vol[j] += vol[k + j];
      }
    for (int k = full; k < nb; ++k) {
      m_area[0] += area[k];
      m_vol[0] += vol[k];
    }
  }
  /** Triangle q alone (q = 0, 1, ... in order). */
  void add_one(int q, const T& area, const T& vol) {
    const int j = q < m_n4 ? (q & 3) : 0;
    m_area[j] += area;
    m_vol[j] += vol;
  }
  T area() const { return (m_area[0] + m_area[1]) + (m_area[2] + m_area[3]); }
  T volume() const { return ((m_vol[0] + m_vol[1]) + (m_vol[2] + m_vol[3])) / 6.0; }

private:
  int m_n4;
  T m_area[4] = {}, m_vol[4] = {};
};

/** Lane helpers: the edge arithmetic below serves one edge (T = double, in
 *  a loop that the compiler vectorises over a block of edges) and one edge
 *  of four cells (T = BatchLanes). */
template <class T> inline T sqrt_of(T x) {
  if constexpr (std::is_same_v<T, double>)
    return std::sqrt(x);
  else
    return sqrt_lanes(x);
}
template <class T> inline auto not_positive(T x) {
  if constexpr (std::is_same_v<T, double>)
    return !(x > 0.0);
  else
    return ~(x > T{});
}
template <class T, class M> inline T select(M m, T a, T b) {
  return m ? a : b;
}
/** Whether the polynomial arctangent covers a deviation (|tan| <= 1/4). */
template <class T> inline auto is_small_angle(T sine, T cosine) {
  if constexpr (std::is_same_v<T, double>) {
    return cosine > 0.0 && std::abs(sine) <= 0.25 * cosine;
  } else {
    const T zero{}, abs_sine = sine < zero ? -sine : sine;
    return (cosine > zero) & (abs_sine <= 0.25 * cosine);
  }
}

/** One edge's terms (edge_terms). */
template <class T> struct EdgeTerms {
  using Mask = decltype(not_positive(T{}));
  T l, inv_l2, coefficient;       ///< length, 1 / l^2, stretching (+ viscosity) / l
  T n1[3], n2[3], n1_2, n2_2;     ///< wings: the triangles' normals, |n|^2
  T sine, cosine, dphi, inv_n1n2; ///< bend: the deviation, 1 / (|n1|^2 |n2|^2)
  Mask bad;                       ///< zero-length edge or degenerate wing
  Mask small;                     ///< bend: dphi from the polynomial (else atan2)
};

/** The arithmetic of one edge (B, C) with wings A, D up to its force factors:
 *  e = c - b, u = a - b, w = d - b, dv = v_c - v_b (visc). The wings' normals
 *  n1 = u x e (triangle ABC) and n2 = e x w (BCD), |n| = twice the area; the
 *  dihedral angle of oif_bending.hpp, psi = atan2((n1 x n2).e / l, n1.n2)
 *  with (n1 x n2).e / l = l n1.w, phi - phi0 = -(psi - psi0), psi0 = pi -
 *  phi0, taken as one angle (sine and cosine rotated by psi0); the
 *  neo-Hookean kappa(lambda) = sqrt(lambda) (lambda^3 + 1) / (lambda^4 + 1)
 *  (oif_edge_terms.hpp). The four quotients (1 / l^2, kappa's denominator,
 *  the angle's tangent, 1 / (|n1|^2 |n2|^2)) share one division: the
 *  divider, not the arithmetic, bounds the loops. dphi is that of the
 *  polynomial (zero where !small: the caller takes atan2 there). */
template <bool neo, bool visc, bool wings, bool bend, class T>
__attribute__((always_inline)) inline EdgeTerms<T>
edge_terms(const T (&e)[3], const T (&u)[3], const T (&w)[3], const T (&dv)[3], double r0,
           double inv_r0, double cos_psi0, double sin_psi0, double ks, double kslin, double kvisc) {
  static_assert(!bend || wings, "bending needs the wing triangles");
  const T zero{}, one = zero + 1.0;
  EdgeTerms<T> t;
  const T ex = e[0], ey = e[1], ez = e[2];
  const T l2 = ex * ex + ey * ey + ez * ez;
  t.bad = not_positive(l2);
  const T l = sqrt_of(l2);
  t.l = l;
  T n1x = zero, n1y = zero, n1z = zero, n2x = zero, n2y = zero, n2z = zero;
  T n1_2 = one, n2_2 = one;
  if constexpr (wings) {
    const T ux = u[0], uy = u[1], uz = u[2], wx = w[0], wy = w[1], wz = w[2];
    n1x = uy * ez - uz * ey, n1y = uz * ex - ux * ez, n1z = ux * ey - uy * ex;
    n2x = ey * wz - ez * wy, n2y = ez * wx - ex * wz, n2z = ex * wy - ey * wx;
    n1_2 = n1x * n1x + n1y * n1y + n1z * n1z;
    n2_2 = n2x * n2x + n2y * n2y + n2z * n2z;
    t.bad = t.bad | not_positive(n1_2) | not_positive(n2_2); // degenerate triangle
    t.n1[0] = n1x, t.n1[1] = n1y, t.n1[2] = n1z;
    t.n2[0] = n2x, t.n2[1] = n2y, t.n2[2] = n2z;
    t.n1_2 = n1_2;
    t.n2_2 = n2_2;
  }
  T sine = zero, cosine = one, tangent_denominator = one, n1n2 = one;
  t.small = zero < one;
  if constexpr (bend) {
    const T y = l * (n1x * w[0] + n1y * w[1] + n1z * w[2]);
    const T x = n1x * n2x + n1y * n2y + n1z * n2z;
    sine = y * cos_psi0 - x * sin_psi0;
    cosine = x * cos_psi0 + y * sin_psi0;
    t.small = is_small_angle(sine, cosine);
    tangent_denominator = select(t.small, cosine, one);
    n1n2 = n1_2 * n2_2;
  }
  T lambda = one, lambda2 = one, kappa_denominator = one;
  if constexpr (neo) {
    lambda = l * inv_r0;
    lambda2 = lambda * lambda;
    kappa_denominator = lambda2 * lambda2 + 1.0;
  }
  // one reciprocal for the four quotients
  const T p = l2 * kappa_denominator, q = tangent_denominator * n1n2;
  const T r = 1.0 / (p * q);
  const T inv_l2 = r * kappa_denominator * q;
  t.inv_l2 = inv_l2;
  // stretching (eq. 3) and viscosity: force on b along e, c gets the opposite
  const T stretch = (l - r0) * l * inv_l2; // (l - l0) / l
  T coefficient = kslin * stretch;
  if constexpr (neo)
    coefficient += ks * (sqrt_of(lambda) * (lambda2 * lambda + 1.0) * (r * l2 * q)) * stretch;
  if constexpr (visc)
    coefficient += kvisc * (dv[0] * ex + dv[1] * ey + dv[2] * ez) * inv_l2;
  t.coefficient = coefficient;
  if constexpr (bend) {
    t.dphi = -atan_small(select(t.small, sine * (r * p * n1n2), zero));
    t.inv_n1n2 = r * p * tangent_denominator;
    t.sine = sine;
    t.cosine = cosine;
  }
  return t;
}

/** One triangle's terms of the fused triangle pass (evaluate_cell and
 *  evaluate_batch; T = double or BatchLanes) from its edge vectors e1 = b -
 *  a, e2 = c - a and its first vertex ra relative to the cell's reference
 *  point: N = e1 x e2, the area S = |N|/2, the volume term ra.N (eqs. 6, 7),
 *  and the two centroid allocations (oif_area.hpp), which share their
 *  direction: vertex i gets (T - p_i) / sum_j |T - p_j|^2 times kal (weight
 *  S - area0) for the local area (eq. 5; coef) and kag (S_cell - S_cell0) /
 *  S_cell0 S for the global area (eq. 6; g, the cell's factor applied once
 *  the cell's area is known). */
template <class T> struct TriangleTerms { T nx, ny, nz, area, volume, g, coef; };
template <class T>
__attribute__((always_inline)) inline TriangleTerms<T>
triangle_terms(const T (&e1)[3], const T (&e2)[3], const T (&ra)[3], double weight, double area0,
               double kal) {
  constexpr double third = 1.0 / 3.0;
  TriangleTerms<T> t;
  t.nx = e1[1] * e2[2] - e1[2] * e2[1];
  t.ny = e1[2] * e2[0] - e1[0] * e2[2];
  t.nz = e1[0] * e2[1] - e1[1] * e2[0];
  t.area = 0.5 * sqrt_of(t.nx * t.nx + t.ny * t.ny + t.nz * t.nz);
  t.volume = ra[0] * t.nx + ra[1] * t.ny + ra[2] * t.nz;
  // centroid relative to the first vertex: T - p0 = (e1 + e2) / 3
  const T m0x = (e1[0] + e2[0]) * third, m0y = (e1[1] + e2[1]) * third,
          m0z = (e1[2] + e2[2]) * third;
  const T m1x = m0x - e1[0], m1y = m0y - e1[1], m1z = m0z - e1[2];
  const T m2x = m0x - e2[0], m2y = m0y - e2[1], m2z = m0z - e2[2];
  const T inv_norm2 = 1.0 / (m0x * m0x + m0y * m0y + m0z * m0z + m1x * m1x + m1y * m1y + m1z * m1z +
                             m2x * m2x + m2y * m2y + m2z * m2z);
  t.g = t.area * inv_norm2;
  t.coef = kal * (weight * t.area - area0) * inv_norm2;
  return t;
}

/** Bending (eq. 4), F = -kb dphi grad phi (oif_bending.hpp): on the wings
 *  A and D kb dphi l n / |n|^2 (fa = ca n1, fd = cd n2), the edge ends B and
 *  C split by the wings' foot points ta, td along the edge. */
template <class T> struct BendingFactors { T ca, cd, ta, td; };
template <class T>
__attribute__((always_inline)) inline BendingFactors<T>
bending_factors(double kb, T dphi, T l, T inv_n1n2, T n1_2, T n2_2, T inv_l2, const T (&e)[3],
                const T (&u)[3], const T (&w)[3]) {
  const T c = kb * dphi * l * inv_n1n2;
  return {c * n2_2, c * n1_2, (u[0] * e[0] + u[1] * e[1] + u[2] * e[2]) * inv_l2,
          (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) * inv_l2};
}
/** Component d of an edge's forces on A, B, C, D: stretching and viscosity
 *  fe on B and -fe on C, the bending as above (n1, n2: the wings' normals'
 *  component d). */
template <class T>
__attribute__((always_inline)) inline void
edge_end_forces(T fe, T n1, T n2, const BendingFactors<T>& b, T& fa, T& fb, T& fc, T& fd) {
  fa = b.ca * n1;
  fd = b.cd * n2;
  fb = fe - ((1.0 - b.ta) * fa + (1.0 - b.td) * fd);
  fc = -fe - (b.ta * fa + b.td * fd);
}

/** -atan2(sine, cosine) in (-pi, pi], as the generic bending: the
 *  deviations that the polynomial (atan_small) does not cover. */
inline double large_deviation(double sine, double cosine) {
  const double dphi = -std::atan2(sine, cosine);
  return dphi <= -M_PI ? dphi + 2.0 * M_PI : dphi;
}

/** The edge pass of edge_block_forces for one combination of terms known
 *  at compile time: neo (ks != 0), visc (kvisc != 0, dv set), wings (u, w
 *  set; n1, n2 and their squared lengths computed), bend (kb != 0; needs
 *  wings). Two loops over the block (vectorised): the first computes per
 *  edge everything up to the bending angle, the second the forces; between
 *  them the edges whose angle left the polynomial's range get the library's
 *  arctangent. The four quotients of the first loop (1 / l^2, the
 *  neo-Hookean kappa's denominator, the angle's tangent, 1 / (|n1|^2
 *  |n2|^2)) share one division: the divider, not the arithmetic, bounds
 *  this loop. */
template <bool neo, bool visc, bool wings, bool bend>
bool edge_block_terms(EdgeBlock& blk, int nb, const double* r0, const double* inv_r0,
                      const double* cos_psi0, const double* sin_psi0, const OifLocalForces& ia) {
  static_assert(!bend || wings, "bending needs the wing triangles");
  const double ks = ia.ks, kslin = ia.kslin, kvisc = ia.kvisc, kb = ia.kb;
  int bad = 0, slow = 0;
  PYOIF_INDEPENDENT_ITERATIONS
  for (int k = 0; k < nb; ++k) {
    const double e[3] = {blk.e[0][k], blk.e[1][k], blk.e[2][k]};
    double u[3] = {0.0, 0.0, 0.0}, w[3] = {0.0, 0.0, 0.0}, dv[3] = {0.0, 0.0, 0.0};
    for (int d = 0; d < 3; ++d) { // only what the gather set
      if constexpr (wings) {
        u[d] = blk.u[d][k];
        w[d] = blk.w[d][k];
      }
      if constexpr (visc)
        dv[d] = blk.dv[d][k];
    }
    const EdgeTerms<double> t = edge_terms<neo, visc, wings, bend>(
        e, u, w, dv, r0[k], inv_r0[k], cos_psi0[k], sin_psi0[k], ks, kslin, kvisc);
    bad |= t.bad;
    blk.l[k] = t.l;
    if constexpr (wings) {
      for (int d = 0; d < 3; ++d) {
        blk.n1[d][k] = t.n1[d];
        blk.n2[d][k] = t.n2[d];
      }
      blk.n1_2[k] = t.n1_2;
      blk.n2_2[k] = t.n2_2;
    }
    blk.inv_l2[k] = t.inv_l2;
    blk.coefficient[k] = t.coefficient;
    if constexpr (bend) {
      slow |= !t.small;
      blk.dphi[k] = t.dphi;
      blk.inv_n1n2[k] = t.inv_n1n2;
      blk.sine[k] = t.sine;
      blk.cosine[k] = t.cosine;
    }
  }
  if (bad)
    return false;
  if constexpr (bend)
    if (slow) // deviations beyond atan(1/4): the library's arctangent
      for (int k = 0; k < nb; ++k) {
        const double sine = blk.sine[k], cosine = blk.cosine[k];
        if (is_small_angle(sine, cosine))
          continue;
        blk.dphi[k] = large_deviation(sine, cosine);
      }
  // F = -kb dphi grad phi: on the wings kb dphi l n / |n|^2, the edge ends
  // split by the wings' foot points ta, td (oif_bending.hpp)
  PYOIF_INDEPENDENT_ITERATIONS
  for (int k = 0; k < nb; ++k) {
    if constexpr (bend) {
      const double e[3] = {blk.e[0][k], blk.e[1][k], blk.e[2][k]};
      const double u[3] = {blk.u[0][k], blk.u[1][k], blk.u[2][k]};
      const double w[3] = {blk.w[0][k], blk.w[1][k], blk.w[2][k]};
      const BendingFactors<double> b =
          bending_factors(kb, blk.dphi[k], blk.l[k], blk.inv_n1n2[k], blk.n1_2[k], blk.n2_2[k],
                          blk.inv_l2[k], e, u, w);
      for (int d = 0; d < 3; ++d)
        edge_end_forces(blk.coefficient[k] * e[d], blk.n1[d][k], blk.n2[d][k], b, blk.fa[d][k],
                        blk.fb[d][k], blk.fc[d][k], blk.fd[d][k]);
    } else {
      for (int d = 0; d < 3; ++d) {
        const double fe = blk.coefficient[k] * blk.e[d][k];
        blk.fb[d][k] = fe;
        blk.fc[d][k] = -fe;
        blk.fa[d][k] = 0.0;
        blk.fd[d][k] = 0.0;
      }
    }
  }
  return true;
}

/** Stretching (eq. 3), membrane viscosity and bending (eq. 4) of the nb
 *  edges whose separations (e, and u, w with wings, dv with kvisc) are in
 *  blk: sets the forces fa..fd (fa, fd zero without wings) and, with wings,
 *  the wing normals n1, n2 and their squared lengths. False on a zero-length
 *  edge or (wings) a degenerate wing triangle: the generic loop must speak. */
bool edge_block_forces(EdgeBlock& blk, int nb, const double* r0, const double* inv_r0,
                       const double* cos_psi0, const double* sin_psi0, const OifLocalForces& ia,
                       bool wings) {
  const bool neo = ia.ks != 0.0, visc = ia.kvisc != 0.0, bend = ia.kb != 0.0 && wings;
  // one instantiation per combination, chosen outside the edge loops
  auto with = [&](auto neo_, auto visc_, auto wings_, auto bend_) {
    return edge_block_terms<decltype(neo_)::value, decltype(visc_)::value, decltype(wings_)::value,
                            decltype(bend_)::value>(blk, nb, r0, inv_r0, cos_psi0, sin_psi0, ia);
  };
  using yes = std::true_type;
  using no = std::false_type;
  auto by_wings = [&](auto neo_, auto visc_) {
    if (bend)
      return with(neo_, visc_, yes{}, yes{});
    return wings ? with(neo_, visc_, yes{}, no{}) : with(neo_, visc_, no{}, no{});
  };
  if (neo)
    return visc ? by_wings(yes{}, yes{}) : by_wings(yes{}, no{});
  return visc ? by_wings(no{}, yes{}) : by_wings(no{}, no{});
}

/** A cell's factors of the global forces, from its area and volume: the
 *  global area force (eq. 6) is kag (S_cell - S_cell0) / S_cell0 times the
 *  triangles' g, the volume force (eq. 7) -kv (|V| - V0) / V0 s N / 6 on each
 *  vertex (volume = that factor times the node's sum of N), s the volume's
 *  sign (outward normals for either orientation). */
struct CellFactors {
  double area, volume, sign;
  CellFactors(double cell_area, double cell_volume, const OifGlobalForces& ia) {
    area = ia.ka_g != 0.0 ? ia.ka_g * (cell_area - ia.A0_g) / ia.A0_g : 0.0;
    sign = cell_volume < 0.0 ? -1.0 : 1.0;
    volume = ia.kv != 0.0 ? -ia.kv * ((sign * cell_volume - ia.V0) / ia.V0) * sign / 6.0 : 0.0;
  }
};

/** The edge pass of edge_block_terms for four cells at once, one per lane
 *  (FusedMembranePlan::evaluate_batch): per edge the same arithmetic
 *  (edge_terms) on vectors of the four cells' values; the node components are
 *  loaded and the forces added as whole vectors. In blocks of kBatchBlock
 *  edges, two loops as edge_block_terms: one edge's chain from the node
 *  loads through the square roots and the division to its force factors is
 *  about 130 cycles long and its whole loop body did not fit the core's
 *  reorder window twice, so one loop ran at the chain's latency; split,
 *  each loop's iterations overlap. Node: NodeLanes. */
constexpr int kBatchBlock = 16;
template <bool neo, bool visc, bool bend, class Node>
bool batch_edge_terms(const Node* x, const Node* v, Node* f, const int* eb, const int* ea,
                      const int* ec, const int* ed, int n_edges, const double* r0,
                      const double* inv_r0, const double* cos_psi0, const double* sin_psi0,
                      const OifLocalForces& ia) {
  const double ks = ia.ks, kslin = ia.kslin, kvisc = ia.kvisc, kb = ia.kb;
  MaskOf<BatchLanes> bad = splat<BatchLanes>(0.0) > splat<BatchLanes>(1.0);
  // per edge of a block: e, the wing normals n1, n2 (bend), the stretching
  // coefficient and the bending factors
  struct alignas(sizeof(BatchLanes)) EdgeLanes {
    BatchLanes e[3], n1[3], n2[3], coefficient;
    BendingFactors<BatchLanes> bending;
  };
  EdgeLanes blk[kBatchBlock];
  for (int first = 0; first < n_edges; first += kBatchBlock) {
    const int nb = std::min(kBatchBlock, n_edges - first);
    for (int i = 0; i < nb; ++i) {
      const int k = first + i;
      EdgeLanes& out = blk[i];
      const Node& xb = x[eb[k]];
      BatchLanes e[3], u[3] = {}, w[3] = {}, dv[3] = {};
      for (int d = 0; d < 3; ++d) {
        e[d] = x[ec[k]].c[d] - xb.c[d];
        if constexpr (bend) { // the wing triangles
          u[d] = x[ea[k]].c[d] - xb.c[d];
          w[d] = x[ed[k]].c[d] - xb.c[d];
        }
        if constexpr (visc)
          dv[d] = v[ec[k]].c[d] - v[eb[k]].c[d];
      }
      const EdgeTerms<BatchLanes> t = edge_terms<neo, visc, bend, bend>(
          e, u, w, dv, r0[k], inv_r0[k], cos_psi0[k], sin_psi0[k], ks, kslin, kvisc);
      bad |= t.bad;
      for (int d = 0; d < 3; ++d)
        out.e[d] = e[d];
      out.coefficient = t.coefficient;
      if constexpr (bend) {
        BatchLanes dphi = t.dphi;
        if (any_lane(~t.small)) // deviations beyond atan(1/4): the library's arctangent
          for (int j = 0; j < lanes_of<BatchLanes>; ++j)
            if (!t.small[j])
              dphi[j] = large_deviation(t.sine[j], t.cosine[j]);
        out.bending = bending_factors(kb, dphi, t.l, t.inv_n1n2, t.n1_2, t.n2_2, t.inv_l2, e, u, w);
        for (int d = 0; d < 3; ++d) {
          out.n1[d] = t.n1[d];
          out.n2[d] = t.n2[d];
        }
      }
    }
    // F = -kb dphi grad phi (see edge_block_terms), added to the nodes
    for (int i = 0; i < nb; ++i) {
      const int k = first + i;
      const EdgeLanes& in = blk[i];
      Node &fb = f[eb[k]], &fc = f[ec[k]];
      if constexpr (bend) {
        Node &fa = f[ea[k]], &fd = f[ed[k]];
        for (int d = 0; d < 3; ++d) {
          BatchLanes fa_, fb_, fc_, fd_;
          edge_end_forces(in.coefficient * in.e[d], in.n1[d], in.n2[d], in.bending, fa_, fb_, fc_,
                          fd_);
          fb.c[d] += fb_;
          fc.c[d] += fc_;
          fa.c[d] += fa_;
          fd.c[d] += fd_;
        }
      } else {
        for (int d = 0; d < 3; ++d) {
          const BatchLanes fe = in.coefficient * in.e[d];
          fb.c[d] += fe;
          fc.c[d] += -fe;
        }
      }
    }
  }
  return !any_lane(bad);
}

/** batch_edge_terms for the terms that are on (one instantiation per
 *  combination, as edge_block_forces; the wings come with bending, as in
 *  evaluate_cell). */
template <class Node>
bool batch_edge_forces(const Node* x, const Node* v, Node* f, const int* eb, const int* ea,
                       const int* ec, const int* ed, int n_edges, const double* r0,
                       const double* inv_r0, const double* cos_psi0, const double* sin_psi0,
                       const OifLocalForces& ia) {
  const bool neo = ia.ks != 0.0, visc = ia.kvisc != 0.0, bend = ia.kb != 0.0;
  auto with = [&](auto neo_, auto visc_, auto bend_) {
    return batch_edge_terms<decltype(neo_)::value, decltype(visc_)::value, decltype(bend_)::value>(
        x, v, f, eb, ea, ec, ed, n_edges, r0, inv_r0, cos_psi0, sin_psi0, ia);
  };
  using yes = std::true_type;
  using no = std::false_type;
  auto by_bend = [&](auto neo_, auto visc_) {
    return bend ? with(neo_, visc_, yes{}) : with(neo_, visc_, no{});
  };
  if (neo)
    return visc ? by_bend(yes{}, yes{}) : by_bend(yes{}, no{});
  return visc ? by_bend(no{}, yes{}) : by_bend(no{}, no{});
}

/** A triangle's key, independent of its orientation: its three slots sorted,
 *  21 bits each (fewer than kMaxTriangleSlots slots). */
constexpr std::size_t kMaxTriangleSlots = std::size_t(1) << 21;
inline std::uint64_t triangle_key(int s0, int s1, int s2) {
  const int lo = std::min({s0, s1, s2}), hi = std::max({s0, s1, s2});
  const int mid = s0 + s1 + s2 - lo - hi;
  return static_cast<std::uint64_t>(lo) | (static_cast<std::uint64_t>(mid) << 21) |
         (static_cast<std::uint64_t>(hi) << 42);
}

/** The slots of a group's particles (index: slot -> local particle index;
 *  bond_slots: the group's ids as slots), grouped in frames: the connected
 *  sets of bonds (cells), each frame's slots contiguous from frame_begin[f],
 *  its first slot the frame's reference node. False when a particle is
 *  missing (the generic loop names it). */
bool slots_by_frame(const BondGroup& group, const ParticleStore& p, std::vector<int>& index,
                    std::vector<int>& frame_begin, std::vector<int>& bond_slots) {
  std::vector<int> slot_of(p.n_local(), -1);
  index.clear();
  bond_slots.resize(group.ids.size());
  for (std::size_t k = 0; k < group.ids.size(); ++k) {
    const int i = p.index(group.ids[k]);
    if (i < 0)
      return false; // the generic loop names the missing particle
    if (slot_of[i] < 0) {
      slot_of[i] = static_cast<int>(index.size());
      index.push_back(i);
    }
    bond_slots[k] = slot_of[i];
  }
  const std::size_t n = index.size();
  // frames: the connected sets of the bonds (union-find over slots), each
  // referred to its first slot
  std::vector<int> parent(n);
  for (std::size_t s = 0; s < n; ++s)
    parent[s] = static_cast<int>(s);
  auto root = [&](int s) {
    while (parent[s] != s)
      s = parent[s] = parent[parent[s]];
    return s;
  };
  const std::size_t stride = group.n_particles > 0 ? group.n_particles : 1;
  for (std::size_t k = 0; k + stride <= bond_slots.size(); k += stride)
    for (std::size_t j = 1; j < stride; ++j) {
      const int r0 = root(bond_slots[k]), r1 = root(bond_slots[k + j]);
      if (r0 != r1)
        parent[std::max(r0, r1)] = std::min(r0, r1); // the root stays the first slot
    }
  // slots renumbered frame by frame (a frame's nodes contiguous, its
  // reference node first; the order within a frame kept): one pass per frame
  std::vector<int> frame_of(n), order(n), new_slot(n);
  for (std::size_t s = 0; s < n; ++s) {
    frame_of[s] = root(static_cast<int>(s));
    order[s] = static_cast<int>(s);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return frame_of[x] < frame_of[y]; });
  std::vector<int> renumbered(n);
  frame_begin.clear();
  for (std::size_t k = 0; k < n; ++k) {
    if (k == 0 || frame_of[order[k]] != frame_of[order[k - 1]])
      frame_begin.push_back(static_cast<int>(k));
    new_slot[order[k]] = static_cast<int>(k);
    renumbered[k] = index[order[k]];
  }
  frame_begin.push_back(static_cast<int>(n));
  index.swap(renumbered);
  for (int& s : bond_slots)
    s = new_slot[s];
  return true;
}

} // namespace

GroupKey::GroupKey(const BondGroup& group, const ParticleStore& p, int kind_)
    : particles_version(p.layout_version), ids(group.ids.data()), per_bond(group.per_bond.data()),
      n_ids(group.ids.size()), n_per_bond(group.per_bond.size()), kind(kind_) {}

bool FastBondPlan::build_slots(const BondGroup& group, const ParticleStore& p,
                               std::vector<int>& bond_slots) {
  if (!slots_by_frame(group, p, m_index, m_frame_begin, bond_slots))
    return false;
  m_x.resize(m_index.size());
  m_v.resize(m_index.size());
  m_f.resize(m_index.size());
  return true;
}

bool FastBondPlan::build_local(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 4 || group.per_bond_stride != 4 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_bonds.resize(n);
  m_ref.resize(n);
  // Unique triangles, keyed by their sorted slots (21 bits each). Each is
  // evaluated once, by one of the bonds that have it (its "owner", in the
  // owner's edge pass, from the vectors gathered there anyway) with weight =
  // (bonds using it) / 3 and area0 = the sum of those bonds' reference areas
  // / 3: the sum of the bonds' kal (S - S0_bond) / 3 of oif_local_forces.hpp
  // is then kal (weight S - area0), applied once. Owners are chosen so that a
  // bond owns at most one triangle (a closed mesh has 2/3 triangle per edge):
  // each bond then evaluates one centroid allocation, not two.
  if (m_index.size() >= kMaxTriangleSlots)
    return false;
  struct Use {
    std::size_t bond;
    int bcd; // 0: triangle ABC, 1: BCD
  };
  std::unordered_map<std::uint64_t, int> triangle_of;
  triangle_of.reserve(n);
  std::vector<std::vector<Use>> uses;
  std::vector<double> area0_sum;
  auto add_triangle = [&](int s0, int s1, int s2, double area0, std::size_t bond, int bcd) {
    auto [it, inserted] =
        triangle_of.try_emplace(triangle_key(s0, s1, s2), static_cast<int>(uses.size()));
    if (inserted) {
      uses.emplace_back();
      area0_sum.push_back(0.0);
    }
    area0_sum[it->second] += area0;
    uses[it->second].push_back({bond, bcd});
  };
  for (std::size_t b = 0; b < n; ++b) {
    const int* s = slots.data() + 4 * b; // (B, A, C, D)
    const double* ref = group.reference(b);
    // the generic loop rejects these as degenerate (and throws): leave it to it
    if (!(ref[0] > 0.0) || !(ref[2] > 0.0) || !(ref[3] > 0.0) || !std::isfinite(ref[1]))
      return false;
    m_bonds[b] = {s[0], s[1], s[2], s[3]};
    m_ref.r0[b] = ref[0];
    m_ref.inv_r0[b] = 1.0 / ref[0];
    // psi0 = pi - phi0: cos psi0 = -cos phi0, sin psi0 = sin phi0
    m_ref.cos_psi0[b] = -std::cos(ref[1]);
    m_ref.sin_psi0[b] = std::sin(ref[1]);
    add_triangle(s[1], s[0], s[2], ref[2], b, 0); // A B C
    add_triangle(s[0], s[2], s[3], ref[3], b, 1); // B C D
  }
  // owners: greedily the first free bond; else move the owner of one of the
  // triangle's bonds to another free bond of its own (one augmenting step);
  // else the triangle is an extra of its first bond
  const std::size_t n_triangles = uses.size();
  std::vector<int> owned(n, -1); // bond -> triangle it evaluates
  std::vector<Use> owner(n_triangles, Use{0, -1});
  std::vector<int> unplaced;
  auto place = [&](int t, const Use& u) {
    owned[u.bond] = t;
    owner[t] = u;
  };
  for (std::size_t t = 0; t < n_triangles; ++t) {
    bool done = false;
    for (const Use& u : uses[t])
      if (!done && owned[u.bond] < 0) {
        place(static_cast<int>(t), u);
        done = true;
      }
    if (!done)
      unplaced.push_back(static_cast<int>(t));
  }
  m_extra.clear();
  for (const int t : unplaced) {
    bool done = false;
    for (const Use& u : uses[t]) {
      const int other = owned[u.bond];
      for (const Use& v : uses[other])
        if (!done && owned[v.bond] < 0) {
          place(other, v);
          place(t, u);
          done = true;
        }
      if (done)
        break;
    }
    if (!done) {
      const Use& u = uses[t].front();
      m_extra.push_back({u.bond, u.bcd, uses[t].size() / 3.0, area0_sum[t] / 3.0});
    }
  }
  std::sort(m_extra.begin(), m_extra.end(),
            [](const ExtraTriangle& x, const ExtraTriangle& y) { return x.bond < y.bond; });
  for (std::size_t t = 0; t < n_triangles; ++t) {
    if (owner[t].bcd < 0)
      continue; // an extra
    const std::size_t b = owner[t].bond;
    m_ref.bcd[b] = owner[t].bcd;
    m_ref.weight[b] = uses[t].size() / 3.0;
    m_ref.area0[b] = area0_sum[t] / 3.0;
  }
  return true;
}

bool FastBondPlan::build_triangles(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 3 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_triangles.resize(n);
  m_slot_mol.resize(m_index.size());
  for (std::size_t k = 0; k < m_index.size(); ++k)
    m_slot_mol[k] = p.mol_id[m_index[k]];
  m_cell_mol.clear();
  m_cell_reference.clear();
  // cells as the generic cell sums define them: the mol_id of a triangle's
  // first node; reference point the first node of the cell's first triangle
  std::unordered_map<int, int> cell_of_mol;
  for (std::size_t t = 0; t < n; ++t) {
    const int* s = slots.data() + 3 * t;
    const int mol = p.mol_id[m_index[s[0]]];
    auto [it, inserted] = cell_of_mol.try_emplace(mol, static_cast<int>(m_cell_mol.size()));
    if (inserted) {
      m_cell_mol.push_back(mol);
      m_cell_reference.push_back(s[0]);
    }
    m_triangles[t] = {s[0], s[1], s[2], it->second};
  }
  // each node in the triangles of one cell only (as an OifCell's): its
  // forces are then its cell's factors times its sums (run); else decline
  m_slot_cell.assign(m_index.size(), -1);
  m_nodes_in_one_cell = true;
  for (const Triangle& tr : m_triangles)
    for (const int v : {tr.v0, tr.v1, tr.v2}) {
      m_nodes_in_one_cell &= m_slot_cell[v] < 0 || m_slot_cell[v] == tr.cell;
      m_slot_cell[v] = tr.cell;
    }
  const std::size_t n_cells = m_cell_mol.size();
  // triangles grouped by cell (a cell's are contiguous when created in bulk;
  // the stable sort keeps their order): per-cell passes over a range
  std::stable_sort(m_triangles.begin(), m_triangles.end(),
                   [](const Triangle& a, const Triangle& b) { return a.cell < b.cell; });
  m_cell_begin.assign(n_cells + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    ++m_cell_begin[m_triangles[t].cell + 1];
  std::size_t largest = 0;
  for (std::size_t c = 0; c < n_cells; ++c) {
    largest = std::max<std::size_t>(largest, m_cell_begin[c + 1]);
    m_cell_begin[c + 1] += m_cell_begin[c];
  }
  m_scratch.resize(kCellArrays * largest);
  m_cell_origin.resize(n_cells);
  return true;
}

bool FastBondPlan::gather_relative_same_cells(const ParticleStore& p, const BoxGeometry& box) {
  int same = 1;
  for (std::size_t s = 0; s < m_index.size(); ++s)
    same &= p.mol_id[m_index[s]] == m_slot_mol[s];
  gather_relative(p, box);
  return same;
}

void FastBondPlan::gather_relative(const ParticleStore& p, const BoxGeometry& box) {
  const Vec3& L = box.length();
  const Vec3 half = 0.5 * L;
  int within = 1;
  for (std::size_t f = 0; f + 1 < m_frame_begin.size(); ++f) {
    const int begin = m_frame_begin[f], end = m_frame_begin[f + 1];
    const int r = m_index[begin];
    const Vec3 pos_r = p.pos[r];
    const Vec3i image_r = p.image[r];
    Vec3 low = Vec3::Zero(), high = Vec3::Zero();
    for (int s = begin; s < end; ++s) {
      const int i = m_index[s];
      // the image difference first (integers, exact): no growth of rounding
      // with the number of boxes a cell has travelled
      const Vec3 x = (p.pos[i] - pos_r) + (p.image[i] - image_r).cast<double>().cwiseProduct(L);
      m_x[s] = x;
      low = low.cwiseMin(x);
      high = high.cwiseMax(x);
    }
    // within half the box on every periodic axis, all the frame's
    // separations are their own minimum images (no check per bond)
    for (int d = 0; d < 3; ++d)
      within &= !box.periodic()[d] || high[d] - low[d] <= half[d];
  }
  m_within_half = within;
}

void FastBondPlan::gather_positions(const ParticleStore& p) {
  for (std::size_t s = 0; s < m_index.size(); ++s)
    m_x[s] = p.pos[m_index[s]];
}

bool FastBondPlan::commit_forces(ParticleStore& p) const {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "m_f is read as an array of doubles");
  // NaN or inf anywhere: decline, the generic loop names the bond
  const double* f = m_f.empty() ? nullptr : m_f[0].data();
  const std::size_t n = 3 * m_f.size();
  const double largest = std::numeric_limits<double>::max();
  int finite = 1;
  for (std::size_t k = 0; k < n; ++k)
    finite &= std::abs(f[k]) <= largest;
  if (!finite)
    return false;
  for (std::size_t s = 0; s < m_index.size(); ++s)
    p.force[m_index[s]] += m_f[s];
  return true;
}

// ---------------------------------------------------------------------------
// OifLocalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifLocalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const GroupKey key(group, p, kind_local);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_local(group, p);
    ++m_n_builds;
  }
  if (!m_usable)
    return false;
  gather_relative(p, box);
  if (ia.kvisc != 0.0)
    for (std::size_t s = 0; s < m_index.size(); ++s)
      m_v[s] = p.vel[m_index[s]];
  for (Vec3& f : m_f)
    f.setZero();

  // One pass over the bonds in blocks: gather the minimum-image edge vectors
  // (indexed loads), then the arithmetic over plain arrays (short independent
  // loops the compiler vectorises; one bond at a time, its long chain of square
  // roots, divisions and the arctangent leaves the core waiting), then scatter
  // the forces on the four nodes.
  const double kvisc = ia.kvisc, kb = ia.kb, kal = ia.kal;
  const bool wings = kb != 0.0 || kal != 0.0; // terms that need a and d
  EdgeBlock blk;
  const ExtraTriangle *extra = m_extra.data(), *const extra_end = extra + m_extra.size();
  for (std::size_t first = 0; first < m_bonds.size(); first += kBlock) {
    const int nb = static_cast<int>(std::min<std::size_t>(kBlock, m_bonds.size() - first));
    const EdgeBond* bond = m_bonds.data() + first;
    const double *r0 = m_ref.r0.data() + first, *inv_r0 = m_ref.inv_r0.data() + first;
    const double *cos_psi0 = m_ref.cos_psi0.data() + first,
                 *sin_psi0 = m_ref.sin_psi0.data() + first;
    const double *bcd = m_ref.bcd.data() + first, *weight = m_ref.weight.data() + first,
                 *area0 = m_ref.area0.data() + first;
    for (int k = 0; k < nb; ++k) {
      const EdgeBond& bd = bond[k];
      const Vec3& xb = m_x[bd.b];
      const Vec3 e = m_x[bd.c] - xb; // c - b, the shared edge (minimum image below)
      for (int d = 0; d < 3; ++d)
        blk.e[d][k] = e[d];
      if (wings) {
        const Vec3 u = m_x[bd.a] - xb; // a - b
        const Vec3 w = m_x[bd.d] - xb; // d - b
        for (int d = 0; d < 3; ++d) {
          blk.u[d][k] = u[d];
          blk.w[d][k] = w[d];
        }
      }
      if (kvisc != 0.0) {
        const Vec3 dv = m_v[bd.c] - m_v[bd.b];
        for (int d = 0; d < 3; ++d)
          blk.dv[d][k] = dv[d];
      }
    }
    // separations of the frame; a cell wider than half the box (unusual)
    // needs the minimum image of the generic loop
    for (int d = 0; d < 3; ++d)
      if (!m_within_half && box.periodic()[d]) {
        const double L = box.length()[d];
        if (beyond_half(blk.e[d], nb, L))
          minimum_image_axis(blk.e[d], nb, L);
        if (wings) {
          if (beyond_half(blk.u[d], nb, L))
            minimum_image_axis(blk.u[d], nb, L);
          if (beyond_half(blk.w[d], nb, L))
            minimum_image_axis(blk.w[d], nb, L);
        }
      }
    if (!edge_block_forces(blk, nb, r0, inv_r0, cos_psi0, sin_psi0, ia, wings))
      return false;

    if (kal != 0.0) {
      // local area (eq. 5) of the triangle this bond owns (weight 0 else),
      // centroid allocation (oif_area.hpp). Both triangles have b, the
      // frame's zero, as a vertex: the triangle is (0, P, Q) with ABC: P = u
      // (a), Q = e (c); BCD: P = e (c), Q = w (d), chosen by factors 0/1
      // (exact), branch-free. Centroid T = (P + Q)/3; vertex i gets
      // scale (T - p_i), scale = kal (weight S - area0) / sum_i |T - p_i|^2.
      constexpr double third = 1.0 / 3.0;
      for (int k = 0; k < nb; ++k) {
        const double s1 = bcd[k], s0 = 1.0 - s1;
        double t[3], mp[3], mq[3];
        for (int d = 0; d < 3; ++d) {
          const double pd = s0 * blk.u[d][k] + s1 * blk.e[d][k];
          const double qd = s0 * blk.e[d][k] + s1 * blk.w[d][k];
          t[d] = (pd + qd) * third;
          mp[d] = t[d] - pd;
          mq[d] = t[d] - qd;
        }
        const double norm2 = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]) +
                             (mp[0] * mp[0] + mp[1] * mp[1] + mp[2] * mp[2]) +
                             (mq[0] * mq[0] + mq[1] * mq[1] + mq[2] * mq[2]);
        const double area = 0.5 * std::sqrt(s0 * blk.n1_2[k] + s1 * blk.n2_2[k]);
        const double scale = kal * (weight[k] * area - area0[k]) / norm2;
        for (int d = 0; d < 3; ++d) {
          const double fp = scale * mp[d], fq = scale * mq[d];
          blk.fb[d][k] += scale * t[d];
          blk.fa[d][k] += s0 * fp;
          blk.fc[d][k] += s0 * fq + s1 * fp;
          blk.fd[d][k] += s1 * fq;
        }
      }
      // triangles that no bond could own alone (none on closed meshes seen)
      for (; extra != extra_end && extra->bond < first + nb; ++extra) {
        const int k = static_cast<int>(extra->bond - first);
        const double e[3] = {blk.e[0][k], blk.e[1][k], blk.e[2][k]};
        const double u[3] = {blk.u[0][k], blk.u[1][k], blk.u[2][k]};
        const double w[3] = {blk.w[0][k], blk.w[1][k], blk.w[2][k]};
        const double zero[3] = {0.0, 0.0, 0.0};
        double* fa[3] = {&blk.fa[0][k], &blk.fa[1][k], &blk.fa[2][k]};
        double* fb[3] = {&blk.fb[0][k], &blk.fb[1][k], &blk.fb[2][k]};
        double* fc[3] = {&blk.fc[0][k], &blk.fc[1][k], &blk.fc[2][k]};
        double* fd[3] = {&blk.fd[0][k], &blk.fd[1][k], &blk.fd[2][k]};
        if (extra->bcd == 0)
          centroid_area_force(u, zero, e, 0.5 * std::sqrt(blk.n1_2[k]), extra->weight, extra->area0,
                              kal, fa, fb, fc);
        else
          centroid_area_force(zero, e, w, 0.5 * std::sqrt(blk.n2_2[k]), extra->weight, extra->area0,
                              kal, fb, fc, fd);
      }
    }

    for (int k = 0; k < nb; ++k) {
      const EdgeBond& bd = bond[k];
      m_f[bd.b] += Vec3(blk.fb[0][k], blk.fb[1][k], blk.fb[2][k]);
      m_f[bd.c] += Vec3(blk.fc[0][k], blk.fc[1][k], blk.fc[2][k]);
      if (wings) {
        m_f[bd.a] += Vec3(blk.fa[0][k], blk.fa[1][k], blk.fa[2][k]);
        m_f[bd.d] += Vec3(blk.fd[0][k], blk.fd[1][k], blk.fd[2][k]);
      }
    }
  }
  return commit_forces(p);
}

// ---------------------------------------------------------------------------
// OifGlobalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifGlobalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const GroupKey key(group, p, kind_global);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
  }
  m_normals_written = false;
  if (!m_usable)
    return false;
  if (!gather_relative_same_cells(p, box)) { // a mol_id changed: the cells regroup
    m_usable = build_triangles(group, p);
    ++m_n_builds;
    if (!m_usable)
      return false;
    gather_relative(p, box);
  }
  if (!m_nodes_in_one_cell)
    return false;
  // One pass over each cell's triangles: per node, the sums that its forces
  // are the cell's factors times (eqs. 6, 7 need the cell's totals first):
  //   global area (centroid allocation, oif_area.hpp): vertex i of triangle
  //     t gets kag (S - S0)/S0 S_t (T - p_i) / sum_j |T - p_j|^2: sum over t
  //     of g_t (T - p_i), g_t = S_t / sum_j |T - p_j|^2, in m_f;
  //   volume (oif_volume.hpp): each vertex gets -kv (|V| - V0)/V0 s N_t / 6:
  //     sum of N_t = (b - a) x (c - a) over t, in m_normal (whose direction
  //     is also the node's normal of OifOutDirection).
  for (Vec3& f : m_f)
    f.setZero();
  m_normal.assign(m_index.size(), Vec3::Zero());
  m_cell_area_factor.resize(m_cell_mol.size());
  m_cell_volume_factor.resize(m_cell_mol.size());
  m_cell_sign.resize(m_cell_mol.size());
  const double ka_g = ia.ka_g, kv = ia.kv, A0_g = ia.A0_g, V0 = ia.V0;
  constexpr double third = 1.0 / 3.0;
  for (std::size_t cell = 0; cell < m_cell_mol.size(); ++cell) {
    const std::size_t begin = m_cell_begin[cell];
    const int n = static_cast<int>(m_cell_begin[cell + 1] - begin);
    const Triangle* tri = m_triangles.data() + begin;
    double* const sc = m_scratch.data();
    const std::size_t stride = m_scratch.size() / kCellArrays;
    auto arr = [&](int which) { return sc + which * stride; };
    double *e1x = arr(0), *e1y = arr(1), *e1z = arr(2), *e2x = arr(3), *e2y = arr(4), *e2z = arr(5),
           *nx = arr(6), *ny = arr(7), *nz = arr(8), *area = arr(9), *vol = arr(10), *ax = arr(11),
           *ay = arr(12), *az = arr(13);
    double *g0x = arr(14), *g0y = arr(15), *g0z = arr(16), *g1x = arr(17), *g1y = arr(18),
           *g1z = arr(19), *g2x = arr(20), *g2y = arr(21), *g2z = arr(22);
    // m_x: unfolded, relative to the frame's reference node (gather_relative)
    const Vec3 origin = m_x[m_cell_reference[cell]];
    for (int k = 0; k < n; ++k) {
      const Vec3& x0 = m_x[tri[k].v0];
      const Vec3 e1 = m_x[tri[k].v1] - x0; // minimum image below if needed
      const Vec3 e2 = m_x[tri[k].v2] - x0;
      // first vertex relative to the cell's reference point, unfolded
      // (oif_cell_sums.hpp): a . (b x c) = a . N with N = (b - a) x (c - a)
      const Vec3 a = x0 - origin;
      e1x[k] = e1[0], e1y[k] = e1[1], e1z[k] = e1[2];
      e2x[k] = e2[0], e2y[k] = e2[1], e2z[k] = e2[2];
      ax[k] = a[0], ay[k] = a[1], az[k] = a[2];
    }
    for (int d = 0; d < 3; ++d)
      if (!m_within_half && box.periodic()[d]) {
        const double L = box.length()[d];
        for (int which : {d, 3 + d}) // e1, e2
          if (beyond_half(arr(which), n, L))
            minimum_image_axis(arr(which), n, L);
      }
    int bad = 0;
    PYOIF_INDEPENDENT_ITERATIONS
    for (int k = 0; k < n; ++k) {
      const double e1x_ = e1x[k], e1y_ = e1y[k], e1z_ = e1z[k];
      const double e2x_ = e2x[k], e2y_ = e2y[k], e2z_ = e2z[k];
      const double x = e1y_ * e2z_ - e1z_ * e2y_;
      const double y = e1z_ * e2x_ - e1x_ * e2z_;
      const double z = e1x_ * e2y_ - e1y_ * e2x_;
      nx[k] = x, ny[k] = y, nz[k] = z;
      const double s = 0.5 * std::sqrt(x * x + y * y + z * z);
      bad |= !(s > 0.0);
      area[k] = s;
      vol[k] = ax[k] * x + ay[k] * y + az[k] * z;
      // centroid relative to the first vertex: T - p0 = (e1 + e2)/3
      const double m0x = (e1x_ + e2x_) * third, m0y = (e1y_ + e2y_) * third,
                   m0z = (e1z_ + e2z_) * third;
      const double m1x = m0x - e1x_, m1y = m0y - e1y_, m1z = m0z - e1z_;
      const double m2x = m0x - e2x_, m2y = m0y - e2y_, m2z = m0z - e2z_;
      const double g = s / (m0x * m0x + m0y * m0y + m0z * m0z + m1x * m1x + m1y * m1y + m1z * m1z +
                            m2x * m2x + m2y * m2y + m2z * m2z);
      g0x[k] = g * m0x, g0y[k] = g * m0y, g0z[k] = g * m0z;
      g1x[k] = g * m1x, g1y[k] = g * m1y, g1z[k] = g * m1z;
      g2x[k] = g * m2x, g2y[k] = g * m2y, g2z[k] = g * m2z;
    }
    if (bad)
      return false;
    AreaVolumeSums<> sums(n);
    sums.add(area, vol, 0, n);
    const double cell_area = sums.area(), cell_volume = sums.volume();
    if (!(cell_area > 0.0))
      return false;
    // volume (eq. 7): F = -kv (|V| - V0)/V0 s N / 6 on each vertex
    const double sign = cell_volume < 0.0 ? -1.0 : 1.0;
    m_cell_volume_factor[cell] =
        kv != 0.0 ? -kv * ((sign * cell_volume - V0) / V0) * sign / 6.0 : 0.0;
    // global area (eq. 6): kag (S - S0) / S0 times the sums of g_t (T - p_i)
    m_cell_area_factor[cell] = ka_g != 0.0 ? ka_g * (cell_area - A0_g) / A0_g : 0.0;
    m_cell_sign[cell] = sign;
    for (int q = 0; q < n; ++q) {
      const Vec3 nq(nx[q], ny[q], nz[q]);
      m_f[tri[q].v0] += Vec3(g0x[q], g0y[q], g0z[q]);
      m_normal[tri[q].v0] += nq;
      m_f[tri[q].v1] += Vec3(g1x[q], g1y[q], g1z[q]);
      m_normal[tri[q].v1] += nq;
      m_f[tri[q].v2] += Vec3(g2x[q], g2y[q], g2z[q]);
      m_normal[tri[q].v2] += nq;
    }
  }
  for (std::size_t s = 0; s < m_index.size(); ++s) {
    const int c = m_slot_cell[s];
    m_f[s] = m_cell_area_factor[c] * m_f[s] + m_cell_volume_factor[c] * m_normal[s];
  }
  if (!commit_forces(p))
    return false;
  if (write_normals) { // OifOutDirection's area-weighted normals, outward by the volume's sign
    for (std::size_t s = 0; s < m_index.size(); ++s) {
      const double len = m_normal[s].norm();
      const Vec3 nq = m_cell_sign[m_slot_cell[s]] * m_normal[s];
      p.normal[m_index[s]] = len > 0.0 ? Vec3(nq / len) : nq;
    }
    m_normals_written = true;
  }
  return true;
}

bool FastBondPlan::same_triangles(const BondGroup& own, const BondGroup& source) {
  return m_same_triangles.get(own, source, [&] {
    return own.n_particles == 3 && source.n_particles == 3 && own.ids == source.ids;
  });
}

// ---------------------------------------------------------------------------
// OifOutDirection
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifOutDirection&, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const GroupKey key(group, p, kind_out_direction);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
    if (m_usable) {
      // a cell's orientation is fixed by its mesh: the sign of its oriented
      // volume, determined once per set of bonds (as OifOutDirection does)
      gather_positions(p);
      std::vector<double> volume(m_cell_mol.size(), 0.0);
      for (std::size_t c = 0; c < m_cell_mol.size(); ++c) {
        const int i = m_index[m_cell_reference[c]];
        m_cell_origin[c] = box.unfolded(p.pos[i], p.image[i]);
      }
      for (const Triangle& tr : m_triangles) {
        const Vec3& x0 = m_x[tr.v0];
        const Vec3 n = box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
        volume[tr.cell] +=
            (box.unfolded(x0, p.image[m_index[tr.v0]]) - m_cell_origin[tr.cell]).dot(n);
      }
      m_outward_sign.resize(m_triangles.size());
      for (std::size_t t = 0; t < m_triangles.size(); ++t)
        m_outward_sign[t] = volume[m_triangles[t].cell] < 0.0 ? -1.0 : 1.0;
    }
  }
  if (!m_usable)
    return false;
  gather_positions(p);
  for (Vec3& f : m_f)
    f.setZero();
  // area-weighted normal of each node: the sum of its triangles' 2 S n
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Triangle& tr = m_triangles[t];
    const Vec3& x0 = m_x[tr.v0];
    const Vec3 n = m_outward_sign[t] *
                   box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
    m_f[tr.v0] += n;
    m_f[tr.v1] += n;
    m_f[tr.v2] += n;
  }
  for (std::size_t s = 0; s < m_index.size(); ++s) {
    const double len = m_f[s].norm();
    p.normal[m_index[s]] = len > 0.0 ? Vec3(m_f[s] / len) : m_f[s];
  }
  return true;
}

// ---------------------------------------------------------------------------
// OifLocalForces + OifGlobalForces (+ OifOutDirection normals), fused
// ---------------------------------------------------------------------------
bool FusedMembranePlan::same_particles(const BondGroup& local, const BondGroup& global) {
  return m_same_particles.get(local, global, [&] {
    auto sorted_unique = [](std::vector<int> ids) {
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      return ids;
    };
    return local.n_particles == 4 && global.n_particles == 3 && !local.ids.empty() &&
           sorted_unique(local.ids) == sorted_unique(global.ids);
  });
}

bool FusedMembranePlan::build(const BondGroup& local, const BondGroup& global,
                              const ParticleStore& p) {
  if (local.n_particles != 4 || local.per_bond_stride != 4 || global.n_particles != 3)
    return false;
  std::vector<int> frame_begin, tri_slots;
  if (!slots_by_frame(global, p, m_index, frame_begin, tri_slots) ||
      m_index.size() >= kMaxTriangleSlots)
    return false;
  const std::size_t n_slots = m_index.size(), n_cells = frame_begin.size() - 1;
  // cells: the frames (connected sets of triangles), each of one mol_id and
  // no two of the same, so that they are the cells of the generic cell sums
  // (triangles grouped by the mol_id of their first node)
  std::vector<int> slot_cell(n_slots);
  m_slot_mol.resize(n_slots);
  std::unordered_set<int> mols;
  for (std::size_t c = 0; c < n_cells; ++c) {
    const int mol = p.mol_id[m_index[frame_begin[c]]];
    if (!mols.insert(mol).second)
      return false;
    for (int s = frame_begin[c]; s < frame_begin[c + 1]; ++s) {
      m_slot_mol[s] = p.mol_id[m_index[s]];
      if (m_slot_mol[s] != mol)
        return false;
      slot_cell[s] = static_cast<int>(c);
    }
  }
  // triangles cell by cell, the group's order kept within a cell (counting sort)
  const std::size_t n_tri = global.size();
  std::vector<int> tri_begin(n_cells + 1, 0);
  for (std::size_t t = 0; t < n_tri; ++t)
    ++tri_begin[slot_cell[tri_slots[3 * t]] + 1];
  for (std::size_t c = 0; c < n_cells; ++c)
    tri_begin[c + 1] += tri_begin[c];
  std::vector<int> next(tri_begin.begin(), tri_begin.end() - 1);
  for (auto* v : {&m_tri_v0, &m_tri_v1, &m_tri_v2})
    v->resize(n_tri);
  m_tri_weight.assign(n_tri, 0.0);
  m_tri_area0.assign(n_tri, 0.0);
  std::unordered_map<std::uint64_t, int> triangle_of;
  triangle_of.reserve(n_tri);
  for (std::size_t t = 0; t < n_tri; ++t) {
    const int* s = tri_slots.data() + 3 * t;
    const int c = slot_cell[s[0]], q = next[c]++, base = frame_begin[c];
    m_tri_v0[q] = s[0] - base;
    m_tri_v1[q] = s[1] - base;
    m_tri_v2[q] = s[2] - base;
    triangle_of.try_emplace(triangle_key(s[0], s[1], s[2]), q);
  }
  // edges: the local bonds as slots, their triangles ABC and BCD among the
  // global group's (else the groups do not pair up)
  std::vector<int> slot_of(p.n_local(), -1);
  for (std::size_t s = 0; s < n_slots; ++s)
    slot_of[m_index[s]] = static_cast<int>(s);
  const std::size_t n_edges = local.size();
  std::vector<int> edge_slots(4 * n_edges), edge_begin(n_cells + 1, 0);
  for (std::size_t b = 0; b < n_edges; ++b) {
    int* s = edge_slots.data() + 4 * b; // (B, A, C, D)
    for (int j = 0; j < 4; ++j) {
      const int i = p.index(local.bond(b)[j]);
      s[j] = i < 0 ? -1 : slot_of[i];
      if (s[j] < 0)
        return false;
    }
    const double* ref = local.reference(b);
    // the generic loop rejects these as degenerate (and throws): leave it to it
    if (!(ref[0] > 0.0) || !(ref[2] > 0.0) || !(ref[3] > 0.0) || !std::isfinite(ref[1]))
      return false;
    const auto abc = triangle_of.find(triangle_key(s[1], s[0], s[2]));
    const auto bcd = triangle_of.find(triangle_key(s[0], s[2], s[3]));
    if (abc == triangle_of.end() || bcd == triangle_of.end())
      return false;
    // eq. 5 per bond: kal (S - S0_bond) / 3 on each of its two triangles
    m_tri_weight[abc->second] += 1.0 / 3.0;
    m_tri_area0[abc->second] += ref[2] / 3.0;
    m_tri_weight[bcd->second] += 1.0 / 3.0;
    m_tri_area0[bcd->second] += ref[3] / 3.0;
    ++edge_begin[slot_cell[s[0]] + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c)
    edge_begin[c + 1] += edge_begin[c];
  next.assign(edge_begin.begin(), edge_begin.end() - 1);
  for (auto* v : {&m_edge_b, &m_edge_a, &m_edge_c, &m_edge_d})
    v->resize(n_edges);
  for (auto* v : {&m_edge_r0, &m_edge_inv_r0, &m_edge_cos_psi0, &m_edge_sin_psi0})
    v->resize(n_edges);
  for (std::size_t b = 0; b < n_edges; ++b) {
    const int* s = edge_slots.data() + 4 * b;
    const int c = slot_cell[s[0]], q = next[c]++, base = frame_begin[c];
    m_edge_b[q] = s[0] - base;
    m_edge_a[q] = s[1] - base;
    m_edge_c[q] = s[2] - base;
    m_edge_d[q] = s[3] - base;
    const double* ref = local.reference(b);
    m_edge_r0[q] = ref[0];
    m_edge_inv_r0[q] = 1.0 / ref[0];
    // psi0 = pi - phi0: cos psi0 = -cos phi0, sin psi0 = sin phi0
    m_edge_cos_psi0[q] = -std::cos(ref[1]);
    m_edge_sin_psi0[q] = std::sin(ref[1]);
  }
  m_cells.resize(n_cells);
  std::size_t largest_nodes = 0, largest_tri = 0;
  for (std::size_t c = 0; c < n_cells; ++c) {
    CellRange& r = m_cells[c];
    r.node_begin = frame_begin[c];
    r.node_end = frame_begin[c + 1];
    r.triangle_begin = tri_begin[c];
    r.triangle_end = tri_begin[c + 1];
    r.edge_begin = edge_begin[c];
    r.edge_end = edge_begin[c + 1];
    // the generic cell sums' reference point: the first node of the cell's
    // first triangle (the volume of an open mesh depends on it)
    r.origin = m_tri_v0[r.triangle_begin];
    largest_nodes = std::max<std::size_t>(largest_nodes, r.node_end - r.node_begin);
    largest_tri = std::max<std::size_t>(largest_tri, r.triangle_end - r.triangle_begin);
  }
  share_cell_tables();
  form_batches();
  m_node.assign(kNodeArrays * largest_nodes, Node4{Lanes{0.0, 0.0, 0.0, 0.0}});
  m_tri.assign(kTriangleArrays * largest_tri, 0.0);
  const BatchLanes zero{};
  m_batch_node.assign(m_batches.empty() ? 0 : kNodeArrays * largest_nodes,
                      NodeLanes{{zero, zero, zero}});
  m_batch_tri.assign(m_batches.empty() ? 0 : 2 * largest_tri, zero);
  m_f.resize(n_slots);
  return true;
}

template <class F> void FusedMembranePlan::for_each_cell_table(F&& f) {
  for (auto* table : {&m_tri_v0, &m_tri_v1, &m_tri_v2})
    f(*table, false);
  for (auto* table : {&m_tri_weight, &m_tri_area0})
    f(*table, false);
  for (auto* table : {&m_edge_b, &m_edge_a, &m_edge_c, &m_edge_d})
    f(*table, true);
  for (auto* table : {&m_edge_r0, &m_edge_inv_r0, &m_edge_cos_psi0, &m_edge_sin_psi0})
    f(*table, true);
}

void FusedMembranePlan::share_cell_tables() {
  // Cells of one OifCellType have the same triangles and edges as cell-local
  // node indices, and the same reference values: they share one copy of
  // these tables, which the pass then reads from L1/L2 for every cell
  // instead of streaming a copy per cell through L3, where it competes with
  // the lattice (at 60 cells the copies were about 4 MB). A cell whose tables
  // differ in any bit keeps its own. The arithmetic is unchanged.
  auto range = [](const CellRange& r, bool edges) {
    return edges ? std::pair{r.edge_begin, r.edge_end - r.edge_begin}
                 : std::pair{r.triangle_begin, r.triangle_end - r.triangle_begin};
  };
  // each cell's template: the first cell with bit-for-bit the same tables
  std::vector<std::size_t> template_of(m_cells.size()), templates;
  for (std::size_t c = 0; c < m_cells.size(); ++c) {
    template_of[c] = c;
    for (std::size_t t : templates) {
      bool equal = true;
      for_each_cell_table([&](const auto& table, bool edges) {
        const auto [a, n] = range(m_cells[c], edges);
        const auto [b, m] = range(m_cells[t], edges);
        equal = equal && n == m &&
                (n == 0 || std::memcmp(table.data() + a, table.data() + b,
                                       sizeof(table[0]) * static_cast<std::size_t>(n)) == 0);
      });
      if (equal) {
        template_of[c] = t;
        break;
      }
    }
    if (template_of[c] == c)
      templates.push_back(c);
  }
  // the tables keep the templates' ranges, one after the other
  for_each_cell_table([&](auto& table, bool edges) {
    std::decay_t<decltype(table)> shared;
    for (std::size_t t : templates) {
      const auto [a, n] = range(m_cells[t], edges);
      shared.insert(shared.end(), table.begin() + a, table.begin() + a + n);
    }
    table.swap(shared);
  });
  std::vector<CellRange> moved(m_cells.size());
  int triangles = 0, edges = 0;
  for (std::size_t t : templates) {
    CellRange& r = moved[t];
    r = m_cells[t];
    r.triangle_begin = triangles;
    r.triangle_end = triangles += m_cells[t].triangle_end - m_cells[t].triangle_begin;
    r.edge_begin = edges;
    r.edge_end = edges += m_cells[t].edge_end - m_cells[t].edge_begin;
  }
  for (std::size_t c = 0; c < m_cells.size(); ++c) {
    const CellRange& t = moved[template_of[c]];
    CellRange& r = m_cells[c];
    r.triangle_begin = t.triangle_begin;
    r.triangle_end = t.triangle_end;
    r.edge_begin = t.edge_begin;
    r.edge_end = t.edge_end;
  }
}

template <class Store, class StoreVelocity>
bool FusedMembranePlan::gather_cell_with(std::size_t cell, const ParticleStore& p,
                                         const BoxGeometry& box, bool velocities, bool* regroup,
                                         Store&& store, StoreVelocity&& store_velocity) const {
  const CellRange& r = m_cells[cell];
  const Vec3& L = box.length();
  const int ref = m_index[r.node_begin];
  const Vec3 pos_r = p.pos[ref];
  const Vec3i image_r = p.image[ref];
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();
  int same = 1;
  for (int s = r.node_begin; s < r.node_end; ++s) {
    const int i = m_index[s];
    same &= p.mol_id[i] == m_slot_mol[s];
    // unfolded relative to the reference node, the image difference first
    // (integers, exact), as FastBondPlan::gather_relative
    const Vec3 xk = (p.pos[i] - pos_r) + (p.image[i] - image_r).cast<double>().cwiseProduct(L);
    store(s - r.node_begin, xk);
    low = low.cwiseMin(xk);
    high = high.cwiseMax(xk);
  }
  if (!same) {
    *regroup = true;
    return false;
  }
  // within half the box on every periodic axis, all the cell's separations
  // are their own minimum images; else the separate plans take the minimum
  // image per separation
  for (int d = 0; d < 3; ++d)
    if (box.periodic()[d] && high[d] - low[d] > 0.5 * L[d])
      return false;
  if (velocities)
    for (int s = r.node_begin; s < r.node_end; ++s)
      store_velocity(s - r.node_begin, p.vel[m_index[s]]);
  return true;
}

bool FusedMembranePlan::gather_cell(std::size_t cell, const ParticleStore& p,
                                    const BoxGeometry& box, bool velocities, bool* regroup) {
  const std::size_t section = m_node.size() / kNodeArrays; // largest cell's nodes
  Node4* const x = m_node.data();
  Node4* const v = m_node.data() + section;
  return gather_cell_with(
      cell, p, box, velocities, regroup,
      [x](int k, const Vec3& xk) {
        x[k].v = Lanes{xk[0], xk[1], xk[2], 0.0};
      },
      [v](int k, const Vec3& vk) {
        v[k].v = Lanes{vk[0], vk[1], vk[2], 0.0};
      });
}

bool FusedMembranePlan::gather_batch(const Batch& batch, const ParticleStore& p,
                                     const BoxGeometry& box, bool velocities, bool* regroup) {
  const std::size_t section = m_batch_node.size() / kNodeArrays;
  NodeLanes* const x = m_batch_node.data();
  NodeLanes* const v = m_batch_node.data() + section;
  for (int lane = 0; lane < kBatchCells; ++lane)
    if (!gather_cell_with(
            batch.cell[lane], p, box, velocities, regroup,
            [x, lane](int k, const Vec3& xk) {
              for (int d = 0; d < 3; ++d)
                x[k].c[d][lane] = xk[d];
            },
            [v, lane](int k, const Vec3& vk) {
              for (int d = 0; d < 3; ++d)
                v[k].c[d][lane] = vk[d];
            }))
      return false;
  return true;
}

bool FusedMembranePlan::evaluate_cell(std::size_t cell, const OifLocalForces& local_ia,
                                      const OifGlobalForces& global_ia, bool write_normals,
                                      ParticleStore& p) {
  const CellRange& r = m_cells[cell];
  const int n_nodes = r.node_end - r.node_begin, n_tri = r.triangle_end - r.triangle_begin;
  // node arrays, one 4-lane vector (x, y, z, 0) per node (Node4)
  const std::size_t section = m_node.size() / kNodeArrays, ts = m_tri.size() / kTriangleArrays;
  const Node4* const x = m_node.data();
  const Node4* const v = m_node.data() + section;
  Node4* const f = m_node.data() + 2 * section;
  Node4* const nsum = m_node.data() + 3 * section;
  const Lanes zero{0.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < n_nodes; ++k) {
    f[k].v = zero;
    nsum[k].v = zero;
  }
  double* const tri = m_tri.data();
  double *const nx = tri, *const ny = tri + ts, *const nz = tri + 2 * ts;
  double *const g = tri + 3 * ts, *const coef = tri + 4 * ts;
  const int *const v0 = m_tri_v0.data() + r.triangle_begin,
                   *const v1 = m_tri_v1.data() + r.triangle_begin,
                   *const v2 = m_tri_v2.data() + r.triangle_begin;
  const double *const weight = m_tri_weight.data() + r.triangle_begin, *const area0 =
                                                                           m_tri_area0.data() +
                                                                           r.triangle_begin;

  // Triangle pass: per triangle N = (b - a) x (c - a), its area S = |N|/2
  // and volume term a.N (eqs. 6, 7; a relative to the cell's reference
  // point), and the two centroid allocations (oif_area.hpp), which share
  // their direction: vertex i gets (T - p_i) / sum_j |T - p_j|^2 times
  //   kal (weight S - area0) for the local area (eq. 5; coef below), and
  //   kag (S_cell - S_cell0) / S_cell0 S for the global area (eq. 6; g
  //   below, the cell's factor applied once the cell's area is known).
  // In blocks: the scalar gather of the separations, then the arithmetic as
  // loops over arrays (vectorised); the cell's area and volume summed block
  // by block (AreaVolumeSums).
  const double kal = local_ia.kal;
  const Lanes origin = x[r.origin].v;
  constexpr double third = 1.0 / 3.0;
  static_assert(kBlock % 4 == 0, "AreaVolumeSums: blocks start at multiples of 4");
  AreaVolumeSums<> sums(n_tri);
  int bad = 0;
  for (int first = 0; first < n_tri; first += kBlock) {
    const int nb = std::min(kBlock, n_tri - first);
    double e1[3][kBlock], e2[3][kBlock], ra[3][kBlock], area[kBlock], vol[kBlock];
    int k0 = 0;
    for (; k0 + 4 <= nb; k0 += 4) { // four triangles at a time (store_components)
      Lanes d1[4], d2[4], a[4];
      for (int j = 0; j < 4; ++j) {
        const int q = first + k0 + j;
        const Lanes pa = x[v0[q]].v;
        d1[j] = x[v1[q]].v - pa;
        d2[j] = x[v2[q]].v - pa;
        a[j] = pa - origin;
      }
      store_components(d1[0], d1[1], d1[2], d1[3], e1[0] + k0, e1[1] + k0, e1[2] + k0);
      store_components(d2[0], d2[1], d2[2], d2[3], e2[0] + k0, e2[1] + k0, e2[2] + k0);
      store_components(a[0], a[1], a[2], a[3], ra[0] + k0, ra[1] + k0, ra[2] + k0);
    }
    for (int k = k0; k < nb; ++k) {
      const int q = first + k;
      const Lanes pa = x[v0[q]].v, d1 = x[v1[q]].v - pa, d2 = x[v2[q]].v - pa, a = pa - origin;
      for (int d = 0; d < 3; ++d) {
        e1[d][k] = d1[d];
        e2[d][k] = d2[d];
        ra[d][k] = a[d];
      }
    }
    PYOIF_INDEPENDENT_ITERATIONS
    for (int k = 0; k < nb; ++k) {
      const int q = first + k;
      const double e1_[3] = {e1[0][k], e1[1][k], e1[2][k]};
      const double e2_[3] = {e2[0][k], e2[1][k], e2[2][k]};
      const double ra_[3] = {ra[0][k], ra[1][k], ra[2][k]};
      const TriangleTerms<double> t = triangle_terms(e1_, e2_, ra_, weight[q], area0[q], kal);
      bad |= !(t.area > 0.0);
      area[k] = t.area;
      vol[k] = t.volume;
      nx[q] = t.nx, ny[q] = t.ny, nz[q] = t.nz;
      g[q] = t.g;
      coef[q] = t.coef;
    }
    sums.add(area, vol, first, nb);
  }
  if (bad)
    return false;
  const double cell_area = sums.area();
  if (!(cell_area > 0.0))
    return false;
  const CellFactors factors(cell_area, sums.volume(), global_ia);
  const double area_factor = factors.area, volume_factor = factors.volume, sign = factors.sign;

  // the area forces along (T - p_i) on the vertices, T - p0 = (e1 + e2) / 3,
  // as vectors per triangle; the normals N summed per node (the volume
  // force and the node normal are along that sum)
  const bool normal_sums = global_ia.kv != 0.0 || write_normals; // as evaluate_batch
  for (int q = 0; q < n_tri; ++q) {
    const double cq = coef[q] + area_factor * g[q];
    const Lanes pa = x[v0[q]].v, e1 = x[v1[q]].v - pa, e2 = x[v2[q]].v - pa, m0 = (e1 + e2) * third;
    f[v0[q]].v += cq * m0;
    f[v1[q]].v += cq * (m0 - e1);
    f[v2[q]].v += cq * (m0 - e2);
    if (normal_sums) {
      const Lanes n_{nx[q], ny[q], nz[q], 0.0};
      nsum[v0[q]].v += n_;
      nsum[v1[q]].v += n_;
      nsum[v2[q]].v += n_;
    }
  }

  // Edge pass: stretching (eq. 3), viscosity and bending (eq. 4) per local
  // bond (B, A, C, D), edge B-C, in blocks (as FastBondPlan's edge pass)
  const bool wings = local_ia.kb != 0.0, velocities = local_ia.kvisc != 0.0;
  EdgeBlock blk;
  for (int first = r.edge_begin; first < r.edge_end; first += kBlock) {
    const int nb = std::min(kBlock, r.edge_end - first);
    const int *const eb = m_edge_b.data() + first, *const ea = m_edge_a.data() + first,
                     *const ec = m_edge_c.data() + first, *const ed = m_edge_d.data() + first;
    int k0 = 0;
    for (; k0 + 4 <= nb; k0 += 4) {                 // four edges at a time (store_components)
      Lanes e[4], u[4] = {}, w[4] = {}, dv[4] = {}; // (zeros: no "may be used uninitialised")
      for (int j = 0; j < 4; ++j) {
        const int k = k0 + j;
        const Lanes xb = x[eb[k]].v;
        e[j] = x[ec[k]].v - xb;
        if (wings) {
          u[j] = x[ea[k]].v - xb;
          w[j] = x[ed[k]].v - xb;
        }
        if (velocities)
          dv[j] = v[ec[k]].v - v[eb[k]].v;
      }
      store_components(e[0], e[1], e[2], e[3], blk.e[0] + k0, blk.e[1] + k0, blk.e[2] + k0);
      if (wings) {
        store_components(u[0], u[1], u[2], u[3], blk.u[0] + k0, blk.u[1] + k0, blk.u[2] + k0);
        store_components(w[0], w[1], w[2], w[3], blk.w[0] + k0, blk.w[1] + k0, blk.w[2] + k0);
      }
      if (velocities)
        store_components(dv[0], dv[1], dv[2], dv[3], blk.dv[0] + k0, blk.dv[1] + k0,
                         blk.dv[2] + k0);
    }
    for (int k = k0; k < nb; ++k) {
      const Lanes xb = x[eb[k]].v, e = x[ec[k]].v - xb;
      for (int d = 0; d < 3; ++d)
        blk.e[d][k] = e[d];
      if (wings) {
        const Lanes u = x[ea[k]].v - xb, w = x[ed[k]].v - xb;
        for (int d = 0; d < 3; ++d) {
          blk.u[d][k] = u[d];
          blk.w[d][k] = w[d];
        }
      }
      if (velocities) {
        const Lanes dv = v[ec[k]].v - v[eb[k]].v;
        for (int d = 0; d < 3; ++d)
          blk.dv[d][k] = dv[d];
      }
    }
    if (!edge_block_forces(blk, nb, m_edge_r0.data() + first, m_edge_inv_r0.data() + first,
                           m_edge_cos_psi0.data() + first, m_edge_sin_psi0.data() + first, local_ia,
                           wings))
      return false;
    for (int k = 0; k < nb; ++k) {
      f[eb[k]].v += Lanes{blk.fb[0][k], blk.fb[1][k], blk.fb[2][k], 0.0};
      f[ec[k]].v += Lanes{blk.fc[0][k], blk.fc[1][k], blk.fc[2][k], 0.0};
      if (wings) {
        f[ea[k]].v += Lanes{blk.fa[0][k], blk.fa[1][k], blk.fa[2][k], 0.0};
        f[ed[k]].v += Lanes{blk.fd[0][k], blk.fd[1][k], blk.fd[2][k], 0.0};
      }
    }
  }

  // per node: the volume force along its normal sum; NaN or inf anywhere:
  // decline (the generic loop names the bond)
  const double largest = std::numeric_limits<double>::max();
  int finite = 1;
  for (int k = 0; k < n_nodes; ++k) {
    const Lanes fk = f[k].v + volume_factor * nsum[k].v;
    for (int d = 0; d < 3; ++d) {
      m_f[r.node_begin + k][d] = fk[d];
      finite &= std::abs(fk[d]) <= largest;
    }
  }
  if (!finite)
    return false;
  // OifOutDirection's area-weighted normals, outward by the volume's sign,
  // straight into the particles while the cell's are in cache (normals are
  // set, not added: should a later cell decline, the pass that then
  // evaluates the OifOutDirection group sets them all again)
  if (write_normals) {
    const int* const index = m_index.data() + r.node_begin;
    for (int k = 0; k < n_nodes; ++k) {
      const Lanes n = nsum[k].v;
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const double scale = len > 0.0 ? sign / len : sign;
      p.normal[index[k]] = Vec3(n[0] * scale, n[1] * scale, n[2] * scale);
    }
  }
  return true;
}

bool FusedMembranePlan::evaluate_batch(const Batch& batch, const OifLocalForces& local_ia,
                                       const OifGlobalForces& global_ia, bool write_normals,
                                       ParticleStore& p) {
  // the cells share their tables (form_batches): the first one's ranges
  const CellRange& r = m_cells[batch.cell[0]];
  const int n_nodes = r.node_end - r.node_begin, n_tri = r.triangle_end - r.triangle_begin;
  const std::size_t section = m_batch_node.size() / kNodeArrays, ts = m_batch_tri.size() / 2;
  const NodeLanes* const x = m_batch_node.data();
  const NodeLanes* const v = m_batch_node.data() + section;
  NodeLanes* const f = m_batch_node.data() + 2 * section;
  NodeLanes* const nsum = m_batch_node.data() + 3 * section;
  const BatchLanes zero = splat<BatchLanes>(0.0);
  for (int k = 0; k < n_nodes; ++k)
    for (int d = 0; d < 3; ++d) {
      f[k].c[d] = zero;
      nsum[k].c[d] = zero;
    }
  BatchLanes* const g = m_batch_tri.data();
  BatchLanes* const coef = m_batch_tri.data() + ts;
  const int *const v0 = m_tri_v0.data() + r.triangle_begin,
                   *const v1 = m_tri_v1.data() + r.triangle_begin,
                   *const v2 = m_tri_v2.data() + r.triangle_begin;
  const double* const weight = m_tri_weight.data() + r.triangle_begin;
  const double* const area0 = m_tri_area0.data() + r.triangle_begin;

  // Triangle pass of evaluate_cell, one triangle at a time for the four
  // cells; the normal sums here already (they do not wait for the cell's
  // factors; the same additions in the same order)
  const double kal = local_ia.kal;
  const NodeLanes origin = x[r.origin];
  constexpr double third = 1.0 / 3.0;
  const bool normal_sums = global_ia.kv != 0.0 || write_normals;
  AreaVolumeSums<BatchLanes> sums(n_tri);
  MaskOf<BatchLanes> bad = zero > zero;
  for (int q = 0; q < n_tri; ++q) {
    const NodeLanes &a = x[v0[q]], &b = x[v1[q]], &c = x[v2[q]];
    BatchLanes e1[3], e2[3], ra[3];
    for (int d = 0; d < 3; ++d) {
      e1[d] = b.c[d] - a.c[d];
      e2[d] = c.c[d] - a.c[d];
      ra[d] = a.c[d] - origin.c[d];
    }
    const TriangleTerms<BatchLanes> t = triangle_terms(e1, e2, ra, weight[q], area0[q], kal);
    bad |= ~(t.area > zero);
    sums.add_one(q, t.area, t.volume);
    g[q] = t.g;
    coef[q] = t.coef;
    if (normal_sums) {
      const BatchLanes n_[3] = {t.nx, t.ny, t.nz};
      for (int d = 0; d < 3; ++d) {
        nsum[v0[q]].c[d] += n_[d];
        nsum[v1[q]].c[d] += n_[d];
        nsum[v2[q]].c[d] += n_[d];
      }
    }
  }
  if (any_lane(bad))
    return false;
  const BatchLanes cell_area = sums.area(), cell_volume = sums.volume();
  BatchLanes area_factor, volume_factor, sign;
  for (int j = 0; j < kBatchCells; ++j) {
    if (!(cell_area[j] > 0.0))
      return false;
    const CellFactors factors(cell_area[j], cell_volume[j], global_ia);
    area_factor[j] = factors.area;
    volume_factor[j] = factors.volume;
    sign[j] = factors.sign;
  }
  // the area forces along (T - p_i), as evaluate_cell
  for (int q = 0; q < n_tri; ++q) {
    const BatchLanes cq = coef[q] + area_factor * g[q];
    const NodeLanes &a = x[v0[q]], &b = x[v1[q]], &c = x[v2[q]];
    for (int d = 0; d < 3; ++d) {
      const BatchLanes e1 = b.c[d] - a.c[d], e2 = c.c[d] - a.c[d], m0 = (e1 + e2) * third;
      f[v0[q]].c[d] += cq * m0;
      f[v1[q]].c[d] += cq * (m0 - e1);
      f[v2[q]].c[d] += cq * (m0 - e2);
    }
  }
  // the edge pass
  const int first = r.edge_begin;
  if (!batch_edge_forces(x, v, f, m_edge_b.data() + first, m_edge_a.data() + first,
                         m_edge_c.data() + first, m_edge_d.data() + first,
                         r.edge_end - r.edge_begin, m_edge_r0.data() + first,
                         m_edge_inv_r0.data() + first, m_edge_cos_psi0.data() + first,
                         m_edge_sin_psi0.data() + first, local_ia))
    return false;
  // per node, as evaluate_cell: the volume force along the normal sum, the
  // normals (sum times sign / |sum|) straight into the particles, and a
  // finite check (here after the normals: they are set, not added, and a
  // declined pass has them all set again)
  const double largest = std::numeric_limits<double>::max();
  MaskOf<BatchLanes> finite = zero < splat<BatchLanes>(1.0);
  Vec3* cell_force[kBatchCells];
  const int* cell_index[kBatchCells];
  for (int j = 0; j < kBatchCells; ++j) {
    cell_force[j] = m_f.data() + m_cells[batch.cell[j]].node_begin;
    cell_index[j] = m_index.data() + m_cells[batch.cell[j]].node_begin;
  }
  for (int k = 0; k < n_nodes; ++k) {
    BatchLanes fk[3];
    for (int d = 0; d < 3; ++d) {
      fk[d] = f[k].c[d] + volume_factor * nsum[k].c[d];
      finite &= (fk[d] <= largest) & (fk[d] >= -largest);
    }
    for (int j = 0; j < kBatchCells; ++j)
      cell_force[j][k] = Vec3(fk[0][j], fk[1][j], fk[2][j]);
    if (write_normals) {
      const BatchLanes* n = nsum[k].c;
      const BatchLanes len = sqrt_lanes(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const BatchLanes scale = len > zero ? sign / len : sign;
      for (int j = 0; j < kBatchCells; ++j)
        p.normal[cell_index[j][k]] =
            Vec3(n[0][j] * scale[j], n[1][j] * scale[j], n[2][j] * scale[j]);
    }
  }
  return !any_lane(~finite);
}

void FusedMembranePlan::form_batches() {
  // cells with one copy of the tables (the same ranges) and as many nodes,
  // in order of their first cell
  m_batches.clear();
  m_single_cells.clear();
  std::vector<std::vector<int>> kinds;
  for (std::size_t c = 0; c < m_cells.size(); ++c) {
    const CellRange& r = m_cells[c];
    auto same = [&](const std::vector<int>& kind) {
      const CellRange& t = m_cells[kind.front()];
      return t.triangle_begin == r.triangle_begin && t.triangle_end == r.triangle_end &&
             t.edge_begin == r.edge_begin && t.edge_end == r.edge_end && t.origin == r.origin &&
             t.node_end - t.node_begin == r.node_end - r.node_begin;
    };
    auto kind = std::find_if(kinds.begin(), kinds.end(), same);
    if (kind == kinds.end())
      kinds.push_back({static_cast<int>(c)});
    else
      kind->push_back(static_cast<int>(c));
  }
  for (const auto& kind : kinds) {
    std::size_t i = 0;
    for (; i + kBatchCells <= kind.size(); i += kBatchCells) {
      Batch b;
      std::copy(kind.begin() + i, kind.begin() + i + kBatchCells, b.cell);
      m_batches.push_back(b);
    }
    m_single_cells.insert(m_single_cells.end(), kind.begin() + i, kind.end());
  }
}

bool FusedMembranePlan::run(const OifLocalForces& local_ia, const BondGroup& local,
                            const OifGlobalForces& global_ia, const BondGroup& global,
                            bool write_normals, ParticleStore& p, const BoxGeometry& box) {
  const GroupKey local_key(local, p, kind_local), global_key(global, p, kind_global);
  if (!(local_key == m_local_key) || !(global_key == m_global_key)) {
    m_local_key = local_key;
    m_global_key = global_key;
    m_usable = build(local, global, p);
    ++m_n_builds;
  }
  if (!m_usable)
    return false;
  const bool velocities = local_ia.kvisc != 0.0;
  // a mol_id changed: the cells regroup (or the groups no longer pair up)
  auto rebuild_and_run = [&] {
    m_usable = build(local, global, p);
    ++m_n_builds;
    return m_usable && run(local_ia, local, global_ia, global, write_normals, p, box);
  };
  for (const Batch& batch : m_batches) {
    bool regroup = false;
    if (!gather_batch(batch, p, box, velocities, &regroup))
      return regroup && rebuild_and_run();
    if (!evaluate_batch(batch, local_ia, global_ia, write_normals, p))
      return false;
  }
  for (const int cell : m_single_cells) {
    bool regroup = false;
    if (!gather_cell(cell, p, box, velocities, &regroup))
      return regroup && rebuild_and_run();
    if (!evaluate_cell(cell, local_ia, global_ia, write_normals, p))
      return false;
  }
  // the forces in one pass over the particles once every cell succeeded (a
  // cell that declines hands the whole group to the separate plans or the
  // generic loop, which add them all)
  for (std::size_t s = 0; s < m_index.size(); ++s)
    p.force[m_index[s]] += m_f[s];
  return true;
}

} // namespace pyoif::oif
