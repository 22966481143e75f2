// Packing rigid cells to a volume fraction before a run: every cell keeps
// its reference shape exactly (so its volume and surface are the reference
// ones), the cells start shrunken at random places and orientations and
// grow while their overlaps and their overlaps with the walls push them
// apart (force-biased growth: Lubachevsky & Stillinger, J. Stat. Phys. 60,
// 561 (1990) grow hard particles; Mościński, Bargieł, Rycerz & Jacobs, Mol.
// Simul. 3, 201 (1989) push overlapping ones apart). A node's overlap is
// read from the other cell's level set (level_set.hpp), the walls' from the
// boundary shapes' signed distances.
#pragma once

#include "packing/level_set.hpp"
#include "shapes/shape.hpp"
#include "utils/vector.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

namespace pyoif::packing {

struct PackerSettings {
  Vec3 box = Vec3::Constant(1.0);
  std::array<bool, 3> periodic{{true, true, true}};
  /** Least distance of a node from another cell's surface. */
  double clearance = 0.5;
  /** Least signed distance of a node from every boundary shape and from the
   *  box faces of non-periodic axes. */
  double wall_clearance = 0.5;
  /** Nodes stay inside [region_lo, region_hi] along the axes where the
   *  region is narrower than the box. */
  Vec3 region_lo = Vec3::Zero(), region_hi = Vec3::Zero();
  bool has_region = false;
  double start_scale = 0.5;
  /** The size the cells grow to (1: their reference size). Below 1, the
   *  packing of rigid cells that the deformable stage of oif.pack_cells
   *  starts from: the cells there are created this much shrunken and
   *  swell to their reference volume under their contacts. */
  double final_scale = 1.0;
  /** Relative growth of the scale per iteration, slowed as the mean overlap
   *  of the contacts approaches `grow_tolerance` x clearance. */
  double growth = 0.01;
  double grow_tolerance = 0.3;
  /** A body moves by `step` x the mean overlap of its contacts per iteration. */
  double step = 0.8;
  /** Share of a body's last move carried into the next (0: plain descent). */
  double momentum = 0.9;
  /** Done when the scale is final_scale and no node is closer than
   *  (1 - final_tolerance) x clearance. */
  double final_tolerance = 0.02;
  int max_iterations = 20000;
  /** Stop early (jammed) when for this many iterations the scale has not
   *  grown by 0.1 % and the worst overlap not fallen by the share
   *  stall_overlap_drop (0: never). */
  int stall_iterations = 0;
  double stall_overlap_drop = 0.01;
  /** Seed of the kicks that separate cells stuck about one centre. */
  std::uint64_t seed = 0;
};

/** x folded into the box along the periodic axes of the settings. */
inline Vec3 fold_into_box(Vec3 x, const PackerSettings& s) {
  for (int k = 0; k < 3; ++k)
    if (s.periodic[k])
      x[k] -= s.box[k] * std::floor(x[k] / s.box[k]);
  return x;
}

struct PackerResult {
  bool converged = false;
  bool jammed = false; ///< stopped by stall_iterations
  int iterations = 0;
  double scale = 0.0;
  double worst_overlap = 0.0; ///< clearance - least node distance (level set), at the end
  double worst_wall_overlap = 0.0;
};

/** The exact check of a packing on the meshes themselves. */
struct PackingCheck {
  int nodes_inside_cells = 0;     ///< nodes with winding number > 1/2 about another cell
  double min_node_distance = 0.0; ///< between nodes of different cells
  double min_wall_distance = 0.0; ///< signed, of any node from any boundary shape
  int pairs_tested = 0;
};

class RigidPacker {
public:
  /** A cell type: its nodes relative to their centroid and its outward
   *  triangles; the level set's grid spacing. Returns the type's index. */
  int add_type(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& triangles,
               double spacing);
  void add_boundary(std::shared_ptr<const shapes::Shape> shape) { m_boundaries.push_back(shape); }
  /** Cells: type index, centre, orientation (unit quaternion w, x, y, z). */
  void set_bodies(const std::vector<int>& types, const std::vector<Vec3>& centres,
                  const std::vector<Eigen::Quaterniond>& orientations);
  PackerResult run(const PackerSettings& settings);
  PackingCheck check(const PackerSettings& settings) const;

  const std::vector<Vec3>& centres() const { return m_centre; }
  const std::vector<Eigen::Quaterniond>& orientations() const { return m_orientation; }
  std::size_t n_bodies() const { return m_type.size(); }

private:
  struct BodyType {
    std::vector<Vec3> nodes;
    std::vector<std::array<int, 3>> triangles;
    std::unique_ptr<LevelSet> level_set;
    double reach = 0.0;     ///< largest node distance from the centre
    double gyration2 = 0.0; ///< mean squared node distance from the centre
    double thinnest = 0.0;  ///< smallest extent of the nodes' box
    /** Patches of nearby nodes (CSR: patch p holds patch_nodes[patch_start[p]
     *  .. patch_start[p + 1]]), each with its centre and radius: a patch
     *  whose centre is farther from another cell than its radius plus the
     *  clearance is skipped with one level-set lookup. */
    std::vector<int> patch_start, patch_nodes;
    std::vector<Vec3> patch_centre;
    std::vector<double> patch_radius;
  };
  struct Pair {
    int i, j;
    Vec3 shift; ///< c_i - (image of c_j nearest to c_i)
  };
  void world_nodes(double scale);
  void find_pairs(double scale, double clearance, const PackerSettings& s);
  Vec3 min_image(Vec3 d, const PackerSettings& s) const;
  /** Adds the overlap forces of body a's nodes on body b's level set. */
  void push_apart(int a, int b, const Vec3& shift_ab, double scale, double clearance);
  void push_from_walls(int b, double scale, const PackerSettings& s);

  std::vector<BodyType> m_types;
  std::vector<std::shared_ptr<const shapes::Shape>> m_boundaries;
  std::vector<int> m_type;
  std::vector<Vec3> m_centre;
  std::vector<Eigen::Quaterniond> m_orientation;
  // per iteration
  std::vector<std::size_t> m_first_node;
  std::vector<Vec3> m_nodes; ///< world positions of every body's nodes
  std::vector<Eigen::Matrix3d> m_rotation;
  std::vector<Pair> m_pairs;
  std::vector<Vec3> m_force, m_torque;
  std::vector<Vec3> m_velocity, m_spin; ///< last move and turn
  std::vector<int> m_contacts;
  std::vector<double> m_body_overlap; ///< sum of the overlaps of each body's contacts
  std::vector<double> m_body_worst;   ///< largest overlap of each body's contacts
  double m_worst = 0.0, m_worst_wall = 0.0, m_overlap_sum = 0.0;
  long m_overlap_count = 0;
  std::vector<double> m_dist; ///< scratch: signed distances of one body's nodes
  std::vector<Vec3> m_folded; ///< scratch: one body's nodes folded into the box
};

} // namespace pyoif::packing
