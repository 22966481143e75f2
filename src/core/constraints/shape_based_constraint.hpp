// A shape acting on the particles of every type through the non-bonded table
// entry (particle type, constraint's particle_type), with the distance to the
// shape's surface as pair distance (model eq. 8: node-wall soft sphere).
#pragma once

#include "shapes/shape.hpp"
#include "utils/vector.hpp"

#include <memory>

namespace pyoif {

struct ShapeBasedConstraint {
  std::shared_ptr<shapes::Shape> shape;
  int particle_type = 0;
  bool penetrable = false;
  bool only_positive = false;
  Vec3 total_force = Vec3::Zero();  ///< force the particles exert on the shape, last step
};

}  // namespace pyoif
