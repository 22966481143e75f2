// Lattice-Boltzmann fluid, its boundaries and the particle coupling.
#include "bindings.hpp"

#include "lb/lb_coupling.hpp"
#include "lb/lb_fluid.hpp"
#include "lb/lb_roofline.hpp"
#include "system/system.hpp"
#include "utils/errors.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <tuple>

#include <string>

namespace py = pybind11;

namespace pyoif::python {

namespace {

using lb::LBFluid;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

lb::Collision collision_of(const std::string& name) {
  if (name == "MRT")
    return lb::Collision::mrt;
  if (name == "MRT_ESPRESSO")
    return lb::Collision::mrt_espresso;
  if (name == "TRT")
    return lb::Collision::trt;
  if (name == "BGK")
    return lb::Collision::bgk;
  throw InputError("collision must be 'MRT', 'MRT_ESPRESSO', 'TRT' or 'BGK', got '" + name + "'");
}

/** Values of property prop on the block lo <= (i, j, k) < hi, shape
 *  (nx, ny, nz, components); collective under MPI (LBFluid::get_block). */
/** A block's values as an array of shape (nx, ny, nz, components); no
 *  values (a gather's other ranks): an empty array. */
RealArray block_array(const std::vector<double>& values, const Vec3i& lo, const Vec3i& hi) {
  if (values.empty())
    return RealArray(std::vector<py::ssize_t>{0});
  const Vec3i n = hi - lo;
  const py::ssize_t nc = static_cast<py::ssize_t>(values.size() / n.prod());
  RealArray out({static_cast<py::ssize_t>(n[0]), static_cast<py::ssize_t>(n[1]),
                 static_cast<py::ssize_t>(n[2]), nc});
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

RealArray get_block(const LBFluid& fluid, const std::string& prop, const Vec3i& lo,
                    const Vec3i& hi) {
  collective_entry("a query of the fluid's nodes");
  return block_array(fluid.get_block(prop, lo, hi), lo, hi);
}

void set_block(LBFluid& fluid, const std::string& prop, const Vec3i& lo, const Vec3i& hi,
               const RealArray& values) {
  collective_entry("setting the fluid's nodes");
  fluid.set_block(prop, lo, hi, std::vector<double>(values.data(), values.data() + values.size()));
}

/** gather_block: the block on rank `root` as get_block's array, an empty
 *  array elsewhere; collective. */
RealArray gather_block(const LBFluid& fluid, const std::string& prop, const Vec3i& lo,
                       const Vec3i& hi, int root) {
  collective_entry("a gather of the fluid's nodes");
  return block_array(fluid.gather_block(prop, lo, hi, root), lo, hi);
}

void scatter_block(LBFluid& fluid, const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                   const RealArray& values, int root) {
  collective_entry("setting the fluid's nodes");
  // the values read in place (no copy: the root holds the whole block)
  fluid.scatter_block(prop, lo, hi, values.data(), static_cast<std::size_t>(values.size()), root);
}

} // namespace

void bind_lb(py::module_& m) {
  py::class_<LBFluid, std::shared_ptr<LBFluid>>(m, "LBFluid")
      .def(py::init([](double agrid, double tau, double dens, double visc, double bulk_visc,
                       const Vec3& ext_force_density, double kT, std::uint64_t seed,
                       const std::string& collision, int n_threads, const Vec3& box_l,
                       const Vec3i& node_grid, bool balance, bool single_precision) {
             lb::LBParams p;
             p.agrid = agrid;
             p.tau = tau;
             p.density = dens;
             p.viscosity = visc;
             p.bulk_viscosity = bulk_visc;
             p.ext_force_density = ext_force_density;
             p.kT = kT;
             p.seed = seed;
             p.collision = collision_of(collision);
             p.n_threads = n_threads;
             p.single_precision = single_precision;
             // every rank of the run takes part: the lattice is split over them
             return std::make_shared<LBFluid>(p, BoxGeometry(box_l, {true, true, true}),
                                              MPI_COMM_WORLD, node_grid, balance);
           }),
           py::arg("agrid"), py::arg("tau"), py::arg("dens"), py::arg("visc"), py::arg("bulk_visc"),
           py::arg("ext_force_density"), py::arg("kT"), py::arg("seed"), py::arg("collision"),
           py::arg("n_threads"), py::arg("box_l"), py::arg("node_grid") = Vec3i::Zero(),
           py::arg("balance") = true, py::arg("single_precision") = false)
      // the grid of subdomains is fixed when the fluid is made; the cuts
      // below are where the load balance of the flagging (system.prepare())
      // leaves them: refused while boundaries are pending
      .def_property_readonly("node_grid", [](const LBFluid& f) { return f.domain().dims(); })
      .def_property_readonly("decomposition",
                             [](const LBFluid& f) {
                               f.require_flagged("the decomposition");
                               return f.domain().describe();
                             })
      .def_property_readonly("local_origin",
                             [](const LBFluid& f) {
                               f.require_flagged("the decomposition");
                               return f.local_origin();
                             })
      .def_property_readonly("local_shape",
                             [](const LBFluid& f) {
                               f.require_flagged("the decomposition");
                               return f.local_grid();
                             })
      .def_property_readonly("n_flaggings", &LBFluid::n_flaggings,
                             "flagging passes so far (system.prepare() flags once for any number "
                             "of boundaries set since the last one)")
      .def_property_readonly("boundaries_pending", &LBFluid::boundaries_pending)
      .def_property_readonly("halo_bytes",
                             [](const LBFluid& f) {
                               f.require_flagged("the halo size");
                               return f.halo_bytes();
                             })
      .def_property_readonly("halo_seconds", &LBFluid::halo_seconds)
      .def_property_readonly("shared_halo_peers",
                             [](const LBFluid& f) {
                               f.require_flagged("the shared-memory halo peers");
                               return f.shared_halo_peers();
                             })
      .def_property_readonly("coupling_exchange_seconds", &LBFluid::coupling_exchange_seconds)
      .def_property_readonly("shape", [](const LBFluid& f) { return f.grid(); })
      .def_property_readonly("agrid", &LBFluid::agrid)
      .def_property_readonly("single_precision", &LBFluid::single_precision)
      .def_property_readonly("tau", &LBFluid::tau)
      .def_property_readonly("n_updates", &LBFluid::n_updates)
      .def_property_readonly("n_fluid_nodes",
                             [](const LBFluid& f) {
                               f.require_flagged("the number of fluid nodes");
                               return f.n_fluid_nodes();
                             })
      .def_property_readonly("n_links",
                             [](const LBFluid& f) {
                               f.require_flagged("the number of bounce-back links");
                               return f.n_links();
                             })
      .def_property("n_threads", &LBFluid::n_threads, &LBFluid::set_n_threads)
      .def_property_readonly("relaxation",
                             [](const LBFluid& f) {
                               const auto& r = f.relaxation();
                               return py::dict(py::arg("shear") = r.shear, py::arg("bulk") = r.bulk,
                                               py::arg("even") = r.even, py::arg("odd") = r.odd);
                             })
      .def("set_ext_force_density", &LBFluid::set_ext_force_density)
      .def(
          "step",
          [](LBFluid& f, int n) {
            if (n < 0)
              throw InputError("steps must be >= 0");
            // with the GIL held (no other thread changes the fluid under
            // it), Ctrl-C seen every 16 updates
            for (int i = 0; i < n; ++i) {
              f.step();
              if ((i & 15) == 15 && PyErr_CheckSignals() != 0)
                throw py::error_already_set();
            }
          },
          py::arg("n") = 1)
      .def_property("speed_watch_every", &LBFluid::speed_watch_every,
                    &LBFluid::set_speed_watch_every,
                    "lattice updates between two passes of the speed watch (0: off)")
      .def(
          "take_speed_watch",
          [](LBFluid& f) {
            // collective: every rank of the fluid calls it
            const lb::SpeedWatch w = f.take_speed_watch();
            if (!w.seen)
              return py::object(py::none());
            return py::object(py::make_tuple(w.mach, w.node, w.update));
          },
          "(Mach, global node, update) of the fastest node the watch saw since the last "
          "call, or None; collective")
      .def("total_mass", [](LBFluid& f) { return f.total_mass(); })
      .def("total_momentum", [](LBFluid& f) { return f.total_momentum(); })
      .def("set_boundaries",
           [](LBFluid& f, const std::vector<std::pair<std::shared_ptr<shapes::Shape>, Vec3>>& b) {
             std::vector<lb::BoundarySpec> specs;
             for (const auto& [shape, vel] : b)
               specs.push_back({shape, vel});
             f.set_boundaries(specs);
           })
      .def("set_open_boundaries",
           // (axis, high, pressure, velocities (3 per face node), density,
           // flow rate) per face
           [](LBFluid& f,
              const std::vector<std::tuple<int, bool, bool, std::vector<double>, double, double>>&
                  faces) {
             std::vector<lb::OpenBoundarySpec> specs;
             for (const auto& [axis, high, pressure, velocity, density, flow_rate] : faces)
               specs.push_back({axis, high, pressure, velocity, density, flow_rate, 1.0});
             f.set_open_boundaries(specs);
           })
      .def("open_seam_leaks", &LBFluid::open_seam_leaks,
           "per open face, fluid nodes of the closed opposite face that meet it across the "
           "periodic edge (0: none); collective")
      .def("open_boundary_gains", &LBFluid::open_boundary_gains)
      .def("set_open_boundary_gains", &LBFluid::set_open_boundary_gains)
      .def("open_boundary_mass_flux",
           [](LBFluid& f, std::size_t i) { return f.open_boundary_mass_flux(i); })
      .def("boundary_force", [](LBFluid& f, int b) { return f.boundary_force(b); })
      .def("get_block", &get_block)
      .def("set_block", &set_block)
      .def("gather_block", &gather_block)
      .def("scatter_block", &scatter_block)
      .def("write_vtk_velocity",
           [](LBFluid& f, const std::string& path) { f.write_vtk_velocity(path); })
      .def("write_vtk_boundary",
           [](LBFluid& f, const std::string& path) { f.write_vtk_boundary(path); });

  m.def(
      "copy_bandwidth",
      [](std::size_t n_doubles, int repeats, int n_threads) {
        py::gil_scoped_release release;
        return lb::copy_bandwidth(n_doubles, repeats, n_threads);
      },
      "STREAM-like copy bandwidth (bytes/s, 16 per element) for the LB roofline",
      py::arg("n_doubles"), py::arg("repeats") = 10, py::arg("n_threads") = 1);

  auto sys = py::reinterpret_borrow<py::class_<System, std::shared_ptr<System>>>(m.attr("System"));
  sys.def(
         "set_lb", [](System& s, std::shared_ptr<LBFluid> fluid) { s.set_lb(std::move(fluid)); },
         py::arg("fluid").none(true))
      .def("set_lb_coupling", &System::set_lb_coupling)
      .def("set_lb_coupling_off", &System::lb_coupling_off)
      .def("lb_interpolated_velocity", [](const System& s, const Vec3& pos) -> Vec3 {
        if (!s.fluid())
          throw InputError("no lattice-Boltzmann fluid is active");
        return lb::interpolated_velocity(*s.fluid(), s.box, pos);
      });
}

} // namespace pyoif::python
