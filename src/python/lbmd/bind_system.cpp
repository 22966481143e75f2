// System, particles, cell system, thermostats, integrator and analysis.
#include "bindings.hpp"

#include "system/system.hpp"
#include "utils/errors.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <csignal>
#include <limits>
#include <optional>
#include <signal.h>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace pyoif::python {

namespace {

/** While alive, SIGINT only sets a flag (read by pending()); the previous
 *  disposition (Python's handler) comes back with restore() or at the end. */
class SigintNote {
public:
  SigintNote() {
    s_flag = 0;
    struct sigaction ours {};
    ours.sa_handler = &SigintNote::note;
    sigemptyset(&ours.sa_mask);
    m_active = sigaction(SIGINT, &ours, &m_previous) == 0;
  }
  ~SigintNote() { restore(); }
  SigintNote(const SigintNote&) = delete;
  SigintNote& operator=(const SigintNote&) = delete;
  void restore() {
    if (m_active)
      sigaction(SIGINT, &m_previous, nullptr);
    m_active = false;
  }
  static bool pending() { return s_flag != 0; }

private:
  static void note(int) { s_flag = 1; }
  static inline volatile std::sig_atomic_t s_flag = 0;
  struct sigaction m_previous {};
  bool m_active = false;
};

/** Walltime signals (lbmd.checkpoint.stop_on_signal): while armed, the
 *  signals only set a flag; a run stops at its next interruption point once
 *  any rank has it (agreed over MPI_COMM_WORLD), and Python writes the
 *  checkpoint. */
class StopSignals {
public:
  static void arm(const std::vector<int>& signals) {
    disarm();
    for (int sig : signals) {
      struct sigaction ours {
      }, previous{};
      ours.sa_handler = &StopSignals::note;
      sigemptyset(&ours.sa_mask);
      if (sigaction(sig, &ours, &previous) != 0)
        throw InputError("stop_on_signal: cannot handle signal " + std::to_string(sig));
      s_previous.emplace_back(sig, previous);
    }
    s_flag = 0;
  }
  static void disarm() {
    for (auto& [sig, previous] : s_previous)
      sigaction(sig, &previous, nullptr);
    s_previous.clear();
  }
  static bool armed() { return !s_previous.empty(); }
  /** Whether a signal came on any rank (collective when armed under MPI). */
  static bool agreed() {
    int pending = s_flag != 0;
    int initialized = 0, size = 1;
    MPI_Initialized(&initialized);
    if (initialized)
      MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (size > 1)
      MPI_Allreduce(MPI_IN_PLACE, &pending, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return pending != 0;
  }
  static void clear() { s_flag = 0; }

private:
  static void note(int) { s_flag = 1; }
  static inline volatile std::sig_atomic_t s_flag = 0;
  static inline std::vector<std::pair<int, struct sigaction>> s_previous;
};

using IdArray = py::array_t<int, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::vector<int> indices_of(const System& s, const IdArray& ids) {
  std::vector<int> idx(ids.size());
  auto r = ids.unchecked<1>();
  for (py::ssize_t i = 0; i < r.shape(0); ++i)
    idx[i] = s.checked_index(r(i));
  return idx;
}

RealArray get_vectors(System& s, const std::string& field, const IdArray& ids) {
  collective_entry("a particle property query");
  s.synchronize(); // spread over ranks: every copy current (collective)
  const auto idx = indices_of(s, ids);
  RealArray out({static_cast<py::ssize_t>(idx.size()), py::ssize_t{3}});
  auto w = out.mutable_unchecked<2>();
  const auto& p = s.particles;
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const int i = idx[n];
    Vec3 v = Vec3::Zero();
    if (field == "pos")
      v = s.box.unfolded(p.pos[i], p.image[i]);
    else if (field == "pos_folded")
      v = s.box.folded(p.pos[i]);
    else if (field == "v")
      v = p.vel[i];
    else if (field == "f")
      v = p.force[i];
    else if (field == "ext_force")
      v = p.ext_force[i];
    else if (field == "image_box")
      v = (p.image[i].cast<double>() +
           (p.pos[i] - s.box.folded(p.pos[i])).cwiseQuotient(s.box.length()))
              .array()
              .round()
              .matrix();
    else if (field == "normal")
      v = p.normal[i];
    else
      throw InputError("unknown vector property '" + field + "'");
    for (int d = 0; d < 3; ++d)
      w(n, d) = v[d];
  }
  return out;
}

void set_vectors(System& s, const std::string& field, const IdArray& ids, const RealArray& values) {
  collective_entry("setting a particle property");
  s.synchronize();
  const auto idx = indices_of(s, ids);
  if (values.ndim() != 2 || values.shape(0) != static_cast<py::ssize_t>(idx.size()) ||
      values.shape(1) != 3)
    throw InputError(field + ": expected an array of shape (" + std::to_string(idx.size()) +
                     ", 3)");
  auto r = values.unchecked<2>();
  auto& p = s.particles;
  if (field != "pos" && field != "v" && field != "ext_force" && field != "f")
    throw InputError("property '" + field + "' cannot be set");
  // all values are checked before any is set: a refused slice stays as it was
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const Vec3 v(r(n, 0), r(n, 1), r(n, 2));
    if (!v.allFinite())
      throw InputError(field + ": values must be finite (particle " + std::to_string(p.id[idx[n]]) +
                       ")");
    if (field == "pos")
      s.check_position_range(v, p.id[idx[n]]);
  }
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const Vec3 v(r(n, 0), r(n, 1), r(n, 2));
    const int i = idx[n];
    if (field == "pos") {
      p.pos[i] = v;
      p.image[i].setZero();
      s.cells.invalidate();
    } else if (field == "v")
      p.vel[i] = v;
    else if (field == "ext_force")
      p.ext_force[i] = v;
    else
      p.force[i] = v;
  }
  if (field != "f") // forces set by hand are the ones to start from
    s.invalidate_forces();
}

