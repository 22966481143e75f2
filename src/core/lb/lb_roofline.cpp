#include "lb/lb_roofline.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

namespace pyoif::lb {

double copy_bandwidth(std::size_t n_doubles, int repeats, int n_threads) {
  std::vector<double> a(n_doubles, 1.0), b(n_doubles, 0.0);
  const long n = static_cast<long>(n_doubles);
  double best = 1e300;
  (void)n_threads;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    double* __restrict pb = b.data();
    const double* __restrict pa = a.data();
#ifdef PYOIF_WITH_OPENMP
#pragma omp parallel for schedule(static) num_threads(n_threads)
#endif
    for (long i = 0; i < n; ++i)
      pb[i] = pa[i];
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double>(t1 - t0).count());
    a[static_cast<std::size_t>(r) % n_doubles] = b[0]; // keep the copies observable
  }
  return 16.0 * static_cast<double>(n_doubles) / best;
}

} // namespace pyoif::lb
