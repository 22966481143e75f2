#include "lb/boundary_links.hpp"

#include "shapes/union.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pyoif::lb {

using namespace d3q19;

std::vector<std::uint16_t> flag_nodes(const std::vector<BoundarySpec>& boundaries,
                                      const PaddedBox& box, double agrid) {
  // every padded node, ghosts included, from the shapes at its global
  // position (wrapped periodically): the ghosts' flags are those the
  // neighbouring rank gives its nodes, with no communication
  std::vector<std::uint16_t> flag(box.n_padded(), 0);
  if (boundaries.empty())
    return flag;
  // per axis and padded coordinate: the wrapped global node and its centre
  std::array<std::vector<int>, 3> global;
  std::array<std::vector<double>, 3> centre;
  for (int d = 0; d < 3; ++d)
    for (int x = 0; x < box.pad[d]; ++x) {
      const int g = ((box.origin[d] + x - 1) % box.global[d] + box.global[d]) % box.global[d];
      global[d].push_back(g);
      centre[d].push_back((static_cast<double>(g) + 0.5) * agrid);
    }
  // A Union's members flag its nodes one by one (a node is in the union
  // exactly when it is in a member), each over its own bounding box
  std::vector<std::pair<const shapes::Shape*, std::uint16_t>> leaves;
  auto add_leaves = [&leaves](const shapes::Shape& shape, std::uint16_t mark, auto& self) -> void {
    if (const auto* u = dynamic_cast<const shapes::Union*>(&shape)) {
      for (const auto& member : u->shapes())
        self(*member, mark, self);
      return;
    }
    leaves.emplace_back(&shape, mark);
  };
  for (std::size_t b = 0; b < boundaries.size(); ++b)
    add_leaves(*boundaries[b].shape, static_cast<std::uint16_t>(b + 1), add_leaves);
  // Shape by shape, in list order, over the padded coordinates whose node
  // centres lie in its bounding box (one node wider each way against
  // rounding; all of them for an unbounded shape), testing only the nodes
  // no earlier boundary took: the first boundary containing a node wins, as
  // a test of every boundary at every node would give
  std::array<std::vector<int>, 3> visit;
  for (const auto& [shape_ptr, mark] : leaves) {
    const shapes::Shape& shape = *shape_ptr;
    Vec3 lo, hi;
    const bool bounded = shape.bounding_box(lo, hi);
    bool empty = false;
    for (int d = 0; d < 3; ++d) {
      double first = 0.0, last = box.global[d] - 1.0;
      if (bounded) {
        const double l = std::floor(lo[d] / agrid - 0.5) - 1.0;
        const double h = std::ceil(hi[d] / agrid - 0.5) + 1.0;
        if (l > first) // (NaN: the whole axis)
          first = l;
        if (h < last)
          last = h;
      }
      visit[d].clear();
      for (int x = 0; x < box.pad[d]; ++x)
        if (global[d][x] >= first && global[d][x] <= last)
          visit[d].push_back(x);
      empty = empty || visit[d].empty();
    }
    if (empty)
      continue;
    for (const int z : visit[2])
      for (const int y : visit[1]) {
        const std::size_t row = box.index(0, y, z);
        for (const int x : visit[0]) {
          std::uint16_t& f = flag[row + static_cast<std::size_t>(x)];
          if (f == 0 && shape.is_inside(Vec3(centre[0][x], centre[1][y], centre[2][z])))
            f = mark;
        }
      }
  }
  return flag;
}

FluidGeometry fluid_geometry(const std::vector<std::uint16_t>& flag, const PaddedBox& box,
                             const std::array<std::ptrdiff_t, d3q19::Q>& neighbour_offset,
                             const std::vector<BoundarySpec>& boundaries, double tau, double agrid,
                             double density, std::size_t stride) {
  FluidGeometry g;
  // runs of fluid nodes along x, in memory order
  for (int z = 1; z <= box.extent[2]; ++z)
    for (int y = 1; y <= box.extent[1]; ++y) {
      int x = 1;
      while (x <= box.extent[0]) {
        if (flag[box.index(x, y, z)] != 0) {
          ++x;
          continue;
        }
        const int start = x;
        while (x <= box.extent[0] && flag[box.index(x, y, z)] == 0)
          ++x;
        g.runs.push_back({box.index(start, y, z), x - start});
        g.n_fluid += static_cast<std::size_t>(x - start);
        for (int xx = start; xx < x; ++xx) {
          const std::size_t n = box.index(xx, y, z);
          for (int q = 1; q < Q; ++q) {
            const std::size_t s = n + neighbour_offset[q];
            if (flag[s] == 0)
              continue;
            const int b = flag[s] - 1;
            const Vec3 u_wall = boundaries[b].velocity * tau / agrid;
            const double cu = c[q][0] * u_wall[0] + c[q][1] * u_wall[1] + c[q][2] * u_wall[2];
            g.links.push_back({n, s, q, b, 6.0 * w[q] * density * cu});
          }
        }
      }
    }
  std::vector<PlaceRun> links;
  for (const BoundaryLink& l : g.links)
    links.push_back({l.q * stride + l.solid, opposite(l.q) * stride + l.node, 1, l.wall_term});
  g.bounce_back = merge_place_runs(std::move(links));
  return g;
}

std::vector<PlaceRun> merge_place_runs(std::vector<PlaceRun> pairs) {
  std::sort(pairs.begin(), pairs.end(),
            [](const PlaceRun& a, const PlaceRun& b) { return a.first < b.first; });
  std::vector<PlaceRun> runs;
  for (const PlaceRun& p : pairs) {
    if (!runs.empty() && p.term == runs.back().term) {
      PlaceRun& last = runs.back();
      // a second pair sets the step (the next place in memory order
      // first: contiguous wherever a row continues), the others follow it
      if (last.length == 1 && p.first > last.first && p.second > last.second &&
          p.first - last.first == p.second - last.second) {
        last.step = p.first - last.first;
        ++last.length;
        continue;
      }
      if (last.length > 1 && p.first == last.first + last.length * last.step &&
          p.second == last.second + last.length * last.step) {
        ++last.length;
        continue;
      }
    }
    runs.push_back(p);
  }
  return runs;
}

} // namespace pyoif::lb
