// PLACEHOLDER: filled by the lb work.
#include "bindings.hpp"

namespace pyoif::python {
void bind_lb(pybind11::module_& /*m*/) {}
}  // namespace pyoif::python
