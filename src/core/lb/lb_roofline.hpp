// A STREAM-like copy benchmark (McCalpin's "Copy": b[i] = a[i]) that gives the
// memory-bandwidth roofline of the lattice-Boltzmann kernel on the machine
// at hand. Bytes counted as STREAM does: 16 per element (read + write).
#pragma once

#include <cstddef>

namespace pyoif::lb {

/** Best copy bandwidth in bytes/s over `repeats` copies of two arrays of
 *  `n_doubles` each, with `n_threads` threads. */
double copy_bandwidth(std::size_t n_doubles, int repeats, int n_threads);

} // namespace pyoif::lb