py::array get_scalars(const System& s, const std::string& field, const IdArray& ids) {
  const auto idx = indices_of(s, ids);
  const auto& p = s.particles;
  if (field == "mass") {
    RealArray out(static_cast<py::ssize_t>(idx.size()));
    auto w = out.mutable_unchecked<1>();
    for (std::size_t n = 0; n < idx.size(); ++n)
      w(n) = p.mass[idx[n]];
    return std::move(out);
  }
  py::array_t<int> out(static_cast<py::ssize_t>(idx.size()));
  auto w = out.mutable_unchecked<1>();
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const int i = idx[n];
    if (field == "type")
      w(n) = p.type[i];
    else if (field == "mol_id")
      w(n) = p.mol_id[i];
    else if (field == "fix")
      w(n) = p.fixed[i];
    else
      throw InputError("unknown property '" + field + "'");
  }
  return std::move(out);
}

void set_scalars(System& s, const std::string& field, const IdArray& ids, const RealArray& values) {
  collective_entry("setting a particle property");
  s.synchronize();
  enum class Scalar { mass, type, mol_id, fix };
  const Scalar which = field == "mass"     ? Scalar::mass
                       : field == "type"   ? Scalar::type
                       : field == "mol_id" ? Scalar::mol_id
                       : field == "fix"
                           ? Scalar::fix
                           : throw InputError("property '" + field + "' cannot be set");
  const auto idx = indices_of(s, ids);
  if (values.ndim() != 1 || values.shape(0) != static_cast<py::ssize_t>(idx.size()))
    throw InputError(field + ": expected " + std::to_string(idx.size()) + " values");
  auto r = values.unchecked<1>();
  auto& p = s.particles;
  constexpr double int_max = std::numeric_limits<int>::max();
  constexpr double int_min = std::numeric_limits<int>::min();
  auto integral_in = [](double x, double lo, double hi) {
    // NaN and values beyond int would turn into arbitrary ids
    return x >= lo && x <= hi && x == std::floor(x);
  };
  // all values are checked before any is set: a refused slice stays as it was
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const double x = r(n);
    switch (which) {
    case Scalar::mass:
      if (!(x > 0.0) || !std::isfinite(x))
        throw InputError("mass must be a finite positive number, got " + format_number(x));
      break;
    case Scalar::type:
      if (!integral_in(x, 0.0, int_max))
        throw InputError("type must be an integer in 0.." +
                         std::to_string(std::numeric_limits<int>::max()) + ", got " +
                         format_number(x));
      break;
    case Scalar::mol_id:
      if (!integral_in(x, int_min, int_max))
        throw InputError("mol_id must be an integer, got " + format_number(x));
      break;
    case Scalar::fix:
      if (!integral_in(x, 0.0, 7.0))
        throw InputError("fix must be a mask of 3 flags (0..7), got " + format_number(x));
      break;
    }
  }
  for (std::size_t n = 0; n < idx.size(); ++n) {
    const int i = idx[n];
    const double x = r(n);
    switch (which) {
    case Scalar::mass:
      p.mass[i] = x;
      break;
    case Scalar::type:
      p.type[i] = static_cast<int>(x);
      break;
    case Scalar::mol_id:
      p.mol_id[i] = static_cast<int>(x);
      ++p.mol_version; // the membranes regroup their cells
      break;
    case Scalar::fix:
      p.fixed[i] = static_cast<std::uint8_t>(x);
      break;
    }
  }
  if (which == Scalar::type)
    s.cells.invalidate();
  if (which == Scalar::type || which == Scalar::mol_id) // the interactions that apply change
    s.invalidate_forces();
}

