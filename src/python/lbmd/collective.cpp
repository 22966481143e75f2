// The entry of every collective query (see bindings.hpp).
#include "bindings.hpp"

#include <mpi.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

namespace pyoif::python {

void collective_entry(const char* what) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1)
    return;
  // A non-blocking barrier: the usual case (every rank makes the same
  // query) passes it at once; a rank left waiting says so after a while,
  // instead of hanging without a word.
  MPI_Request request;
  MPI_Ibarrier(MPI_COMM_WORLD, &request);
  int done = 0;
  MPI_Test(&request, &done, MPI_STATUS_IGNORE);
  if (done)
    return;
  pybind11::gil_scoped_release release;
  // (PYOIF_COLLECTIVE_WARN_S: another delay, for tests)
  static const double warn_after_s = [] {
    const char* v = std::getenv("PYOIF_COLLECTIVE_WARN_S");
    return v ? std::atof(v) : 10.0;
  }();
  const auto start = std::chrono::steady_clock::now();
  bool warned = false;
  for (int spins = 0; !done; ++spins) {
    if (spins > 1000)
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (!done && !warned &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
            warn_after_s) {
      int rank = 0;
      MPI_Comm_rank(MPI_COMM_WORLD, &rank);
      std::fprintf(stderr,
                   "[rank %d] %s has waited %.0f s for the other ranks. Under mpirun every "
                   "rank must make every query (the fluid's nodes, the particles' "
                   "properties, analysis): one made on some ranks only, e.g. inside `if "
                   "lbmd.rank == 0:`, waits forever. Still waiting.\n",
                   rank, what, warn_after_s);
      warned = true;
    }
  }
}

} // namespace pyoif::python
