// Counter-based random numbers: a value is a pure function of
// (seed, stream, counter, key), so runs are reproducible, restartable from a
// checkpoint without hidden RNG state, and independent of the rank count.
// Mixing: SplitMix64 finaliser (Steele, Lea & Flood 2014).
#pragma once

#include <cmath>
#include <cstdint>

namespace pyoif::random {

inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/** Stream identifiers, so that different consumers of one seed never share numbers. */
enum class Stream : std::uint64_t { langevin = 1, lb_coupling = 2, lb_fluid = 3, seeding = 4, packing = 5 };

struct Key {
  std::uint64_t seed, stream, counter, key;
};

inline std::uint64_t hash(const Key& k, std::uint64_t index) {
  std::uint64_t h = mix64(k.seed ^ mix64(k.stream * 0x632be59bd9b4e019ULL));
  h = mix64(h ^ k.counter);
  h = mix64(h ^ k.key);
  return mix64(h ^ index);
}

/** Uniform in (0, 1), never exactly 0 or 1. */
inline double uniform(const Key& k, std::uint64_t index) {
  return (static_cast<double>(hash(k, index) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

/** Standard normal deviate via Box-Muller; index selects an independent pair. */
inline double normal(const Key& k, std::uint64_t index) {
  const double u1 = uniform(k, 2 * index);
  const double u2 = uniform(k, 2 * index + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace pyoif::random
