// The exact check of a packing of deformed cells (the deformable stage of
// oif.pack_cells): every cell's nodes against the other cells' meshes as
// they are, not against a rigid body's level set. A node counts as inside
// another cell where the winding number of that cell's surface about it
// exceeds 1/2; the least node-to-node distance between different cells
// and the least signed distance of a node from every boundary shape are
// reported, as RigidPacker::check does for rigid bodies.
#pragma once

#include "packing/rigid_packer.hpp"
#include "shapes/shape.hpp"
#include "utils/vector.hpp"

#include <array>
#include <memory>
#include <vector>

namespace pyoif::packing {

struct MeshSet {
  /** The nodes of every cell, one cell after the other (unfolded: each
   *  cell's nodes in one piece). */
  std::vector<Vec3> nodes;
  /** Cell c holds nodes[first_node[c] .. first_node[c + 1]]. */
  std::vector<std::size_t> first_node;
  /** Cell c's triangles are triangles[type[c]], outward, indices local to
   *  the cell. */
  std::vector<int> type;
  std::vector<std::vector<std::array<int, 3>>> triangles;
};

/** Node distances are exact below `search` (and `search` where none is
 *  closer); pairs are taken at the image of least centroid distance along
 *  the periodic axes of `settings`. */
PackingCheck check_meshes(const MeshSet& cells,
                          const std::vector<std::shared_ptr<const shapes::Shape>>& boundaries,
                          const PackerSettings& settings, double search);

/** The least signed distance of the nodes (folded into the box along the
 *  periodic axes of `settings`) from the boundary shapes; HUGE_VAL with
 *  none. */
double min_wall_distance(std::vector<Vec3> nodes,
                         const std::vector<std::shared_ptr<const shapes::Shape>>& boundaries,
                         const PackerSettings& settings);

} // namespace pyoif::packing
