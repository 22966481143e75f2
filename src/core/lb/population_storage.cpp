#include "lb/population_storage.hpp"

#include <cstdlib>
#include <cstring>
#include <new>

namespace pyoif::lb {

PopulationStorage::~PopulationStorage() {
  std::free(m_data);
}

void PopulationStorage::allocate(std::size_t n_nodes,
                                 const std::array<std::ptrdiff_t, d3q19::Q>& neighbour_offset,
                                 bool single_precision, double rest_density) {
  m_single = single_precision;
  m_rest_density = rest_density;
  m_stride = ((n_nodes + 7) / 8) * 8;
  std::free(m_data);
  m_data = nullptr;
  const std::size_t bytes = ((d3q19::Q * m_stride * value_bytes() + 63) / 64) * 64;
  m_data = std::aligned_alloc(64, bytes);
  if (!m_data)
    throw std::bad_alloc();
  clear();
  for (int q = 0; q < d3q19::Q; ++q) {
    m_read_normal[q] = static_cast<std::ptrdiff_t>(q * m_stride);
    m_read_swapped[q] =
        static_cast<std::ptrdiff_t>(d3q19::opposite(q) * m_stride) - neighbour_offset[q];
  }
  m_swapped = false;
}

void PopulationStorage::clear() {
  std::memset(m_data, 0, d3q19::Q * m_stride * value_bytes()); // 0.0 in either type
}

} // namespace pyoif::lb
