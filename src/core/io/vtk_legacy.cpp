#include "io/vtk_legacy.hpp"

#include "utils/errors.hpp"

#include <cstdio>
#include <memory>
#include <sys/stat.h>

namespace pyoif::io {

void write_vtk_structured_points(const std::string& path, const Vec3i& dims, const Vec3& origin,
                                 double spacing, const std::string& name, int n_components,
                                 const std::vector<double>& data) {
  if (n_components != 1 && n_components != 3)
    throw InputError("VTK output: 1 or 3 components per point, got " +
                     std::to_string(n_components));
  const std::size_t n_points = static_cast<std::size_t>(dims.prod());
  if (data.size() != n_points * n_components)
    throw InputError("VTK output: data size does not match the grid");
  // written under a temporary name and renamed at the end: a reader (or a
  // run that dies here) never sees a half-written file under the final name
  // (never over a device or fifo: only a regular file is replaced)
  struct stat existing {};
  if (::stat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode))
    throw InputError("VTK output: '" + path +
                     "' exists and is not a regular file (a directory, device or fifo)");
  const std::string tmp = path + ".tmp";
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(tmp.c_str(), "w"), &std::fclose);
  if (!file)
    throw InputError("VTK output: cannot open '" + path + "' for writing");
  std::FILE* f = file.get();
  std::fprintf(f, "# vtk DataFile Version 3.0\nPyOIF lattice-Boltzmann %s\nASCII\n", name.c_str());
  std::fprintf(f, "DATASET STRUCTURED_POINTS\nDIMENSIONS %d %d %d\n", dims[0], dims[1], dims[2]);
  std::fprintf(f, "ORIGIN %.17g %.17g %.17g\nSPACING %.17g %.17g %.17g\n", origin[0], origin[1],
               origin[2], spacing, spacing, spacing);
  std::fprintf(f, "POINT_DATA %zu\n", n_points);
  if (n_components == 3)
    std::fprintf(f, "VECTORS %s double\n", name.c_str());
  else
    std::fprintf(f, "SCALARS %s double 1\nLOOKUP_TABLE default\n", name.c_str());
  for (std::size_t i = 0; i < n_points; ++i) {
    if (n_components == 3)
      std::fprintf(f, "%.17g %.17g %.17g\n", data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    else
      std::fprintf(f, "%.17g\n", data[i]);
  }
  // the buffered tail reaches the file only at fclose: its result counts
  // too (a full disk), else a truncated file would pass as written
  const bool write_error = std::ferror(f) != 0;
  const bool close_error = std::fclose(file.release()) != 0;
  if (write_error || close_error) {
    std::remove(tmp.c_str());
    throw InputError("VTK output: error while writing '" + path +
                     "' (disk full or not writable?); nothing was written");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError("VTK output: cannot rename the finished file to '" + path + "'");
  }
}

} // namespace pyoif::io
