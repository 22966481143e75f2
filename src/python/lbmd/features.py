"""ESPResSo-style feature checks.

ESPResSo is compiled with optional features; this engine always has the
ones it implements. ``assert_features`` accepts ESPResSo feature names this
engine provides and raises for the others, so ported scripts fail early and
clearly instead of half-way through.
"""

# ESPResSo 4.2 feature names that this engine always provides.
_PROVIDED = frozenset({
    "MASS", "EXTERNAL_FORCES", "SOFT_SPHERE", "MEMBRANE_COLLISION", "MORSE", "OIF_LOCAL_FORCES",
    "OIF_GLOBAL_FORCES", "LB_BOUNDARIES", "EXCLUSIONS", "LANGEVIN_PER_PARTICLE",
    "LB_ELECTROHYDRODYNAMICS_NOT", "WALBERLA_NOT",
}) - {"LB_ELECTROHYDRODYNAMICS_NOT", "WALBERLA_NOT"}


class FeaturesError(Exception):
    """A script asked for an ESPResSo feature this engine does not implement."""


def features():
    """Sorted list of the ESPResSo feature names this engine provides."""
    return sorted(_PROVIDED)


def _as_list(names):
    return [names] if isinstance(names, str) else list(names)


def has_features(*args):
    """True if every named feature is provided (names as in ESPResSo)."""
    names = [n for a in args for n in _as_list(a)]
    return all(n in _PROVIDED for n in names)


def assert_features(*args):
    """Raise FeaturesError naming the features this engine does not provide."""
    names = [n for a in args for n in _as_list(a)]
    missing = [n for n in names if n not in _PROVIDED]
    if missing:
        raise FeaturesError(
            f"missing features {', '.join(missing)}: this engine does not implement them "
            f"(it provides {', '.join(features())})")
