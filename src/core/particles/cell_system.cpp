#include "particles/cell_system.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pyoif {

bool CellSystem::needs_rebuild(const ParticleStore& p, double time) const {
  const double limit2 = displacement_limit2();
  bool moved = !m_valid || m_pos_at_rebuild.size() != p.n_local();
  for (std::size_t i = 0; i < p.n_local(); ++i) {
    const Vec3& x = p.pos[i];
    if (runaway(x)) {
      std::ostringstream msg;
      msg << "particle " << p.id[i] << " has a non-finite or runaway position (" << x.transpose()
          << ") at time " << time << "; force " << p.force[i].transpose()
          << ". Reduce the time step or check the interaction parameters.";
      throw SimulationInstability("particle_nan", msg.str())
          .at_particle(p.id[i])
          .at_time(time)
          .with_value(x.norm());
    }
    if (!moved && (x - m_pos_at_rebuild[i]).squaredNorm() > limit2)
      moved = true;
  }
  return moved;
}

void CellSystem::rebuild(ParticleStore& p, const BoxGeometry& box, double max_cut,
                         const std::uint8_t* owned, const std::uint8_t* current) {
  m_blowup_distance = box.image_range();
  for (std::size_t i = 0; i < p.n_local(); ++i)
    box.fold(p.pos[i], p.image[i]);
  m_pos_at_rebuild = p.pos;
  m_range = max_cut > 0.0 ? max_cut + skin : 0.0;
  p.clear_ghosts();
  m_pairs.clear();
  if (m_range > 0.0) {
    for (int d = 0; d < 3; ++d)
      if (box.periodic()[d] && m_range > box.length()[d]) {
        std::ostringstream msg;
        msg << "cell_system: the interaction range (largest cutoff + skin = " << m_range
            << ") exceeds the box length " << box.length()[d] << " on axis " << d
            << "; enlarge the box or reduce the cutoffs or cell_system.skin";
        throw InputError(msg.str());
      }
    make_ghosts(p, box, m_range, current);
    p.ghost_force.assign(p.n_ghost(), Vec3::Zero());
    build_pairs(p, m_range, owned, current);
  }
  m_valid = true;
  m_has_hint = false;
  ++m_n_rebuilds;
}

void CellSystem::make_ghosts(ParticleStore& p, const BoxGeometry& box, double range,
                             const std::uint8_t* current) const {
  // Axis by axis, imaging locals and the ghosts made so far, so edges and
  // corners get their images too.
  for (int d = 0; d < 3; ++d) {
    if (!box.periodic()[d])
      continue;
    const double L = box.length()[d];
    const std::size_t n_sources = p.n_local() + p.n_ghost();
    for (std::size_t i = 0; i < n_sources; ++i) {
      const int origin = p.owner(i);
      if (current && !current[origin])
        continue; // an out-of-date copy (particles spread over ranks)
      const Vec3 x = p.position(i);
      const Vec3i base = i < p.n_local() ? Vec3i::Zero() : p.ghost_shift[i - p.n_local()];
      for (int s : {+1, -1}) {
        const bool near_face = (s > 0) ? (x[d] < range) : (x[d] >= L - range);
        if (!near_face)
          continue;
        Vec3 xg = x;
        xg[d] += s * L;
        Vec3i shift = base;
        shift[d] += s;
        p.ghost_pos.push_back(xg);
        p.ghost_origin.push_back(origin);
        p.ghost_shift.push_back(shift);
      }
    }
  }
}

namespace {
// Lexicographic sign of an image shift, to keep one of the two mirror pairs
// (i, image of j) and (j, image of i) of a physical pair.
bool positive(const Vec3i& s) {
  for (int d = 0; d < 3; ++d)
    if (s[d] != 0)
      return s[d] > 0;
  return false;
}
} // namespace

