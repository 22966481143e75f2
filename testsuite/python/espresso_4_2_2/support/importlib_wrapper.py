"""Stand-in for ESPResSo's testsuite/scripts/importlib_wrapper.py, written for
this project: what ESPResSo's sample tests use of it. ``configure_and_import``
imports a sample after replacing the values of some of its top-level
assignments (``maxCycle=4`` makes ``maxCycle = 50`` read ``maxCycle = 4``, the
original kept as a comment) and with ``sys.argv`` set to the sample's path and
``cmd_arguments`` during the import; it returns the module and a skip decorator (the engine
raises FeaturesError at ``assert_features`` for what it lacks, so the
decorator never skips)."""
import importlib.util
import os
import re
import sys


def substitute_variable_values(code, **parameters):
    """Replace the right-hand side of the first top-level ``name = ...`` of
    each parameter; a parameter not assigned in the code is an error."""
    for name, value in parameters.items():
        pattern = re.compile(rf"^{re.escape(name)}\s*=\s*(.*)$", re.MULTILINE)
        match = pattern.search(code)
        if match is None:
            raise AssertionError(f"importlib_wrapper: '{name}' is not assigned at top level in the sample")
        line = f"{name} = {value!r}  # original value: {match.group(1)}"
        code = code[:match.start()] + line + code[match.end():]
    return code


def configure_and_import(filepath, gpu=False, script_suffix="", cmd_arguments=None, **parameters):
    filepath = os.path.abspath(str(filepath))
    with open(filepath) as f:
        code = substitute_variable_values(f.read(), **parameters)
    name = os.path.splitext(os.path.basename(filepath))[0] + "_processed" + script_suffix
    argv = sys.argv
    sys.argv = [filepath] + [str(a) for a in (cmd_arguments or [])]
    spec = importlib.util.spec_from_loader(name, loader=None, origin=filepath)
    module = importlib.util.module_from_spec(spec)
    module.__file__ = filepath
    sys.modules[name] = module
    try:
        exec(compile(code, filepath, "exec"), module.__dict__)
    finally:
        sys.argv = argv  # the test's own unittest.main() reads it
    return module, (lambda x: x)