IdArray add_particles(System& s, const IdArray& ids, const RealArray& pos, const RealArray& vel,
                      const RealArray& mass, const IdArray& type, const IdArray& mol_id,
                      const RealArray& ext_force, const IdArray& fixed) {
  s.synchronize();
  const py::ssize_t n = pos.ndim() == 2 ? pos.shape(0) : 0;
  // every array one row per particle (a checkpoint's arrays come here unchecked)
  const auto rows = [n](const auto& a, int ndim, const char* name) {
    if (a.ndim() != ndim || a.shape(0) != n || (ndim == 2 && a.shape(1) != 3))
      throw InputError(std::string("add_particles: '") + name + "' must have shape (" +
                       std::to_string(n) + (ndim == 2 ? ", 3)" : ",)") + " like 'pos'");
  };
  rows(pos, 2, "pos");
  rows(ids, 1, "ids");
  rows(vel, 2, "v");
  rows(mass, 1, "mass");
  rows(type, 1, "type");
  rows(mol_id, 1, "mol_id");
  rows(ext_force, 2, "ext_force");
  rows(fixed, 1, "fixed");
  auto id_r = ids.unchecked<1>();
  auto p_r = pos.unchecked<2>();
  auto v_r = vel.unchecked<2>();
  auto m_r = mass.unchecked<1>();
  auto t_r = type.unchecked<1>();
  auto mol_r = mol_id.unchecked<1>();
  auto f_r = ext_force.unchecked<2>();
  auto fix_r = fixed.unchecked<1>();
  IdArray out(n);
  auto w = out.mutable_unchecked<1>();
  // all or nothing: a row refused (or memory running out) part way through
  // takes the particles of this call out again
  py::ssize_t added = 0;
  try {
    for (py::ssize_t i = 0; i < n; ++i, ++added)
      w(i) = s.add_particle(id_r(i), Vec3(p_r(i, 0), p_r(i, 1), p_r(i, 2)),
                            Vec3(v_r(i, 0), v_r(i, 1), v_r(i, 2)), m_r(i), t_r(i), mol_r(i),
                            Vec3(f_r(i, 0), f_r(i, 1), f_r(i, 2)),
                            static_cast<std::uint8_t>(fix_r(i)));
  } catch (...) {
    // particles just added have no bonds or exclusions (removing a particle
    // removes those of its id): taking them out of the store is enough, not
    // System::remove_particle's pass over every bond group per particle
    for (py::ssize_t i = added - 1; i >= 0; --i)
      s.particles.remove(w(i));
    s.cells.invalidate();
    s.invalidate_forces();
    throw;
  }
  return out;
}

IdArray all_ids(const System& s) {
  std::vector<int> ids(s.particles.id);
  std::sort(ids.begin(), ids.end());
  IdArray out(static_cast<py::ssize_t>(ids.size()));
  std::copy(ids.begin(), ids.end(), out.mutable_data());
  return out;
}

/** Pairs of particle ids closer than `distance` (minimum image), from the
 *  neighbour search: used by tests against brute force and by analysis. */
