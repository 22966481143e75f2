// How long code runs slower after dense 512-bit floating-point work.
//
// Intel cores lower their clock while they execute dense AVX-512 floating
// point ("licence" levels) and return to the higher clock only some time
// after the last such instruction. The lattice kernel is such work; the cell
// passes that follow it in a time step run in that time. This program
// measures the effect: a scalar dependent chain (clock-bound, no memory) is
// timed in chunks of a few tens of microseconds right after 2 ms of 512-bit
// FMAs, right after 2 ms of 256-bit FMAs, and in steady state; the median
// of 40 rounds per chunk.
//
//     build/avx512_clock [--csv avx512_clock.csv]
//
// Prints how much slower the chunks ran than in steady state, in spells of
// 8 chunks after each kind of dense work; writes the chunk times as CSV.
// See doc/performance.md (ninth round).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include <sched.h>

#if defined(__AVX512F__)
namespace {

using Clock = std::chrono::steady_clock;

double microseconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::micro>(b - a).count();
}

/** 8 and 4 doubles (GCC vector extension: a * b + c compiles to one FMA of
 *  that width). */
using Doubles8 = double __attribute__((vector_size(64)));
using Doubles4 = double __attribute__((vector_size(32)));

/** Eight independent FMA chains of `Vec` for `ms` milliseconds, in
 *  registers (about two FMAs per cycle); returns a lane of the result, for
 *  the caller to keep. */
template <class Vec> __attribute__((noinline)) double dense_fma(double ms) {
  const Vec a = Vec{} + 0.999999;
  // different starts: eight equal chains would be computed once
  Vec c0 = a, c1 = a + 1e-3, c2 = a + 2e-3, c3 = a + 3e-3, c4 = a + 4e-3, c5 = a + 5e-3,
      c6 = a + 6e-3, c7 = a + 7e-3;
  const Clock::time_point start = Clock::now();
  while (microseconds(start, Clock::now()) < 1000.0 * ms)
    for (int i = 0; i < 1000; ++i) {
      c0 = a * c0 + a;
      c1 = a * c1 + a;
      c2 = a * c2 + a;
      c3 = a * c3 + a;
      c4 = a * c4 + a;
      c5 = a * c5 + a;
      c6 = a * c6 + a;
      c7 = a * c7 + a;
    }
  const Vec sum = (c0 + c1) + (c2 + c3) + (c4 + c5) + (c6 + c7);
  double first;
  std::memcpy(&first, &sum, sizeof first);
  return first;
}

/** Times of `chunks` chunks of a scalar dependent chain (clock-bound). */
__attribute__((noinline)) void scalar_probe(std::vector<double>& chunk_us, double& sink) {
  double x = sink;
  for (double& t : chunk_us) {
    const Clock::time_point start = Clock::now();
    for (int i = 0; i < 20000; ++i)
      x = x * 1.0000001 + 1e-9;
    t = microseconds(start, Clock::now());
  }
  sink = x;
}

/** Median of each chunk over the rounds: a round the process lost its core
 *  in does not swamp the figure. */
std::vector<double> chunk_medians(std::vector<std::vector<double>> rounds) {
  std::vector<double> medians;
  for (std::size_t i = 0; i < rounds[0].size(); ++i) {
    std::vector<double> values;
    for (const auto& r : rounds)
      values.push_back(r[i]);
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    medians.push_back(values[values.size() / 2]);
  }
  return medians;
}

} // namespace
#endif

int main(int argc, char** argv) {
  const char* csv = "avx512_clock.csv";
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--csv") == 0)
      csv = argv[i + 1];
#if !defined(__AVX512F__)
  std::printf("built without AVX-512: nothing to measure\n");
  (void)csv;
  return 0;
#else
  // on one core throughout: a move to another core between the FMAs and
  // the probe would hide the effect
  cpu_set_t one_core;
  CPU_ZERO(&one_core);
  CPU_SET(sched_getcpu(), &one_core);
  sched_setaffinity(0, sizeof one_core, &one_core);
  constexpr int chunks = 80, rounds = 40;
  std::vector<std::vector<double>> runs512, runs256, runs_steady;
  std::vector<double> t(chunks);
  double sink = 1.0;
  // the probe's chunks right after `dense` ran, appended to `runs`
  auto probe_after = [&](double (*dense)(double), std::vector<std::vector<double>>& runs) {
    sink += dense(2.0) * 1e-300;
    scalar_probe(t, sink);
    runs.push_back(t);
  };
  for (int r = 0; r < rounds; ++r) {
    probe_after(dense_fma<Doubles8>, runs512);
    probe_after(dense_fma<Doubles4>, runs256);
    scalar_probe(t, sink); // leaves any slower clock behind
    scalar_probe(t, sink);
    runs_steady.push_back(t);
  }
  const std::vector<double> after512 = chunk_medians(runs512), after256 = chunk_medians(runs256),
                            steady = chunk_medians(runs_steady);
  double reference = 0.0;
  for (double x : steady)
    reference += x / chunks;
  std::printf("scalar chunk in steady state: %.1f us\n", reference);
  std::printf("time after the dense FMAs    slower than steady: after 512-bit  after 256-bit\n");
  constexpr int bin = 8;
  double elapsed = 0.0;
  for (int i0 = 0; i0 < chunks; i0 += bin) {
    double t512 = 0.0, t256 = 0.0;
    for (int i = i0; i < i0 + bin; ++i) {
      t512 += after512[i];
      t256 += after256[i];
    }
    std::printf("%6.0f - %6.0f us                              %+5.1f %%       %+5.1f %%\n",
                elapsed, elapsed + t512, 100.0 * (t512 / (bin * reference) - 1.0),
                100.0 * (t256 / (bin * reference) - 1.0));
    elapsed += t512;
  }
  if (std::FILE* f = std::fopen(csv, "w")) {
    std::fprintf(f, "chunk,after_512_us,after_256_us,steady_us\n");
    for (int i = 0; i < chunks; ++i)
      std::fprintf(f, "%d,%.3f,%.3f,%.3f\n", i, after512[i], after256[i], steady[i]);
    std::fclose(f);
    std::printf("written %s\n", csv);
  }
  (void)sink;
  return 0;
#endif
}
