// PLACEHOLDER: filled by the oif work.
#include "bindings.hpp"

namespace pyoif::python {
void bind_oif(pybind11::module_& /*m*/) {}
}  // namespace pyoif::python
