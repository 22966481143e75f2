#include "packing/mesh_check.hpp"

#include "packing/level_set.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>

namespace pyoif::packing {

PackingCheck check_meshes(const MeshSet& cells,
                          const std::vector<std::shared_ptr<const shapes::Shape>>& boundaries,
                          const PackerSettings& s, double search) {
  const std::size_t n = cells.type.size();
  require(cells.first_node.size() == n + 1 && cells.first_node.back() == cells.nodes.size(),
          "pack_cells: the cells' node ranges do not match their nodes");
  std::vector<int> largest_index(cells.triangles.size(), -1);
  for (std::size_t t = 0; t < cells.triangles.size(); ++t)
    for (const auto& tri : cells.triangles[t])
      for (int k : tri) {
        require(k >= 0, "pack_cells: a negative triangle node index");
        largest_index[t] = std::max(largest_index[t], k);
      }
  for (std::size_t c = 0; c < n; ++c) {
    const int t = cells.type[c];
    require(t >= 0 && t < static_cast<int>(cells.triangles.size()),
            "pack_cells: a cell's type has no triangles");
    require(largest_index[t] < static_cast<int>(cells.first_node[c + 1] - cells.first_node[c]),
            "pack_cells: a triangle node index beyond its cell's nodes");
  }
  PackingCheck out;
  out.min_node_distance = search;
  out.min_wall_distance = HUGE_VAL;
  // per cell: centroid and the box of its nodes about it
  std::vector<Vec3> centroid(n, Vec3::Zero()), lo(n), hi(n);
  for (std::size_t c = 0; c < n; ++c) {
    const auto first = cells.first_node[c], last = cells.first_node[c + 1];
    require(last > first, "pack_cells: a cell without nodes");
    for (auto k = first; k < last; ++k)
      centroid[c] += cells.nodes[k];
    centroid[c] /= static_cast<double>(last - first);
    lo[c] = hi[c] = cells.nodes[first] - centroid[c];
    for (auto k = first; k < last; ++k) {
      lo[c] = lo[c].cwiseMin(cells.nodes[k] - centroid[c]);
      hi[c] = hi[c].cwiseMax(cells.nodes[k] - centroid[c]);
    }
  }
  std::vector<Vec3> other;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j)
        continue;
      // the image of j whose centroid is nearest to i's
      Vec3 shift = centroid[i] - centroid[j];
      for (int k = 0; k < 3; ++k)
        if (s.periodic[k])
          shift[k] -= s.box[k] * std::round(shift[k] / s.box[k]);
      const Vec3 cj = centroid[i] - shift;
      const Vec3 jlo = cj + lo[j], jhi = cj + hi[j];
      const Vec3 ilo = centroid[i] + lo[i], ihi = centroid[i] + hi[i];
      if (((ilo.array() - search) > jhi.array()).any() ||
          ((ihi.array() + search) < jlo.array()).any())
        continue;
      ++out.pairs_tested;
      const auto jfirst = cells.first_node[j], jlast = cells.first_node[j + 1];
      other.resize(jlast - jfirst);
      for (auto k = jfirst; k < jlast; ++k)
        other[k - jfirst] = cj + (cells.nodes[k] - centroid[j]);
      for (auto q = cells.first_node[i]; q < cells.first_node[i + 1]; ++q) {
        const Vec3& x = cells.nodes[q];
        if (((x.array() + search) < jlo.array()).any() ||
            ((x.array() - search) > jhi.array()).any())
          continue;
        for (const Vec3& y : other)
          out.min_node_distance = std::min(out.min_node_distance, (x - y).norm());
        if (((x.array() >= jlo.array()) && (x.array() <= jhi.array())).all() &&
            winding_number(x, other, cells.triangles[cells.type[j]]) > 0.5)
          ++out.nodes_inside_cells;
      }
    }
  out.min_wall_distance = min_wall_distance(cells.nodes, boundaries, s);
  return out;
}

double min_wall_distance(std::vector<Vec3> nodes,
                         const std::vector<std::shared_ptr<const shapes::Shape>>& boundaries,
                         const PackerSettings& s) {
  for (Vec3& x : nodes)
    x = fold_into_box(x, s); // as the engine's walls see them
  double least = HUGE_VAL;
  std::vector<double> dist(nodes.size());
  for (const auto& shape : boundaries) {
    shape->signed_distances(nodes.data(), nodes.size(), HUGE_VAL, dist.data());
    for (double d : dist)
      least = std::min(least, d);
  }
  return least;
}

} // namespace pyoif::packing
