// Storage of the bonds of one bonded interaction: particle ids, n per bond,
// flattened; optionally per-bond reference values (e.g. relaxed lengths and
// angles of OIF bonds), stride values per bond. One group per interaction keeps
// the bond loop contiguous and free of per-bond dispatch.
#pragma once

#include <vector>

namespace pyoif {

struct BondGroup {
  int n_particles = 2;          ///< particles per bond (owner first)
  int per_bond_stride = 0;      ///< reference values per bond
  std::vector<int> ids;         ///< n_particles * n_bonds particle ids
  std::vector<double> per_bond; ///< per_bond_stride * n_bonds values

  std::size_t size() const { return n_particles ? ids.size() / n_particles : 0; }
  const int* bond(std::size_t b) const { return ids.data() + b * n_particles; }
  const double* reference(std::size_t b) const {
    return per_bond_stride ? per_bond.data() + b * per_bond_stride : nullptr;
  }
};

} // namespace pyoif