std::vector<std::tuple<int, int>> get_pairs(System& s, double distance) {
  s.synchronize();
  if (distance > s.nonbonded.max_range() + s.cells.skin)
    throw InputError("get_pairs: distance must not exceed the interaction range "
                     "(largest cutoff + skin)");
  s.compute_forces();
  std::vector<std::tuple<int, int>> out;
  const auto& p = s.particles;
  for (const auto& pr : s.cells.pairs()) {
    if ((p.position(pr[0]) - p.position(pr[1])).norm() >= distance)
      continue;
    int a = p.id[p.owner(pr[0])], b = p.id[p.owner(pr[1])];
    out.emplace_back(std::min(a, b), std::max(a, b));
  }
  return out;
}

} // namespace

void bind_system(py::module_& m) {
  py::class_<LangevinParams>(m, "LangevinParams")
      .def_readonly("active", &LangevinParams::active)
      .def_readonly("kT", &LangevinParams::kT)
      .def_readonly("gamma", &LangevinParams::gamma)
      .def_readonly("seed", &LangevinParams::seed);

  m.def("arm_stop_signals", &StopSignals::arm,
        "lbmd.checkpoint.stop_on_signal: these signals stop a run (empty list: none)");
  m.def("clear_stop_signal", &StopSignals::clear);
  py::class_<System, std::shared_ptr<System>>(m, "System")
      .def(py::init<const Vec3&, const std::array<bool, 3>&>(), py::arg("box_l"),
           py::arg("periodicity"))
      .def_property(
          "box_l", [](const System& s) { return s.box.length(); },
          [](System& s, const Vec3& l) { s.set_box_l(l); })
      .def_property(
          "periodicity", [](const System& s) { return s.box.periodic(); },
          [](System& s, const std::array<bool, 3>& p) { s.set_periodicity(p); })
      .def_property("time_step", &System::time_step, &System::set_time_step)
      .def_readwrite("time", &System::time)
      .def_readonly("step_count", &System::step_count)
      .def_property(
          "skin", [](const System& s) { return s.cells.skin; },
          [](System& s, double skin) {
            if (!(skin >= 0.0) || !std::isfinite(skin))
              throw InputError("skin must be a finite non-negative number");
            s.cells.skin = skin;
            s.cells.invalidate();
          })
      .def_property_readonly("particles_spread", &System::particles_spread)
      .def_property_readonly("n_rebuilds", [](const System& s) { return s.cells.n_rebuilds(); })
      .def("run_timings",
           [](const System& s) {
             const System::RunTimings& t = s.run_timings;
             py::dict d;
             d["steps"] = t.steps;
             d["total"] = t.total;
             d["membrane"] = t.membrane;
             d["bonded"] = t.bonded;
             d["non_bonded"] = t.non_bonded;
             d["constraints"] = t.constraints;
             d["coupling"] = t.coupling;
             d["lb_fluid"] = t.lb_fluid;
             return d;
           })
      .def("reset_run_timings", [](System& s) { s.run_timings = System::RunTimings{}; })
      .def_property_readonly("max_range", [](const System& s) { return s.nonbonded.max_range(); })
      .def_property_readonly("rank",
                             [](const System&) { return Communicator(MPI_COMM_WORLD).rank(); })
      .def_property_readonly("n_ranks",
                             [](const System&) { return Communicator(MPI_COMM_WORLD).size(); })
      // particles
      .def("add_particles", &add_particles)
      .def("remove_particle",
           [](System& s, int pid) {
             s.synchronize();
             s.remove_particle(pid);
           })
      .def("clear_particles",
           [](System& s) {
             s.synchronize();
             s.clear_particles();
           })
      .def("n_particles", [](const System& s) { return s.particles.n_local(); })
      .def("exists", [](const System& s, int pid) { return s.particles.index(pid) >= 0; })
      .def("all_ids", &all_ids)
      .def("max_id", [](const System& s) { return s.particles.max_id(); })
      .def("get_vectors", &get_vectors)
      .def("set_vectors", &set_vectors)
      .def("get_scalars", &get_scalars)
      .def("set_scalars", &set_scalars)
      .def("add_exclusion", &System::add_exclusion)
      .def("remove_exclusion", &System::remove_exclusion)
      .def("get_pairs", &get_pairs)
      // thermostats
      .def("set_langevin",
           [](System& s, double kT, double gamma, std::uint64_t seed) {
             s.set_langevin({true, kT, gamma, seed});
           })
      .def("langevin_off", &System::langevin_off)
      // the cells' checks in a run (System::cell_checks, Membranes)
      .def_readwrite("cell_checks", &System::cell_checks)
      .def_property(
          "cell_drift_tolerance", [](const System& s) { return s.membranes.drift_tolerance; },
          [](System& s, double tolerance) {
            if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
              throw InputError("cell_drift_tolerance must be a finite number >= 0 (a fraction, "
                               "e.g. 0.05; 0 switches the warnings off), got " +
                               format_number(tolerance));
            s.membranes.drift_tolerance = tolerance;
          })
      .def("take_drift_notes",
           [](System& s) {
             // every rank's notes (each cell is checked by the rank that owns it)
             std::vector<py::tuple> out;
             for (const auto& n : s.membranes.take_drift_notes())
               out.push_back(py::make_tuple(n.mol_id, n.quantity, n.ratio, n.time, n.step));
             return out;
           })
      .def_property_readonly("langevin", [](const System& s) { return s.langevin(); })
      // integration
      // The run keeps the GIL: no other Python thread can change the system
      // under it. With `interruptible` (the caller checked: main thread, one
      // MPI rank, a Python SIGINT handler in place) Ctrl-C only sets a flag
      // during the run; every 16 steps the loop stops if it is set, in a
      // consistent state, and the Python handler then runs between steps
      // (KeyboardInterrupt by default; a handler that returns lets the run
      // go on). No Python code runs in the middle of a step.
      .def(
          "prepare",
          [](System& s) {
            collective_entry("system.prepare()");
            s.prepare();
          },
          "Collective: flags the lattice for boundaries set since the last call (which may "
          "move the ranks' cuts); integrate() begins with it, queries never call it.")
      .def(
          "integrate",
          [](System& s, int steps, bool recalc_forces, bool reuse_forces, bool interruptible) {
            // returns whether a walltime signal stopped the run (StopSignals)
            const bool stoppable = StopSignals::armed();
            if (stoppable && StopSignals::agreed())
              return true; // a signal between runs: stop before the first step
            if (!interruptible && !stoppable) {
              s.integrate(steps, recalc_forces, reuse_forces);
              return false;
            }
            struct Interrupted {};
            struct Stopped {};
            struct ClearPoint {
              System& s;
              ~ClearPoint() { s.interruption_point = nullptr; }
            } clear_point{s};
            s.interruption_point = [interruptible, stoppable] {
              if (interruptible && SigintNote::pending())
                throw Interrupted{};
              if (stoppable && StopSignals::agreed())
                throw Stopped{};
            };
            // the signal, handed to Python's own machinery once the state is
            // consistent: its handler runs here
            auto hand_to_python = [] {
              PyErr_SetInterrupt();
              if (PyErr_CheckSignals() != 0)
                throw py::error_already_set();
            };
            int remaining = steps;
            while (true) {
              std::optional<SigintNote> note; // our C handler while the loop runs
              if (interruptible)
                note.emplace();
              const std::uint64_t start = s.step_count;
              bool finished = false;
              try {
                s.integrate(remaining, recalc_forces, reuse_forces);
                finished = true;
              } catch (const Interrupted&) {
              } catch (const Stopped&) {
                return true;
              }
              if (note)
                note->restore();
              if (finished) {
                // a signal after the last interruption point (a run shorter
                // than 16 steps, its last steps): handled after the run
                if (interruptible && SigintNote::pending())
                  hand_to_python();
                return false;
              }
              remaining -= static_cast<int>(s.step_count - start);
              recalc_forces = reuse_forces = false; // the forces are those of the last step
              hand_to_python();
            }
          },
          py::arg("steps"), py::arg("recalc_forces") = false, py::arg("reuse_forces") = false,
          py::arg("interruptible") = false)
      .def("compute_forces", &System::compute_forces)
      .def("energies",
           [](System& s) {
             collective_entry("analysis.energy()");
             const Energies e = s.compute_energies();
             py::dict d;
             d["total"] = e.total();
             d["kinetic"] = e.kinetic;
             d["bonded"] = e.bonded;
             d["non_bonded"] = e.non_bonded;
             for (const auto& [id, value] : e.bonded_by_id)
               d[py::make_tuple("bonded", id)] = value;
             return d;
           })
      .def("particle_momentum", &System::particle_momentum)
      .def("fluid_momentum", &System::fluid_momentum);
}

} // namespace pyoif::python
