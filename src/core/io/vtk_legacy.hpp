// Legacy VTK writer (the "vtk DataFile Version 3.0" ASCII format that
// ParaView and VTK's vtkStructuredPointsReader open): point data on a
// regular grid.
#pragma once

#include "utils/vector.hpp"

#include <string>
#include <vector>

namespace pyoif::io {

/** Writes `n_components` (1: SCALARS, 3: VECTORS) values per point, x fastest,
 *  points at origin + (i, j, k) * spacing. Throws InputError if the file cannot
 *  be written. */
void write_vtk_structured_points(const std::string& path, const Vec3i& dims, const Vec3& origin,
                                 double spacing, const std::string& name, int n_components,
                                 const std::vector<double>& data);

} // namespace pyoif::io
