"""Parameter declaration and validation, in one place for the whole package.

A class declares its parameters as a list of :class:`Param`; :func:`parse`
checks a call's keyword arguments against it: unknown or missing keywords and
values of the wrong type (a string for a number) are ``TypeError``, values out
of range or of the wrong size are ``ValueError``, each message naming the
class, the parameter and what was expected.
"""
import math
import numbers

import numpy as np

REQUIRED = object()


class Param:
    """One parameter: name, kind, default, and an optional range check.

    kind is one of 'float', 'int' (32-bit), 'seed' (64-bit unsigned), 'bool',
    'vec3' (3 floats), 'bool3'
    (3 bools), 'int_array', 'object' (any value, or an instance of `cls`).
    `check` is a (predicate, description) pair, e.g. ``positive``.
    """

    def __init__(self, name, kind, default=REQUIRED, check=None, cls=None, doc=""):
        self.name = name
        self.kind = kind
        self.default = default
        self.check = check
        self.cls = cls
        self.doc = doc

    def convert(self, owner, value):
        where = f"{owner}: parameter '{self.name}'"
        k = self.kind
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()  # np.array(0.01) as 0.01
        if k == "float":
            value = real_number(where, value)
        elif k in ("int", "seed"):
            if isinstance(value, bool) or not isinstance(value, numbers.Integral):
                raise TypeError(f"{where} must be an integer, got {value!r}")
            value = int(value)
            # the engine's ints are 32-bit, its seeds 64-bit unsigned: a larger
            # value would not reach it (or wrap around)
            lo, hi = (-2**31, 2**31 - 1) if k == "int" else (0, 2**64 - 1)
            if not lo <= value <= hi:
                raise ValueError(f"{where} must be in {lo}..{hi}, got {value!r}")
        elif k == "bool":
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{where} must be True or False, got {value!r}")
            value = bool(value)
        elif k == "vec3":
            value = vector3(where, value)
        elif k == "bool3":
            arr = np.asarray(value)
            if arr.shape != (3,) or arr.dtype != bool:
                raise ValueError(f"{where} must be 3 booleans, got {value!r}")
            value = [bool(x) for x in arr]
        elif k == "object":
            if self.cls is not None and not isinstance(value, self.cls):
                names = (self.cls.__name__ if isinstance(self.cls, type)
                         else " or ".join(c.__name__ for c in self.cls))
                raise TypeError(f"{where} must be a {names}, got {type(value).__name__}")
        else:  # pragma: no cover - declaration error
            raise AssertionError(f"unknown parameter kind {k}")
        if self.check is not None:
            predicate, description = self.check
            if not predicate(value):
                raise ValueError(f"{where} must be {description}, got {value!r}")
        return value


def parse(owner, params, kwargs):
    """Validate kwargs against the declared params; returns a dict of all of them."""
    known = {p.name: p for p in params}
    unknown = [k for k in kwargs if k not in known]
    if unknown:
        raise TypeError(f"{owner}: unknown parameter(s) {', '.join(map(repr, unknown))}; "
                        f"accepted: {', '.join(known)}")
    out = {}
    for p in params:
        if p.name in kwargs:
            out[p.name] = p.convert(owner, kwargs[p.name])
        elif p.default is REQUIRED:
            raise TypeError(f"{owner}: missing required parameter '{p.name}'")
        else:
            out[p.name] = p.default
    return out


def real_number(where, value, check=None):
    """value as a finite float; `where` names what is checked. TypeError for
    what is not a real number (booleans included), ValueError for NaN and
    infinities and for values that fail `check`: a range check such as
    ``positive`` or its name in ``named_checks`` ("pos", "nonneg")."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{where} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {value!r}")
    if check is not None:
        predicate, description = named_checks[check] if isinstance(check, str) else check
        if not predicate(value):
            raise ValueError(f"{where} must be {description}, got {value!r}")
    return value


def vector3(where, value, positive=False):
    """value as an array of 3 finite floats; `where` names what is checked
    (e.g. "OifCell: parameter 'origin'"). TypeError for what is not numbers
    (strings would convert silently, '1' -> 1.0; booleans, None), ValueError
    for another count, a component that is not finite or, with `positive`,
    one that is <= 0."""
    try:
        raw = np.asarray(value)
        if raw.dtype.kind not in "iuf":
            raise TypeError
        arr = raw.astype(float)
    except (TypeError, ValueError):
        raise TypeError(f"{where} must be 3 numbers, got {value!r}") from None
    if arr.shape != (3,):
        raise ValueError(f"{where} must be 3 numbers, got {value!r}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{where} must be 3 finite numbers, got {value!r}")
    if positive and not np.all(arr > 0):
        raise ValueError(f"{where} must be positive in every component, got {value!r}")
    return arr


def is_whole_number(value):
    """An integer of any numeric kind: int, np.int64, a 0-d integer array, or
    a whole float (np.round(1.2) is 1.0); not bool, not 2.7."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, (numbers.Integral, np.integer)):
        return True
    return isinstance(value, (float, np.floating)) and bool(np.isfinite(value)) and float(value).is_integer()


