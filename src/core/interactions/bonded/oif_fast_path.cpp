#include "interactions/bonded/oif_fast_path.hpp"

#include "interactions/bonded/oif_edge_terms.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <unordered_map>

namespace pyoif::oif {

namespace {

constexpr int kind_local = 0, kind_global = 1, kind_out_direction = 2;

/** The centroid allocation of oif_area.hpp (Jancigova & Cimrak 2015) for a
 *  triangle given by its edges e1 = b - a, e2 = c - a: F(X) = coefficient *
 *  vec(XT) / sum |XT|^2. Adds to fa, fb, fc. */
inline void add_centroid_allocated_edges(const Vec3& e1, const Vec3& e2, double coefficient,
                                         Vec3& fa, Vec3& fb, Vec3& fc) {
  const Vec3 ma = (e1 + e2) / 3.0; // T - a
  const Vec3 mb = ma - e1, mc = ma - e2;
  const double scale = coefficient / (ma.squaredNorm() + mb.squaredNorm() + mc.squaredNorm());
  fa += scale * ma;
  fb += scale * mb;
  fc += scale * mc;
}

/** atan2(y, x) in (-pi, pi] for the deviation of a dihedral angle from its
 *  reference, given as (sin, cos) times a positive factor. Deviations below
 *  atan(1/4) (14 degrees, most of a membrane's angles) take an odd polynomial
 *  t P(t^2), t = y/x, P the Chebyshev economisation on [0, 1/16] of the Taylor
 *  series of atan(sqrt s)/sqrt s (maintainer-free derivation: exact rational
 *  arithmetic, dropped terms < 5e-18; max relative error 2.2e-16 against libm
 *  on 2e5 random points); larger ones call std::atan2. Result in [-pi, pi]. */
inline double angle_from_reference(double y, double x) {
  if (x > 0.0 && std::abs(y) <= 0.25 * x) {
    const double t = y / x, s = t * t;
    double pz = 0.04599761088928747;
    pz = pz * s - 0.06523656687585018;
    pz = pz * s + 0.07683492919828101;
    pz = pz * s - 0.09090589248444612;
    pz = pz * s + 0.11111104259672454;
    pz = pz * s - 0.1428571420303533;
    pz = pz * s + 0.19999999999499324;
    pz = pz * s - 0.33333333333332166;
    pz = pz * s + 1.0;
    return t * pz;
  }
  return std::atan2(y, x);
}

} // namespace

FastBondPlan::Key FastBondPlan::key_of(const BondGroup& group, const ParticleStore& p,
                                       int kind) const {
  Key k;
  k.particles_version = p.layout_version;
  k.ids = group.ids.data();
  k.per_bond = group.per_bond.data();
  k.n_ids = group.ids.size();
  k.n_per_bond = group.per_bond.size();
  k.kind = kind;
  return k;
}

bool FastBondPlan::build_slots(const BondGroup& group, const ParticleStore& p,
                               std::vector<int>& bond_slots) {
  std::vector<int> slot_of(p.n_local(), -1);
  m_index.clear();
  bond_slots.resize(group.ids.size());
  for (std::size_t k = 0; k < group.ids.size(); ++k) {
    const int i = p.index(group.ids[k]);
    if (i < 0)
      return false; // the generic loop names the missing particle
    if (slot_of[i] < 0) {
      slot_of[i] = static_cast<int>(m_index.size());
      m_index.push_back(i);
    }
    bond_slots[k] = slot_of[i];
  }
  const std::size_t n = m_index.size();
  m_x.resize(n);
  m_v.resize(n);
  m_f.resize(n);
  return true;
}

bool FastBondPlan::build_local(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 4 || group.per_bond_stride != 4 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_bonds.resize(n);
  m_triangles.clear();
  // unique triangles, keyed by their sorted slots (21 bits each)
  if (m_index.size() >= (std::size_t(1) << 21))
    return false;
  std::unordered_map<std::uint64_t, int> triangle_of;
  triangle_of.reserve(n);
  std::vector<int> uses;
  auto add_triangle = [&](int s0, int s1, int s2, double area0) {
    int lo = std::min({s0, s1, s2}), hi = std::max({s0, s1, s2});
    const int mid = s0 + s1 + s2 - lo - hi;
    const std::uint64_t key = static_cast<std::uint64_t>(lo) |
                              (static_cast<std::uint64_t>(mid) << 21) |
                              (static_cast<std::uint64_t>(hi) << 42);
    auto [it, inserted] = triangle_of.try_emplace(key, static_cast<int>(m_triangles.size()));
    if (inserted) {
      m_triangles.push_back({s0, s1, s2, -1, 0.0, 0.0});
      uses.push_back(0);
    }
    m_triangles[it->second].area0 += area0;
    ++uses[it->second];
  };
  for (std::size_t b = 0; b < n; ++b) {
    const int* s = slots.data() + 4 * b; // (B, A, C, D)
    const double* ref = group.reference(b);
    // the generic loop rejects these as degenerate (and throws): leave it to it
    if (!(ref[0] > 0.0) || !(ref[2] > 0.0) || !(ref[3] > 0.0) || !std::isfinite(ref[1]))
      return false;
    // psi0 = pi - phi0: cos psi0 = -cos phi0, sin psi0 = sin phi0
    m_bonds[b] = {
        s[0], s[1], s[2], s[3], ref[0], 1.0 / ref[0], -std::cos(ref[1]), std::sin(ref[1])};
    add_triangle(s[1], s[0], s[2], ref[2]); // A B C
    add_triangle(s[0], s[2], s[3], ref[3]); // B C D
  }
  // each use adds kal (S - S0_bond) / 3 (oif_local_forces.hpp): summed,
  // kal (uses/3 S - sum S0_bond / 3)
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    m_triangles[t].weight = uses[t] / 3.0;
    m_triangles[t].area0 /= 3.0;
  }
  return true;
}

