// PLACEHOLDER: replaced by the lattice-Boltzmann implementation.
#include "lb/lb_coupling.hpp"
#include "lb/lb_fluid.hpp"

namespace pyoif::lb {
void LBFluid::validate(const BoxGeometry&, double) const {}
void LBFluid::step() {}
Vec3 LBFluid::total_momentum() const { return Vec3::Zero(); }
double LBFluid::total_mass() const { return 0.0; }
void couple_particles(LBFluid&, ParticleStore&, const BoxGeometry&, const CouplingParams&,
                      std::uint64_t, double) {}
}  // namespace pyoif::lb