void CellSystem::build_exclusion_lists() {
  sort_exclusions();
  int max_id = -1;
  for (const std::uint64_t k : m_exclusions)
    max_id = std::max(max_id, static_cast<int>(k & 0xffffffffu)); // the larger id of the pair
  m_exclusion_start.assign(static_cast<std::size_t>(max_id) + 2, 0);
  for (const std::uint64_t k : m_exclusions) {
    ++m_exclusion_start[static_cast<std::size_t>(k >> 32) + 1];
    ++m_exclusion_start[static_cast<std::size_t>(k & 0xffffffffu) + 1];
  }
  for (std::size_t i = 1; i < m_exclusion_start.size(); ++i)
    m_exclusion_start[i] += m_exclusion_start[i - 1];
  m_exclusion_partners.resize(m_exclusion_start.back());
  std::vector<std::size_t> fill(m_exclusion_start.begin(), m_exclusion_start.end() - 1);
  for (const std::uint64_t k : m_exclusions) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    m_exclusion_partners[fill[a]++] = b;
    m_exclusion_partners[fill[b]++] = a;
  }
  for (std::size_t i = 0; i + 1 < m_exclusion_start.size(); ++i)
    std::sort(m_exclusion_partners.begin() + static_cast<std::ptrdiff_t>(m_exclusion_start[i]),
              m_exclusion_partners.begin() + static_cast<std::ptrdiff_t>(m_exclusion_start[i + 1]));
  m_exclusion_lists_valid = true;
}