bool FastBondPlan::build_triangles(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 3 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_triangles.resize(n);
  m_triangle_mol.resize(n);
  m_cell_mol.clear();
  m_cell_reference.clear();
  // cells as the generic cell sums define them: the mol_id of a triangle's
  // first node; reference point the first node of the cell's first triangle
  std::unordered_map<int, int> cell_of_mol;
  for (std::size_t t = 0; t < n; ++t) {
    const int* s = slots.data() + 3 * t;
    const int mol = p.mol_id[m_index[s[0]]];
    auto [it, inserted] = cell_of_mol.try_emplace(mol, static_cast<int>(m_cell_mol.size()));
    if (inserted) {
      m_cell_mol.push_back(mol);
      m_cell_reference.push_back(s[0]);
    }
    m_triangles[t] = {s[0], s[1], s[2], it->second, 1.0, 0.0};
    m_triangle_mol[t] = mol;
  }
  const std::size_t n_cells = m_cell_mol.size();
  m_cell_area.resize(n_cells);
  m_cell_volume.resize(n_cells);
  m_cell_volume_factor.resize(n_cells);
  m_cell_origin.resize(n_cells);
  m_tri_normal.resize(n);
  m_tri_area.resize(n);
  return true;
}

bool FastBondPlan::cells_unchanged(const ParticleStore& p) const {
  for (std::size_t t = 0; t < m_triangles.size(); ++t)
    if (p.mol_id[m_index[m_triangles[t].v0]] != m_triangle_mol[t])
      return false;
  return true;
}

void FastBondPlan::gather_positions(const ParticleStore& p) {
  for (std::size_t s = 0; s < m_index.size(); ++s)
    m_x[s] = p.pos[m_index[s]];
}

bool FastBondPlan::commit_forces(ParticleStore& p) const {
  double check = 0.0;
  for (const Vec3& f : m_f)
    check += f[0] + f[1] + f[2];
  if (!std::isfinite(check)) // NaN or inf anywhere: the generic loop names the bond
    return false;
  for (std::size_t s = 0; s < m_index.size(); ++s)
    p.force[m_index[s]] += m_f[s];
  return true;
}

