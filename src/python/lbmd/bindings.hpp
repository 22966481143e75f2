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

}  // namespace pyoif::python
