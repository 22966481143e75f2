// Fused stream-and-collide over runs of fluid nodes, in place with the AA
// pattern (population_storage.hpp). This is where a PyOIF run spends its
// time.
//
// Collision in population space, equivalent to the moment-space MRT of
// Duenweg, Schiller & Ladd, Phys. Rev. E 76, 036704 (2007) (DSL) with
// Guo-type forcing (DSL sec. III.E; Guo, Zheng & Shi, PRE 65, 046308 (2002)):
// with u = (j + F/2) / rho, Pi the second moment and
//   n+ = even part of f - f_eq,  n- = odd part of f - f_eq(j),
// the post-collision populations are
//   f+* = f_eq+ + l_e n+ + w/(2 c_s^4) H:B,   H = c c - c_s^2 I,
//   B   = (l_s - l_e) Pi_neq,dev + (l_b - l_e) Pi_neq,iso + S,
//   S   = (1 + l_s)/2 (uF + Fu)_dev + (1 + l_b)/2 (uF + Fu)_iso,
//   f-* = l_o n- + w c.((1 - l_o) j + F) / c_s^2 ... i.e. j* = j + F,
// l = 1 - omega of the shear, bulk, even-ghost and odd-ghost modes. The
// Hermite projection w/(2 c_s^4) H:A is the w-orthogonal projection on the
// stress modes, so this relaxes each DSL mode group at its own rate while
// costing about as much as BGK. It is written per opposite pair (q, q+1):
// f+ = (f_q + f_q+1)/2 and f- = (f_q - f_q+1)/2.
#include "lb/collide_stream.hpp"

#include "utils/random.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "lb/lattice_codegen.hpp" // last: it applies to this file's functions