// ---------------------------------------------------------------------------
// OifLocalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifLocalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_local);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_local(group, p);
    ++m_n_builds;
  }
  if (!m_usable)
    return false;
  gather_positions(p);
  if (ia.kvisc != 0.0)
    for (std::size_t s = 0; s < m_index.size(); ++s)
      m_v[s] = p.vel[m_index[s]];
  for (Vec3& f : m_f)
    f.setZero();

  // local area (eq. 5), once per triangle
  if (ia.kal != 0.0) {
    const double kal = ia.kal;
    for (const Triangle& t : m_triangles) {
      const Vec3& x0 = m_x[t.v0];
      const Vec3 e1 = box.minimum_image(m_x[t.v1], x0);
      const Vec3 e2 = box.minimum_image(m_x[t.v2], x0);
      const double area = 0.5 * e1.cross(e2).norm();
      if (!(area > 0.0))
        return false;
      add_centroid_allocated_edges(e1, e2, kal * (t.weight * area - t.area0), m_f[t.v0], m_f[t.v1],
                                   m_f[t.v2]);
    }
  }

  // edges: stretching (eq. 3), viscosity, bending (eq. 4)
  const double ks = ia.ks, kslin = ia.kslin, kvisc = ia.kvisc, kb = ia.kb;
  const bool edge_terms = ks != 0.0 || kslin != 0.0 || kvisc != 0.0;
  for (const EdgeBond& bd : m_bonds) {
    const Vec3& xb = m_x[bd.b];
    const Vec3 e = box.minimum_image(m_x[bd.c], xb); // c - b, the shared edge
    const double l2 = e.squaredNorm();
    if (!(l2 > 0.0))
      return false;
    const double l = std::sqrt(l2), inv_l2 = 1.0 / l2;
    if (edge_terms) {
      // force on b along e (c gets the opposite): eq. 3 and the viscosity
      const double stretch = (l - bd.r0) * l * inv_l2; // (l - l0) / l
      double coefficient = 0.0;
      if (ks != 0.0)
        coefficient += ks * neo_hookean_kappa(l * bd.inv_r0) * stretch;
      if (kslin != 0.0)
        coefficient += kslin * stretch;
      if (kvisc != 0.0)
        coefficient += kvisc * (m_v[bd.c] - m_v[bd.b]).dot(e) * inv_l2;
      const Vec3 fe = coefficient * e;
      m_f[bd.b] += fe;
      m_f[bd.c] -= fe;
    }
    if (kb != 0.0) {
      // the dihedral angle and its gradient of oif_bending.hpp
      const Vec3 u = box.minimum_image(m_x[bd.a], xb); // a - b
      const Vec3 w = box.minimum_image(m_x[bd.d], xb); // d - b
      const Vec3 n1 = u.cross(e), n2 = e.cross(w);
      const double n1_2 = n1.squaredNorm(), n2_2 = n2.squaredNorm();
      if (!(n1_2 > 0.0) || !(n2_2 > 0.0))
        return false;
      // psi = atan2((n1 x n2).e / l, n1.n2), and (n1 x n2).e / l = l n1.w;
      // phi - phi0 = -(psi - psi0) with psi0 = pi - phi0, taken as one angle
      const double y = l * n1.dot(w), x = n1.dot(n2);
      double dphi = -angle_from_reference(y * bd.cos_psi0 - x * bd.sin_psi0,
                                          x * bd.cos_psi0 + y * bd.sin_psi0);
      if (dphi <= -M_PI) // into (-pi, pi] as the generic bending
        dphi += 2.0 * M_PI;
      // F = -kb dphi grad phi: on the wings kb dphi l n / |n|^2, the edge ends
      // split by the wings' foot points ta, td (oif_bending.hpp)
      const double c = kb * dphi * l / (n1_2 * n2_2);
      const Vec3 fa = (c * n2_2) * n1;
      const Vec3 fd = (c * n1_2) * n2;
      const double ta = u.dot(e) * inv_l2, td = w.dot(e) * inv_l2;
      m_f[bd.a] += fa;
      m_f[bd.d] += fd;
      m_f[bd.b] -= (1.0 - ta) * fa + (1.0 - td) * fd;
      m_f[bd.c] -= ta * fa + td * fd;
    }
  }
  return commit_forces(p);
}

