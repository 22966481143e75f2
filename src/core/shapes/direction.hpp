// The `direction` parameter of ESPResSo's shapes: +1, the shape is the solid
// described by the other parameters; -1, the shape is its complement (hollow:
// particles and fluid live inside). Distance and normal change sign together.
#pragma once

#include "utils/errors.hpp"

#include <string>

namespace pyoif::shapes {

inline int checked_direction(int direction, const char* owner) {
  if (direction != 1 && direction != -1)
    throw InputError(std::string(owner) + ": parameter 'direction' must be 1 or -1, got " +
                     std::to_string(direction));
  return direction;
}

} // namespace pyoif::shapes
