// Small vector types shared by the whole core.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace pyoif {

using Vec3 = Eigen::Vector3d;
using Vec3i = Eigen::Vector3i;

}  // namespace pyoif
