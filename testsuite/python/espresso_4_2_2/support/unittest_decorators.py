"""Stand-in for ESPResSo's testsuite/python/unittest_decorators.py (the
decorators ESPResSo's tests import as ``utx``), written for this project: the
features are the lbmd engine's (lbmd.has_features). Only what the OIF tests
use."""
import importlib
import unittest

import lbmd


def no_skip(x):
    return x


def skipIfMissingFeatures(*args):
    """Skip the test (class) unless the engine provides the ESPResSo features."""
    if not lbmd.has_features(*args):
        missing = [f for a in args for f in ([a] if isinstance(a, str) else a) if not lbmd.has_features(f)]
        return unittest.skip(f"Skipping test: missing feature{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(missing)}")
    return no_skip


def skipIfMissingModules(*args):
    """Skip unless every named Python module imports."""
    missing = []
    for name in args:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    if missing:
        return unittest.skip(f"Skipping test: missing python module{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(missing)}")
    return no_skip
