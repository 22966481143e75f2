// What a non-bonded evaluator sees of one pair: the separation vector
// d = x_i - x_j (minimum image), its length, and per-particle data some models
// need (membrane normals and cell ids for membrane collision).
#pragma once

#include "utils/vector.hpp"

namespace pyoif {

struct PairContext {
  Vec3 d;       ///< x_i - x_j
  double dist;  ///< |d|
  int mol_i, mol_j;
  Vec3 normal_i, normal_j;  ///< outward membrane normals (zero when not a membrane node)
  bool wall = false;        ///< j is a shape constraint (d is the surface normal times dist)
};

}  // namespace pyoif