#: ids, types and mol_ids are C++ ints; the largest id leaves room for max_id() + 1
INT32_MAX = 2**31 - 1


def integers(owner, name, value, lo=0, hi=INT32_MAX):
    """value (an integer or array of integers) as an int32 array, refused
    (naming owner and parameter) when not integers or outside [lo, hi]:
    no silent truncation of 1.7 or wrap-around of 2**40."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        arr = np.asarray(None, dtype=object)
    if arr.dtype == object and arr.size:  # Python ints beyond int64, mixed lists
        if all(isinstance(x, numbers.Integral) and not isinstance(x, bool) for x in arr.ravel()):
            bad = [int(x) for x in arr.ravel() if not lo <= int(x) <= hi]
            if bad:
                raise ValueError(f"{owner}: parameter '{name}' must be integers in {lo}..{hi}, got {bad[0]}")
            arr = arr.astype(np.int64)
    if arr.size and arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.floor(arr)):
        pass  # whole numbers stored as floats (np.zeros(n)) are fine; 1.7 is not
    elif arr.size and (arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer)):
        raise TypeError(f"{owner}: parameter '{name}' must be an integer or integers, got {value!r}")
    if arr.size and (arr.min() < lo or arr.max() > hi):
        bad = arr.min() if arr.min() < lo else arr.max()
        raise ValueError(f"{owner}: parameter '{name}' must be integers in {lo}..{hi}, got {int(bad)}")
    return np.ascontiguousarray(np.atleast_1d(arr).astype(np.int32))


# Range checks: (predicate, description)
#: no length of a scene in micrometres (the unit of length of the samples
#: and of lbmd.units' default) is below this: a smaller one was given in
#: metres. A script in another unit of length (metres) sets it to 0.
SMALLEST_LENGTH = 1e-3


def check_not_metres(where, length):
    """ValueError naming the unit mistake when a length (a number, > 0) is
    below SMALLEST_LENGTH: `where` names the parameter, e.g. "System:
    parameter 'box_l'"."""
    if 0 < length < SMALLEST_LENGTH:
        raise ValueError(
            f"{where} is {length:g} long: a length in metres? Lengths are in the script's unit of "
            f"length, micrometres in the samples (lbmd.units converts SI values): {length:g} m is "
            f"{length * 1e6:g} um (a script whose unit of length is the metre sets "
            f"lbmd.validation.SMALLEST_LENGTH = 0)")


positive = (lambda x: x > 0, "> 0")
non_negative = (lambda x: x >= 0, ">= 0")
greater_than_one = (lambda x: x > 1, "> 1")
#: range checks by the names the oif package gives them
named_checks = {"pos": positive, "nonneg": non_negative}


def in_open_range(lo, hi):
    return (lambda x: lo < x < hi, f"in the open range ({lo}, {hi})")


def all_positive():
    return (lambda v: bool(np.all(np.asarray(v) > 0)), "positive in every component")


def unit_or_nonzero():
    return (lambda v: float(np.linalg.norm(v)) > 0, "a non-zero vector")


class ParameterObject:
    """Base of objects whose constructor takes only declared keyword parameters.

    Subclasses set ``_params`` (a list of Param). Parameters read back exactly
    as set through attributes and ``get_params()``.
    """

    _params = []

    def __init__(self, *args, **kwargs):
        if args:
            raise TypeError(f"{type(self).__name__}: parameters are keywords, e.g. "
                            f"{type(self).__name__}({', '.join(p.name + '=...' for p in self._params[:2])})")
        object.__setattr__(self, "_values", parse(type(self).__name__, self._params, kwargs))
        self._validate()

    def _validate(self):
        """Checks across parameters; subclasses override."""

    #: attributes holding C++ objects or the owning system: left out when the
    #: object is pickled (lbmd.checkpoint) and made again by _restore_core
    #: and by the System the object belongs to
    _not_pickled = ("_core", "_system_core", "_system")

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in self._not_pickled}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._restore_core()

    def _restore_core(self):
        """After unpickling: make the C++ object again (shapes, constraints)."""

    def get_params(self):
        return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in self._values.items()}

    def __getattr__(self, name):
        values = self.__dict__.get("_values", {})
        if name in values:
            return values[name]
        raise AttributeError(f"{type(self).__name__} has no attribute '{name}'")

    def __setattr__(self, name, value):
        # ESPResSo scripts may try `sphere.radius = 5`: refused, as storing it
        # on the Python object would change nothing in the engine
        if name.startswith("_"):
            object.__setattr__(self, name, value)
            return
        kind = type(self).__name__
        raise AttributeError(f"{kind}: '{name}' cannot be changed after creation; create a new "
                             f"{kind}(...) with the new value")

    def __repr__(self):
        args = ", ".join(f"{k}={_fmt(v)}" for k, v in self._values.items())
        return f"{type(self).__name__}({args})"

    def __dir__(self):
        # the parameters, served by __getattr__, for tab completion
        return sorted(set(super().__dir__()) | set(self.__dict__.get("_values", {})))


def _fmt(v):
    if isinstance(v, np.ndarray):
        return repr(v.tolist())
    return repr(v)