void CellSystem::build_pairs(const ParticleStore& p, double range, const std::uint8_t* owned,
                             const std::uint8_t* current) {
  if (!m_exclusion_lists_valid && !m_exclusions.empty())
    build_exclusion_lists();
  const std::size_t n_local = p.n_local();
  const std::size_t n_all = n_local + p.n_ghost();
  if (n_all == 0)
    return;
  // (particles spread over ranks: out-of-date copies are left out)
  auto binned = [&](std::size_t i) { return !current || current[p.owner(i)]; };
  Vec3 lo = Vec3::Constant(HUGE_VAL), hi = Vec3::Constant(-HUGE_VAL);
  for (std::size_t i = 0; i < n_all; ++i)
    if (binned(i)) {
      lo = lo.cwiseMin(p.position(i));
      hi = hi.cwiseMax(p.position(i));
    }
  if (!(lo[0] <= hi[0]))
    return;                   // nothing to bin
  std::size_t n_grid = n_all; // the particles the grid is made for
  if (m_has_hint) {
    lo = m_hint.lo;
    hi = m_hint.hi;
    n_grid = m_hint.n_all;
  }
  // Cells of at least `range` per side, at most ~2 per particle.
  std::array<int, 3> nc;
  Vec3 cell_size;
  double size = range;
  for (;;) {
    long total = 1;
    for (int d = 0; d < 3; ++d) {
      nc[d] = std::max(1, static_cast<int>(std::floor((hi[d] - lo[d]) / size)));
      total *= nc[d];
    }
    if (total <= static_cast<long>(2 * n_grid + 27))
      break;
    size *= 1.26;
  }
  for (int d = 0; d < 3; ++d)
    cell_size[d] = std::max((hi[d] - lo[d]) / nc[d], 1e-300);
  const int n_cells = nc[0] * nc[1] * nc[2];
  auto cell_coord = [&](const Vec3& x, int d) {
    return std::clamp(static_cast<int>((x[d] - lo[d]) / cell_size[d]), 0, nc[d] - 1);
  };
  std::vector<int> cell_of(n_all);
  m_cell_start.assign(n_cells + 1, 0);
  for (std::size_t i = 0; i < n_all; ++i) {
    if (!binned(i)) {
      cell_of[i] = -1;
      continue;
    }
    const Vec3& x = p.position(i);
    const int c = (cell_coord(x, 2) * nc[1] + cell_coord(x, 1)) * nc[0] + cell_coord(x, 0);
    cell_of[i] = c;
    ++m_cell_start[c + 1];
  }
  for (int c = 0; c < n_cells; ++c)
    m_cell_start[c + 1] += m_cell_start[c];
  m_cell_particles.resize(n_all);
  {
    std::vector<int> fill(m_cell_start.begin(), m_cell_start.end() - 1);
    for (std::size_t i = 0; i < n_all; ++i)
      if (cell_of[i] >= 0)
        m_cell_particles[fill[cell_of[i]]++] = static_cast<int>(i);
  }
  // spread over ranks: the cells holding a particle (or image) this rank
  // owns; a pair of cells without one is skipped
  std::vector<std::uint8_t> has_owned;
  if (owned) {
    has_owned.assign(n_cells, 0);
    for (std::size_t i = 0; i < n_all; ++i)
      if (cell_of[i] >= 0)
        has_owned[cell_of[i]] |= owned[p.owner(i)];
  }

  const double range2 = range * range;
  auto consider = [&](int a, int b) {
    if (owned && !owned[p.owner(a)] && !owned[p.owner(b)])
      return;
    if (static_cast<std::size_t>(a) >= n_local)
      std::swap(a, b); // a is local from here on (if either is)
    if (static_cast<std::size_t>(a) >= n_local)
      return; // ghost-ghost pairs belong to other owners
    const bool b_local = static_cast<std::size_t>(b) < n_local;
    if ((p.position(a) - p.position(b)).squaredNorm() >= range2)
      return;
    const int id_a = p.id[a];
    const int id_b = p.id[p.owner(b)];
    if (!b_local) {
      // The mirror pair (b's origin, image of a) is also present: keep one.
      if (id_a > id_b || (id_a == id_b && !positive(p.ghost_shift[b - n_local])))
        return;
    }
    if (id_a != id_b && excluded(id_a, id_b))
      return;
    m_pairs.push_back({a, b});
  };

  // Half shell: the cell itself (i < j) and 13 of its 26 neighbours.
  static const int shell[13][3] = {{1, 0, 0},  {-1, 1, 0}, {0, 1, 0},  {1, 1, 0}, {-1, -1, 1},
                                   {0, -1, 1}, {1, -1, 1}, {-1, 0, 1}, {0, 0, 1}, {1, 0, 1},
                                   {-1, 1, 1}, {0, 1, 1},  {1, 1, 1}};
  for (int cz = 0; cz < nc[2]; ++cz)
    for (int cy = 0; cy < nc[1]; ++cy)
      for (int cx = 0; cx < nc[0]; ++cx) {
        const int c = (cz * nc[1] + cy) * nc[0] + cx;
        if (!owned || has_owned[c])
          for (int i = m_cell_start[c]; i < m_cell_start[c + 1]; ++i)
            for (int j = i + 1; j < m_cell_start[c + 1]; ++j)
              consider(m_cell_particles[i], m_cell_particles[j]);
        for (const auto& s : shell) {
          const int nx = cx + s[0], ny = cy + s[1], nz = cz + s[2];
          if (nx < 0 || ny < 0 || nz < 0 || nx >= nc[0] || ny >= nc[1] || nz >= nc[2])
            continue;
          const int n = (nz * nc[1] + ny) * nc[0] + nx;
          if (owned && !has_owned[c] && !has_owned[n])
            continue;
          for (int i = m_cell_start[c]; i < m_cell_start[c + 1]; ++i)
            for (int j = m_cell_start[n]; j < m_cell_start[n + 1]; ++j)
              consider(m_cell_particles[i], m_cell_particles[j]);
        }
      }
}

void CellSystem::update_ghosts(ParticleStore& p, const BoxGeometry& box) const {
  const Vec3& L = box.length();
  for (std::size_t g = 0; g < p.n_ghost(); ++g)
    p.ghost_pos[g] = p.pos[p.ghost_origin[g]] + p.ghost_shift[g].cast<double>().cwiseProduct(L);
}

void CellSystem::collect_ghost_forces(ParticleStore& p) const {
  for (std::size_t g = 0; g < p.n_ghost(); ++g) {
    p.force[p.ghost_origin[g]] += p.ghost_force[g];
    p.ghost_force[g].setZero();
  }
}

} // namespace pyoif
