// Parameters of every non-bonded model for each pair of particle types.
#pragma once

#include "interactions/nonbonded/nonbonded_registry.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace pyoif {

namespace detail {
template <class Tuple> struct params_of;
template <class... M> struct params_of<std::tuple<M...>> {
  using type = std::tuple<typename M::Params...>;
};
} // namespace detail

/** All models' parameters for one type pair. */
struct PairParams {
  detail::params_of<NonbondedModels>::type models;
  double range = 0.0; ///< largest active cutoff (0: no interaction)

  template <class M> typename M::Params& get() { return std::get<typename M::Params>(models); }
  template <class M> const typename M::Params& get() const {
    return std::get<typename M::Params>(models);
  }
  void update_range() {
    range = 0.0;
    std::apply(
        [&](const auto&... p) { ((range = p.active() ? std::max(range, p.range()) : range), ...); },
        models);
  }
};

class NonbondedTable {
public:
  /** Entry for types (t1, t2), symmetric; grows the table as needed. */
  PairParams& at(int t1, int t2) {
    check_type(t1);
    check_type(t2);
    const int n = std::max(t1, t2) + 1;
    if (n > m_n_types)
      resize(n);
    return m_entries[t1 * m_n_types + t2];
  }
  /** Entry for (t1, t2) to read, without growing the table (a pair outside
   *  it: the default entry, every model off). */
  const PairParams& entry_or_default(int t1, int t2) const {
    check_type(t1);
    check_type(t2);
    static const PairParams none{};
    if (t1 >= m_n_types || t2 >= m_n_types)
      return none;
    return m_entries[t1 * m_n_types + t2];
  }
  /** Entry for reading in the hot loop; nullptr when the types have no entry. */
  const PairParams* find(int t1, int t2) const {
    if (t1 >= m_n_types || t2 >= m_n_types)
      return nullptr;
    const PairParams& e = m_entries[t1 * m_n_types + t2];
    return e.range > 0.0 ? &e : nullptr;
  }
  /** Copy (t1,t2) to (t2,t1) and refresh the ranges after a parameter change. */
  void commit(int t1, int t2) {
    PairParams& e = at(t1, t2);
    e.update_range();
    at(t2, t1) = e;
    m_max_range = 0.0;
    for (const auto& entry : m_entries)
      m_max_range = std::max(m_max_range, entry.range);
  }
  /** Largest active cutoff over all type pairs (kept up to date by commit(),
   *  read every step by the neighbour search). */
  double max_range() const { return m_max_range; }
  int n_types() const { return m_n_types; }

  /** The table is dense in the largest type: 1024 types are 10^6 entries
   *  (about 100 MB); beyond, a typo would ask for gigabytes. */
  static constexpr int max_type = 1023;

private:
  static void check_type(int t) {
    if (t < 0 || t > max_type)
      throw InputError("non-bonded interactions: particle types must be integers in 0.." +
                       std::to_string(max_type) + ", got " + std::to_string(t));
  }
  void resize(int n) {
    std::vector<PairParams> e(static_cast<std::size_t>(n) * n);
    for (int i = 0; i < m_n_types; ++i)
      for (int j = 0; j < m_n_types; ++j)
        e[i * n + j] = m_entries[i * m_n_types + j];
    m_entries = std::move(e);
    m_n_types = n;
  }
  int m_n_types = 0;
  std::vector<PairParams> m_entries;
  double m_max_range = 0.0;
};

/** Force on i from all active models of one entry, and optionally the energy. */
inline Vec3 pair_force(const PairParams& params, const PairContext& c, double* energy = nullptr) {
  Vec3 f = Vec3::Zero();
  std::apply(
      [&](const auto&... p) {
        auto one = [&](const auto& prm) {
          using Model = typename std::decay_t<decltype(prm)>::Model;
          if (prm.active() && c.dist < prm.range()) {
            f += Model::force(prm, c);
            if (energy)
              *energy += Model::energy(prm, c);
          }
        };
        (one(p), ...);
      },
      params.models);
  return f;
}

} // namespace pyoif