namespace pyoif::lb {

using namespace d3q19;

namespace {

/** Speed limit: |u| >= c_s (lattice) means the run has left the model's range. */
constexpr double u2_limit = 1.0 / 3.0;

struct NodeResult {
  double rho, u2;
};

/** A node the model cannot go on from: a density that is not positive or not
 *  finite (an infinite one has zero speed), a speed at the sound speed or
 *  not a number. Branch-free: it is evaluated for every node. */
inline bool out_of_range(const NodeResult& res) {
  return !(res.rho > 0.0) | !(res.rho <= std::numeric_limits<double>::max()) | !(res.u2 < u2_limit);
}

/** acc + a x for a velocity component a in {-1, 0, 1} known at compile time.
 *  A zero term is dropped here because IEEE arithmetic does not let the
 *  compiler fold acc + 0 * x away (x could be inf or NaN); dropping it leaves
 *  every finite result bit for bit unchanged. */
template <int a> __attribute__((always_inline)) inline double add_scaled(double acc, double x) {
  if constexpr (a == 0)
    return acc;
  else if constexpr (a > 0)
    return acc + x;
  else
    return acc - x;
}

/** a x + b y + c z for compile-time a, b, c in {-1, 0, 1}, not all zero;
 *  summed in the order x, y, z with the zero terms dropped. */
template <int a, int b, int cc>
__attribute__((always_inline)) inline double dot(double x, double y, double z) {
  static_assert(a != 0 || b != 0 || cc != 0, "at least one non-zero coefficient");
  if constexpr (a != 0)
    return add_scaled<cc>(add_scaled<b>(a > 0 ? x : -x, y), z);
  else if constexpr (b != 0)
    return add_scaled<cc>(b > 0 ? y : -y, z);
  else
    return cc > 0 ? z : -z;
}

/** body(std::integral_constant<int, k>) for the opposite pairs k = 0..8, so
 *  that the velocity components are compile-time constants in the body. */
template <typename Body, int... K>
__attribute__((always_inline)) inline void for_each_pair_impl(Body&& body,
                                                              std::integer_sequence<int, K...>) {
  (body(std::integral_constant<int, K>{}), ...);
}
template <typename Body> __attribute__((always_inline)) inline void for_each_pair(Body&& body) {
  for_each_pair_impl(body, std::make_integer_sequence<int, n_pairs>{});
}

/** Collision of one node; f in, out post-collision (same q order).
 *  even_ghosts_relaxed: the even ghost modes go to equilibrium in one update
 *  (lambda even = 0, both MRTs), which drops their terms at compile time; the
 *  odd part always relaxes at l.odd (0 in ESPResSo's MRT: the same result).
 *  The sums run over the non-zero velocity components only (D3Q19 has 45 of
 *  its 81 c_a c_b products zero), in the order of the plain sums over k. */
template <bool even_ghosts_relaxed>
__attribute__((always_inline)) inline NodeResult collide(const double* f, const double* F,
                                                         const Relaxation& l, double* out) {
  double s[n_pairs], d[n_pairs];
#pragma GCC unroll 9
  for (int k = 0; k < n_pairs; ++k) {
    s[k] = f[2 * k + 1] + f[2 * k + 2];
    d[k] = f[2 * k + 1] - f[2 * k + 2];
  }
  double rho = f[0], j[3] = {0.0, 0.0, 0.0};
  double pi_xx = 0.0, pi_yy = 0.0, pi_zz = 0.0, pi_xy = 0.0, pi_xz = 0.0, pi_yz = 0.0;
  for_each_pair([&](auto K) __attribute__((always_inline)) {
    constexpr int k = decltype(K)::value;
    constexpr int cx = c[2 * k + 1][0], cy = c[2 * k + 1][1], cz = c[2 * k + 1][2];
    rho += s[k];
    j[0] = add_scaled<cx>(j[0], d[k]);
    j[1] = add_scaled<cy>(j[1], d[k]);
    j[2] = add_scaled<cz>(j[2], d[k]);
    pi_xx = add_scaled<cx * cx>(pi_xx, s[k]);
    pi_yy = add_scaled<cy * cy>(pi_yy, s[k]);
    pi_zz = add_scaled<cz * cz>(pi_zz, s[k]);
    pi_xy = add_scaled<cx * cy>(pi_xy, s[k]);
    pi_xz = add_scaled<cx * cz>(pi_xz, s[k]);
    pi_yz = add_scaled<cy * cz>(pi_yz, s[k]);
  });
  const double inv_rho = 1.0 / rho;
  const double u[3] = {(j[0] + 0.5 * F[0]) * inv_rho, (j[1] + 0.5 * F[1]) * inv_rho,
                       (j[2] + 0.5 * F[2]) * inv_rho};
  const double u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  // non-equilibrium stress: Pi - rho c_s^2 I - rho u u
  const double third_rho = rho * (1.0 / 3.0);
  const double n_xx = pi_xx - third_rho - rho * u[0] * u[0];
  const double n_yy = pi_yy - third_rho - rho * u[1] * u[1];
  const double n_zz = pi_zz - third_rho - rho * u[2] * u[2];
  const double n_xy = pi_xy - rho * u[0] * u[1];
  const double n_xz = pi_xz - rho * u[0] * u[2];
  const double n_yz = pi_yz - rho * u[1] * u[2];
  const double n_iso = (n_xx + n_yy + n_zz) * (1.0 / 3.0);
  const double uf_iso = (2.0 / 3.0) * (u[0] * F[0] + u[1] * F[1] + u[2] * F[2]);
  const double shear_src = 0.5 * (1.0 + l.shear), bulk_src = 0.5 * (1.0 + l.bulk);
  const double l_even = even_ghosts_relaxed ? 0.0 : l.even;
  const double l_odd = l.odd;
  const double ds = l.shear - l_even, db = l.bulk - l_even;
  const double iso = db * n_iso + bulk_src * uf_iso;
  const double b_xx = ds * (n_xx - n_iso) + shear_src * (2.0 * u[0] * F[0] - uf_iso) + iso;
  const double b_yy = ds * (n_yy - n_iso) + shear_src * (2.0 * u[1] * F[1] - uf_iso) + iso;
  const double b_zz = ds * (n_zz - n_iso) + shear_src * (2.0 * u[2] * F[2] - uf_iso) + iso;
  const double b_xy = ds * n_xy + shear_src * (u[0] * F[1] + u[1] * F[0]);
  const double b_xz = ds * n_xz + shear_src * (u[0] * F[2] + u[2] * F[0]);
  const double b_yz = ds * n_yz + shear_src * (u[1] * F[2] + u[2] * F[1]);
  const double tr_b_third = (b_xx + b_yy + b_zz) * (1.0 / 3.0);
  const double one_minus_le = 1.0 - l_even;
  const double jj[3] = {(1.0 - l_odd) * j[0] + F[0], (1.0 - l_odd) * j[1] + F[1],
                        (1.0 - l_odd) * j[2] + F[2]};
  const double eq_common = 1.0 - 1.5 * u2;
  double out0 = one_minus_le * w[0] * rho * eq_common;
  if constexpr (!even_ghosts_relaxed)
    out0 += l_even * f[0];
  out[0] = out0 - w[0] * 4.5 * tr_b_third;
  for_each_pair([&](auto K) __attribute__((always_inline)) {
    constexpr int k = decltype(K)::value;
    constexpr int cx = c[2 * k + 1][0], cy = c[2 * k + 1][1], cz = c[2 * k + 1][2];
    constexpr double wk = w[2 * k + 1];
    const double cu = dot<cx, cy, cz>(u[0], u[1], u[2]);
    double cbc = dot<cx * cx, cy * cy, cz * cz>(b_xx, b_yy, b_zz);
    if constexpr (cx * cy != 0 || cx * cz != 0 || cy * cz != 0)
      cbc += 2.0 * dot<cx * cy, cx * cz, cy * cz>(b_xy, b_xz, b_yz);
    double even = one_minus_le * wk * rho * (eq_common + 4.5 * cu * cu);
    if constexpr (!even_ghosts_relaxed)
      even += 0.5 * l_even * s[k];
    even += wk * 4.5 * (cbc - tr_b_third);
    const double odd = 0.5 * l_odd * d[k] + 3.0 * wk * dot<cx, cy, cz>(jj[0], jj[1], jj[2]);
    out[2 * k + 1] = even + odd;
    out[2 * k + 2] = even - odd;
  });
  return {rho, u2};
}

/** Density and speed^2 of a node in the arithmetic type T. */
template <typename T> struct NodeResultOf { T rho, u2; };

template <typename T> inline bool out_of_range(const NodeResultOf<T>& res) {
  return !(res.rho > T(0)) | !(res.rho <= std::numeric_limits<T>::max()) | !(res.u2 < T(u2_limit));
}

/** The relaxation factors in the arithmetic type T. */
template <typename T> struct RelaxationOf {
  T shear, bulk, even, odd;
  explicit RelaxationOf(const Relaxation& l)
      : shear(T(l.shear)), bulk(T(l.bulk)), even(T(l.even)), odd(T(l.odd)) {}
};

/** collide() on the deviations g_q = f_q - w_q rho0 from the rest state at
 *  the reference density rho0 (single precision's storage, lb_fluid.hpp),
 *  in the arithmetic type T. Skordos, Phys. Rev. E 48, 4823 (1993): with
 *  f_q = w_q rho0 + g_q every moment splits into the rest state's and the
 *  deviations' (sum_q w_q = 1, sum_q w_q c_q = 0, sum_q w_q c_q c_q = I/3):
 *    rho = rho0 + drho, drho = sum g;  j = sum c g;
 *    Pi = rho0/3 I + Pi_g, Pi_g = sum c c g;
 *    Pi_neq = Pi - rho/3 I - rho u u = Pi_g - drho/3 I - rho u u,
 *  and the post-collision deviation g* = f* - w rho0 follows from collide()'s
 *  f* with f_eq - w rho0 = w (drho + rho (3 c.u + 9/2 (c.u)^2 - 3/2 u^2)):
 *    g+* = (1 - l_e) w (drho + rho (9/2 (c.u)^2 - 3/2 u^2)) + l_e g+
 *          + w/(2 c_s^4) H:B   (l_e w rho0 of the ghost term cancels),
 *    g-* = f-* (the rest state has no odd part).
 *  Every term is then of the size of the deviations, not of w rho0, so the
 *  rounding of T (float: 6e-8 relative) falls on the small parts only. */
template <typename T, bool even_ghosts_relaxed>
__attribute__((always_inline)) inline NodeResultOf<T>
collide_deviation(const T* g, const T* F, const RelaxationOf<T>& l, T rho0, T* out) {
  T s[n_pairs], d[n_pairs];
#pragma GCC unroll 9
  for (int k = 0; k < n_pairs; ++k) {
    s[k] = g[2 * k + 1] + g[2 * k + 2];
    d[k] = g[2 * k + 1] - g[2 * k + 2];
  }
  T drho = g[0], j[3] = {T(0), T(0), T(0)};
  T pi_xx = T(0), pi_yy = T(0), pi_zz = T(0), pi_xy = T(0), pi_xz = T(0), pi_yz = T(0);
  for_each_pair([&](auto K) __attribute__((always_inline)) {
    constexpr int k = decltype(K)::value;
    constexpr int cx = c[2 * k + 1][0], cy = c[2 * k + 1][1], cz = c[2 * k + 1][2];
    drho += s[k];
    if constexpr (cx != 0)
      j[0] += T(cx) * d[k];
    if constexpr (cy != 0)
      j[1] += T(cy) * d[k];
    if constexpr (cz != 0)
      j[2] += T(cz) * d[k];
    if constexpr (cx != 0)
      pi_xx += s[k];
    if constexpr (cy != 0)
      pi_yy += s[k];
    if constexpr (cz != 0)
      pi_zz += s[k];
    if constexpr (cx * cy != 0)
      pi_xy += T(cx * cy) * s[k];
    if constexpr (cx * cz != 0)
      pi_xz += T(cx * cz) * s[k];
    if constexpr (cy * cz != 0)
      pi_yz += T(cy * cz) * s[k];
  });
  const T rho = rho0 + drho;
  const T inv_rho = T(1) / rho;
  const T u[3] = {(j[0] + T(0.5) * F[0]) * inv_rho, (j[1] + T(0.5) * F[1]) * inv_rho,
                  (j[2] + T(0.5) * F[2]) * inv_rho};
  const T u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
  // non-equilibrium stress: Pi_g - drho c_s^2 I - rho u u
  const T third_drho = drho * T(1.0 / 3.0);
  const T n_xx = pi_xx - third_drho - rho * u[0] * u[0];
  const T n_yy = pi_yy - third_drho - rho * u[1] * u[1];
  const T n_zz = pi_zz - third_drho - rho * u[2] * u[2];
  const T n_xy = pi_xy - rho * u[0] * u[1];
  const T n_xz = pi_xz - rho * u[0] * u[2];
  const T n_yz = pi_yz - rho * u[1] * u[2];
  const T n_iso = (n_xx + n_yy + n_zz) * T(1.0 / 3.0);
  const T uf_iso = T(2.0 / 3.0) * (u[0] * F[0] + u[1] * F[1] + u[2] * F[2]);
  const T shear_src = T(0.5) * (T(1) + l.shear), bulk_src = T(0.5) * (T(1) + l.bulk);
  const T l_even = even_ghosts_relaxed ? T(0) : l.even;
  const T l_odd = l.odd;
  const T ds = l.shear - l_even, db = l.bulk - l_even;
  const T iso = db * n_iso + bulk_src * uf_iso;
  const T b_xx = ds * (n_xx - n_iso) + shear_src * (T(2) * u[0] * F[0] - uf_iso) + iso;
  const T b_yy = ds * (n_yy - n_iso) + shear_src * (T(2) * u[1] * F[1] - uf_iso) + iso;
  const T b_zz = ds * (n_zz - n_iso) + shear_src * (T(2) * u[2] * F[2] - uf_iso) + iso;
  const T b_xy = ds * n_xy + shear_src * (u[0] * F[1] + u[1] * F[0]);
  const T b_xz = ds * n_xz + shear_src * (u[0] * F[2] + u[2] * F[0]);
  const T b_yz = ds * n_yz + shear_src * (u[1] * F[2] + u[2] * F[1]);
  const T tr_b_third = (b_xx + b_yy + b_zz) * T(1.0 / 3.0);
  const T one_minus_le = T(1) - l_even;
  const T jj[3] = {(T(1) - l_odd) * j[0] + F[0], (T(1) - l_odd) * j[1] + F[1],
                   (T(1) - l_odd) * j[2] + F[2]};
  const T rest_eq = drho - T(1.5) * rho * u2; // (f_eq - w rho0) / w without the c.u terms
  T out0 = one_minus_le * T(w[0]) * rest_eq;
  if constexpr (!even_ghosts_relaxed)
    out0 += l_even * g[0];
  out[0] = out0 - T(w[0] * 4.5) * tr_b_third;
  for_each_pair([&](auto K) __attribute__((always_inline)) {
    constexpr int k = decltype(K)::value;
    constexpr int cx = c[2 * k + 1][0], cy = c[2 * k + 1][1], cz = c[2 * k + 1][2];
    constexpr double wk = w[2 * k + 1];
    T cu = T(0), cbc = T(0), cj = T(0);
    if constexpr (cx != 0) {
      cu += T(cx) * u[0];
      cbc += b_xx;
      cj += T(cx) * jj[0];
    }
    if constexpr (cy != 0) {
      cu += T(cy) * u[1];
      cbc += b_yy;
      cj += T(cy) * jj[1];
    }
    if constexpr (cz != 0) {
      cu += T(cz) * u[2];
      cbc += b_zz;
      cj += T(cz) * jj[2];
    }
    if constexpr (cx * cy != 0)
      cbc += T(2 * cx * cy) * b_xy;
    if constexpr (cx * cz != 0)
      cbc += T(2 * cx * cz) * b_xz;
    if constexpr (cy * cz != 0)
      cbc += T(2 * cy * cz) * b_yz;
    T even = one_minus_le * T(wk) * (rest_eq + T(4.5) * rho * cu * cu);
    if constexpr (!even_ghosts_relaxed)
      even += T(0.5) * l_even * s[k];
    even += T(wk * 4.5) * (cbc - tr_b_third);
    const T odd = T(0.5) * l_odd * d[k] + T(3.0 * wk) * cj;
    out[2 * k + 1] = even + odd;
    out[2 * k + 2] = even - odd;
  });
  return {rho, u2};
}

/** Padded (x, y, z) of a padded node index. */
inline Vec3i padded_coordinates(const Vec3i& pad, std::size_t n) {
  const std::size_t px = static_cast<std::size_t>(pad[0]), py = static_cast<std::size_t>(pad[1]);
  return Vec3i(static_cast<int>(n % px), static_cast<int>((n / px) % py),
               static_cast<int>(n / (px * py)));
}

/** The field marks of the padded nodes n .. n + 31 (bit i: n + i). */
inline std::uint32_t field_valid_bits32(const std::uint64_t* marks, std::size_t n) {
  const std::size_t word = n >> 6;
  const unsigned shift = static_cast<unsigned>(n & 63);
  std::uint64_t bits = marks[word] >> shift;
  if (shift > 32) // the block reaches into the next word (one spare word at the end)
    bits |= marks[word + 1] << (64 - shift);
  return static_cast<std::uint32_t>(bits);
}

template <typename Real, bool thermal, bool with_field, bool even_ghosts_relaxed, bool even>
bool collide_stream_run(const SweepParams& s, const FluidRun& r, const FluidRun* next_run, Real* f,
                        BadNode& bad_node) {
  // AA pattern (see population_storage.hpp): population q of node n is read at
  // f[read[q] + n] and its post-collision value written to f[write[q] + n];
  // within one update each node reads and writes the same 19 places
  // (write[q] = read[-q]), so the update is in place and race-free. The read
  // places are those of the layout the update starts from (SweepParams::read).
  const std::ptrdiff_t* const read = s.read;
  std::ptrdiff_t write[Q];
  for (int q = 0; q < Q; ++q)
    write[q] = read[opposite(q)];
  const Relaxation l = s.relaxation[r.relaxation];
  const double fx = s.ext_force[0], fy = s.ext_force[1], fz = s.ext_force[2];
  // the coupling's force field, read at the nodes marked valid (SweepParams)
  const double* __restrict g = with_field ? s.field : nullptr;
  const std::size_t begin = r.start, end = r.start + r.length;
  // a node out of range: its moments, recomputed from the populations that
  // are still unwritten (the caller throws, the update is abandoned)
  // (in double, also in single precision: it is what the report shows)
  constexpr bool deviations = std::is_same_v<Real, float>; // see lb_fluid.hpp
  const RelaxationOf<double> l_double(l);
  // one node's collision in double, of full populations or (single
  // precision) of their deviations from rest
  auto collide_in_double = [&](const double* fn, const double* F, double* out) -> NodeResult {
    if constexpr (deviations) {
      const NodeResultOf<double> dev =
          collide_deviation<double, false>(fn, F, l_double, s.density, out);
      return {dev.rho, dev.u2};
    } else {
      return collide<false>(fn, F, l, out);
    }
  };
  auto record_bad = [&](std::size_t n, const auto* F_in) {
    double fn[Q], out[Q], F[3] = {double(F_in[0]), double(F_in[1]), double(F_in[2])};
    for (int q = 0; q < Q; ++q)
      fn[q] = f[read[q] + static_cast<std::ptrdiff_t>(n)];
    const NodeResult res = collide_in_double(fn, F, out);
    bad_node = {n, res.rho, std::sqrt(res.u2)};
    return true;
  };
  if constexpr (!thermal) {
    // Blocks of nodes: the collision runs vectorised over a block reading the
    // 19 streams directly and writing an L1-resident buffer; the block is
    // checked (density, speed) before anything is written back, so an
    // unstable node is reported with its pre-collision state. The write-back
    // goes to the lines just read (still in L1/L2).
    constexpr int block = 32;
    static_assert(block == 32, "field_valid_bits32 gives the field's marks of 32 nodes");
    // the hardware prefetcher does not keep 19 streams far enough ahead:
    // request the rows `distance` nodes ahead into L2 (in the next run when
    // this one ends; runs are in memory order), one request per cache line;
    // 768 bytes ahead per stream in either precision
    constexpr std::size_t distance = 96 * sizeof(double) / sizeof(Real);
    constexpr int per_line = 64 / sizeof(Real);
    // post-collision values, already rounded to the stored type; the
    // arithmetic: double on full populations, or float on the deviations
    using Arith = Real;
    const RelaxationOf<float> l_float(l);
    const float rho0_float = static_cast<float>(s.density);
    alignas(64) Real fout[Q][block];
    alignas(64) Arith force[3][block];
    for (std::size_t b0 = begin; b0 < end; b0 += block) {
      const int len = static_cast<int>(std::min<std::size_t>(block, end - b0));
      std::size_t ahead = b0 + distance;
      if (ahead >= end)
        ahead = next_run ? next_run->start + (ahead - end) : b0;
      for (int q = 0; q < Q; ++q)
        for (int p = 0; p < block; p += per_line)
          __builtin_prefetch(f + read[q] + static_cast<std::ptrdiff_t>(ahead + p), 1, 2);
      for (int i = 0; i < len; ++i) {
        force[0][i] = static_cast<Arith>(fx);
        force[1][i] = static_cast<Arith>(fy);
        force[2][i] = static_cast<Arith>(fz);
      }
      // only nodes that received a deposit: a block without any reads nothing
      if (with_field) {
        std::uint32_t valid = field_valid_bits32(s.field_valid, b0);
        if (len < block)
          valid &= (std::uint32_t{1} << len) - 1u;
        // the marked entries alone: the coupling has just written them (in
        // cache), the block's others are stale and may have left the cache
        const double* __restrict gb = g + 3 * b0;
        for (std::uint32_t bits = valid; bits; bits &= bits - 1) {
          const int i = __builtin_ctz(bits);
          force[0][i] = static_cast<Arith>(fx + gb[3 * i]);
          force[1][i] = static_cast<Arith>(fy + gb[3 * i + 1]);
          force[2][i] = static_cast<Arith>(fz + gb[3 * i + 2]);
        }
      }
      const Real* in[Q];
      for (int q = 0; q < Q; ++q)
        in[q] = f + read[q] + static_cast<std::ptrdiff_t>(b0);
      int bad = 0;
      // one node's collision in the arithmetic of the storage (float
      // deviations from rest, or double populations); true when out of range
      auto collide_node = [&](const Arith* fn, const Arith* F, Arith* out)
          __attribute__((always_inline)) {
        if constexpr (deviations)
          return out_of_range(
              collide_deviation<float, even_ghosts_relaxed>(fn, F, l_float, rho0_float, out));
        else
          return out_of_range(collide<even_ghosts_relaxed>(fn, F, l, out));
      };
#pragma GCC ivdep
      for (int i = 0; i < len; ++i) {
        Arith fn[Q], out[Q];
#pragma GCC unroll 19
        for (int q = 0; q < Q; ++q)
          fn[q] = in[q][i];
        const Arith F[3] = {force[0][i], force[1][i], force[2][i]};
        const bool out_of = collide_node(fn, F, out);
#pragma GCC unroll 19
        for (int q = 0; q < Q; ++q)
          fout[q][i] = static_cast<Real>(out[q]);
        bad |= out_of;
      }
      if (bad) {
        for (int i = 0; i < len; ++i) {
          const Arith F[3] = {force[0][i], force[1][i], force[2][i]};
          Arith fn[Q], out[Q];
          for (int q = 0; q < Q; ++q)
            fn[q] = in[q][i];
          if (collide_node(fn, F, out))
            return record_bad(b0 + i, F);
        }
        return record_bad(b0, force[0]); // not reached: the block had a bad node
      }
      for (int q = 0; q < Q; ++q) {
        Real* __restrict dst = f + write[q] + static_cast<std::ptrdiff_t>(b0);
        const Real* __restrict src = fout[q];
        for (int i = 0; i < len; ++i)
          dst[i] = src[i];
      }
    }
  } else {
    const std::uint64_t counter = s.update;
    for (std::size_t n = begin; n < end; ++n) {
      double fn[Q], out[Q];
      for (int q = 0; q < Q; ++q)
        fn[q] = f[read[q] + static_cast<std::ptrdiff_t>(n)];
      double F[3] = {fx, fy, fz};
      if (with_field && ((s.field_valid[n >> 6] >> (n & 63)) & 1u))
        for (int d = 0; d < 3; ++d)
          F[d] += g[3 * n + d];
      // (single precision: the deviations collided in double; the noise
      // goes to the stress and ghost modes, which the rest state lacks)
      const NodeResult res = collide_in_double(fn, F, out);
      if (out_of_range(res))
        return record_bad(n, F);
      // fluctuating MRT (DSL eq. 66): noise on the stress and ghost modes,
      // variance rho kT / c_s^2 * b_m (1 - lambda_m^2), projected back with
      // the w-weighted basis; mass and momentum untouched
      // keyed by the global node: the same noise on any decomposition
      const Vec3i node_g = padded_coordinates(s.pad, n) - Vec3i::Ones() + s.origin;
      const random::Key key{s.seed, static_cast<std::uint64_t>(random::Stream::lb_fluid), counter,
                            (static_cast<std::uint64_t>(node_g[0]) * s.global[1] + node_g[1]) *
                                    s.global[2] +
                                node_g[2]};
      double amp[Q];
      for (int m = 4; m < Q; ++m)
        amp[m] = std::sqrt(res.rho * s.noise_factor[m]) * random::normal(key, m);
      for (int q = 0; q < Q; ++q) {
        double sum = 0.0;
        for (int m = 4; m < Q; ++m)
          sum += (*s.basis)[m][q] * amp[m];
        out[q] += w[q] * sum;
      }
      for (int q = 0; q < Q; ++q)
        f[write[q] + static_cast<std::ptrdiff_t>(n)] = static_cast<Real>(out[q]);
    }
  }
  return false;
}

} // namespace

template <typename Real>
std::size_t collide_stream(const SweepParams& s, const std::vector<FluidRun>& runs, Real* f,
                           int threads, BadNode& bad_node) {
  const bool thermal = s.noise_factor != nullptr;
  const bool field = s.field != nullptr;
  const bool relaxed = s.even_ghosts_relaxed;
  const bool even = s.even;
  const long n_runs = static_cast<long>(runs.size());
  long first_bad = n_runs;
  // one instantiation per combination, chosen outside the node loops
  auto update = [&](long i, BadNode& b) {
    const FluidRun& r = runs[static_cast<std::size_t>(i)];
    const FluidRun* next = i + 1 < n_runs ? &r + 1 : nullptr;
    if (thermal) {
      if (even)
        return field ? collide_stream_run<Real, true, true, false, true>(s, r, next, f, b)
                     : collide_stream_run<Real, true, false, false, true>(s, r, next, f, b);
      return field ? collide_stream_run<Real, true, true, false, false>(s, r, next, f, b)
                   : collide_stream_run<Real, true, false, false, false>(s, r, next, f, b);
    }
    if (relaxed) {
      if (even)
        return field ? collide_stream_run<Real, false, true, true, true>(s, r, next, f, b)
                     : collide_stream_run<Real, false, false, true, true>(s, r, next, f, b);
      return field ? collide_stream_run<Real, false, true, true, false>(s, r, next, f, b)
                   : collide_stream_run<Real, false, false, true, false>(s, r, next, f, b);
    }
    if (even)
      return field ? collide_stream_run<Real, false, true, false, true>(s, r, next, f, b)
                   : collide_stream_run<Real, false, false, false, true>(s, r, next, f, b);
    return field ? collide_stream_run<Real, false, true, false, false>(s, r, next, f, b)
                 : collide_stream_run<Real, false, false, false, false>(s, r, next, f, b);
  };
  (void)threads;
#ifdef PYOIF_WITH_OPENMP
#pragma omp parallel for schedule(static) num_threads(threads)
#endif
  for (long i = 0; i < n_runs; ++i) {
    BadNode b;
    if (update(i, b)) {
#ifdef PYOIF_WITH_OPENMP
#pragma omp critical(pyoif_lb_bad_node)
#endif
      if (i < first_bad) {
        first_bad = i;
        bad_node = b;
      }
    }
  }
  return static_cast<std::size_t>(first_bad);
}

template std::size_t collide_stream<float>(const SweepParams&, const std::vector<FluidRun>&, float*,
                                           int, BadNode&);
template std::size_t collide_stream<double>(const SweepParams&, const std::vector<FluidRun>&,
                                            double*, int, BadNode&);

} // namespace pyoif::lb
