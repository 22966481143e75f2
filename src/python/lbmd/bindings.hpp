// The binders of the _lbmd extension module, one per concern, each in its own
// source file; module.cpp calls them in order (bind_system first: the others
// add to the classes it creates).
#pragma once

#include <pybind11/pybind11.h>

namespace pyoif::python {

void bind_system(pybind11::module_& m);
void bind_interactions(pybind11::module_& m);
void bind_shapes(pybind11::module_& m);
void bind_lb(pybind11::module_& m);
void bind_oif(pybind11::module_& m);
void bind_checkpoint(pybind11::module_& m);
void bind_packing(pybind11::module_& m);

/** Called first by every collective query (particle properties, the
 *  fluid's nodes, analysis): under mpirun a non-blocking barrier of all
 *  ranks that says on stderr, after 10 s of waiting, that a query made on
 *  some ranks only never returns (collective.cpp). `what` names the query. */
void collective_entry(const char* what);

} // namespace pyoif::python
