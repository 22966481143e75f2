#include "particles/particle_store.hpp"

namespace pyoif {

std::size_t ParticleStore::add(int pid, const Vec3& p, const Vec3i& img, const Vec3& v, double m,
                               int t, int mol, const Vec3& fext, std::uint8_t fix) {
  const std::size_t idx = id.size();
  // the id map first: if it cannot grow (std::bad_alloc) nothing has changed
  if (static_cast<std::size_t>(pid) >= index_of_id.size())
    index_of_id.resize(static_cast<std::size_t>(pid) + 1, -1);
  layout_version = next_layout_version();
  id.push_back(pid);
  pos.push_back(p);
  image.push_back(img);
  vel.push_back(v);
  force.push_back(Vec3::Zero());
  ext_force.push_back(fext);
  normal.push_back(Vec3::Zero());
  mass.push_back(m);
  type.push_back(t);
  mol_id.push_back(mol);
  fixed.push_back(fix);
  index_of_id[pid] = static_cast<int>(idx);
  return idx;
}

void ParticleStore::remove(int pid) {
  const int idx = index(pid);
  if (idx < 0)
    return;
  const std::size_t last = id.size() - 1;
  layout_version = next_layout_version();
  auto move_last = [&](auto& vec) {
    vec[idx] = vec[last];
    vec.pop_back();
  };
  index_of_id[id[last]] = idx;
  index_of_id[pid] = -1;
  move_last(id);
  move_last(pos);
  move_last(image);
  move_last(vel);
  move_last(force);
  move_last(ext_force);
  move_last(normal);
  move_last(mass);
  move_last(type);
  move_last(mol_id);
  move_last(fixed);
  while (!index_of_id.empty() && index_of_id.back() < 0)
    index_of_id.pop_back();
  clear_ghosts();
}

void ParticleStore::clear() {
  *this = ParticleStore{};
} // a fresh layout_version

} // namespace pyoif