// ---------------------------------------------------------------------------
// OifGlobalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifGlobalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_global);
  if (!(key == m_key) || (m_usable && !cells_unchanged(p))) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
  }
  if (!m_usable)
    return false;
  gather_positions(p);
  const std::size_t n_cells = m_cell_mol.size();
  for (std::size_t c = 0; c < n_cells; ++c) {
    const int i = m_index[m_cell_reference[c]];
    m_cell_origin[c] = box.unfolded(p.pos[i], p.image[i]);
    m_cell_area[c] = 0.0;
    m_cell_volume[c] = 0.0;
  }
  // per-cell surface and volume (oif_cell_sums.hpp): with a the first vertex
  // relative to the cell's reference point (unfolded) and N = (b-a) x (c-a),
  // a . (b x c) = a . N
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Triangle& tr = m_triangles[t];
    const Vec3& x0 = m_x[tr.v0];
    const Vec3 n = box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
    const double area = 0.5 * n.norm();
    const Vec3 a = box.unfolded(x0, p.image[m_index[tr.v0]]) - m_cell_origin[tr.cell];
    m_cell_area[tr.cell] += area;
    m_cell_volume[tr.cell] += a.dot(n) / 6.0;
    m_tri_normal[t] = n;
    m_tri_area[t] = area;
  }
  for (Vec3& f : m_f)
    f.setZero();
  const double ka_g = ia.ka_g, kv = ia.kv, A0_g = ia.A0_g, V0 = ia.V0;
  // volume (eq. 7, oif_volume.hpp): F = -kv (|V| - V0)/V0 s N / 6 on each vertex
  for (std::size_t c = 0; c < n_cells; ++c) {
    const double v = m_cell_volume[c];
    const double s = v < 0.0 ? -1.0 : 1.0;
    m_cell_volume_factor[c] = kv != 0.0 ? -kv * ((s * v - V0) / V0) * s / 6.0 : 0.0;
  }
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Triangle& tr = m_triangles[t];
    const double area = m_tri_area[t], cell_area = m_cell_area[tr.cell];
    if (!(area > 0.0) || !(cell_area > 0.0))
      return false;
    if (ka_g != 0.0) {
      const Vec3& x0 = m_x[tr.v0];
      add_centroid_allocated_edges(
          box.minimum_image(m_x[tr.v1], x0), box.minimum_image(m_x[tr.v2], x0),
          global_area_coefficient(area, cell_area, A0_g, ka_g), m_f[tr.v0], m_f[tr.v1], m_f[tr.v2]);
    }
    if (kv != 0.0) {
      const Vec3 fv = m_cell_volume_factor[tr.cell] * m_tri_normal[t];
      m_f[tr.v0] += fv;
      m_f[tr.v1] += fv;
      m_f[tr.v2] += fv;
    }
  }
  return commit_forces(p);
}

// ---------------------------------------------------------------------------
// OifOutDirection
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifOutDirection&, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_out_direction);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
    if (m_usable) {
      // a cell's orientation is fixed by its mesh: the sign of its oriented
      // volume, determined once per set of bonds (as OifOutDirection does)
      gather_positions(p);
      std::vector<double> volume(m_cell_mol.size(), 0.0);
      for (std::size_t c = 0; c < m_cell_mol.size(); ++c) {
        const int i = m_index[m_cell_reference[c]];
        m_cell_origin[c] = box.unfolded(p.pos[i], p.image[i]);
      }
      for (const Triangle& tr : m_triangles) {
        const Vec3& x0 = m_x[tr.v0];
        const Vec3 n = box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
        volume[tr.cell] +=
            (box.unfolded(x0, p.image[m_index[tr.v0]]) - m_cell_origin[tr.cell]).dot(n);
      }
      m_outward_sign.resize(m_triangles.size());
      for (std::size_t t = 0; t < m_triangles.size(); ++t)
        m_outward_sign[t] = volume[m_triangles[t].cell] < 0.0 ? -1.0 : 1.0;
    }
  }
  if (!m_usable)
    return false;
  gather_positions(p);
  for (Vec3& f : m_f)
    f.setZero();
  // area-weighted normal of each node: the sum of its triangles' 2 S n
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Triangle& tr = m_triangles[t];
    const Vec3& x0 = m_x[tr.v0];
    const Vec3 n = m_outward_sign[t] *
                   box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
    m_f[tr.v0] += n;
    m_f[tr.v1] += n;
    m_f[tr.v2] += n;
  }
  for (std::size_t s = 0; s < m_index.size(); ++s) {
    const double len = m_f[s].norm();
    p.normal[m_index[s]] = len > 0.0 ? Vec3(m_f[s] / len) : m_f[s];
  }
  return true;
}

} // namespace pyoif::oif
