// The scalar types of the membrane kernels: plain double (one cell) or
// Lanes, a vector of four doubles (GCC/Clang vector extension) holding one
// value of four cells, one cell per lane. Every kernel of the membrane terms
// is a template over T and uses only the operations below, so one source
// serves both and the two give the same result bit for bit (the same IEEE
// operations in the same order, lane by lane).
#pragma once

#include <cmath>
#include <type_traits>

#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace pyoif::membrane {

/** Four doubles, one per cell of a batch. Four: eight (512-bit vectors) made
 *  the membrane pass only 2-7 % faster per cell at 8-60 cells, since its
 *  loops are bound by the number of vector operations per lane, and left
 *  more cells to the one-cell pass (doc/performance.md, tenth round). */
using Lanes = double __attribute__((vector_size(32)));

template <class T> constexpr int lanes_of = static_cast<int>(sizeof(T) / sizeof(double));

/** A comparison's result: bool for double, a vector of -1/0 for Lanes. */
template <class T> using Mask = decltype(T{} > T{});

/** x in every lane. */
template <class T> inline T splat(double x) {
  return T{} + x;
}

/** Lane j of x (x itself for double). */
template <class T> inline double lane(const T& x, int j) {
  if constexpr (std::is_same_v<T, double>) {
    (void)j;
    return x;
  } else {
    return x[j];
  }
}
template <class T> inline void set_lane(T& x, int j, double value) {
  if constexpr (std::is_same_v<T, double>) {
    (void)j;
    x = value;
  } else {
    x[j] = value;
  }
}

/** Lane-wise square root, correctly rounded as std::sqrt. */
template <class T> inline T sqrt_of(T x) {
  if constexpr (std::is_same_v<T, double>) {
    return std::sqrt(x);
  } else {
#if defined(__AVX__)
    return reinterpret_cast<T>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(x)));
#else
    for (int j = 0; j < lanes_of<T>; ++j)
      x[j] = std::sqrt(x[j]);
    return x;
#endif
  }
}

template <class T> inline T abs_of(T x) {
  if constexpr (std::is_same_v<T, double>)
    return std::abs(x);
  else
    return x < T{} ? -x : x;
}

/** !(x > 0) lane-wise: true for zero, negative and NaN. */
template <class T> inline Mask<T> not_positive(T x) {
  if constexpr (std::is_same_v<T, double>)
    return !(x > 0.0);
  else
    return ~(x > T{});
}

/** !(|x| <= largest finite) lane-wise: true for inf and NaN. */
template <class T> inline Mask<T> not_finite(T x) {
  if constexpr (std::is_same_v<T, double>)
    return !(std::abs(x) <= 1.7976931348623157e308);
  else
    return ~(abs_of(x) <= 1.7976931348623157e308);
}

/** m ? a : b lane-wise. */
template <class T> inline T select(Mask<T> m, T a, T b) {
  return m ? a : b;
}

template <class T> inline bool any_lane(Mask<T> m) {
  if constexpr (std::is_same_v<T, double>) {
    return m;
  } else {
    long long any = 0;
    for (int j = 0; j < lanes_of<T>; ++j)
      any |= m[j];
    return any != 0;
  }
}
template <class T> inline bool lane_set(Mask<T> m, int j) {
  if constexpr (std::is_same_v<T, double>) {
    (void)j;
    return m;
  } else {
    return m[j] != 0;
  }
}
template <class T> inline Mask<T> no_lane() {
  return T{} > T{};
}

/** Four quotients from one division: inv[k] = 1 / den[k]. r = 1 / (d0 d1 d2
 *  d3), and each reciprocal is r times the other three denominators. The
 *  divider, not the arithmetic, bounds the membrane's edge pass (one division
 *  instead of four: -4.6 % in an A/B without fluid, doc/performance.md). The
 *  denominators must stay far from overflow together (edge lengths, areas
 *  and cosines of a membrane are O(1) in the units of the mesh). */
template <class T> struct FourReciprocals {
  T inv[4];
  explicit FourReciprocals(const T (&den)[4]) {
    const T d01 = den[0] * den[1], d23 = den[2] * den[3];
    const T r = 1.0 / (d01 * d23);
    inv[0] = r * den[1] * d23;
    inv[1] = r * den[0] * d23;
    inv[2] = r * d01 * den[3];
    inv[3] = r * d01 * den[2];
  }
};

} // namespace pyoif::membrane
