"""SI values to the engine's units and back, and the membrane moduli.

The engine has no built-in units: a script picks a unit of length, of time
and of mass, and every number it passes is a multiple of those. The PyOIF
paper (Jančigová et al., PLoS Comput. Biol. 16, e1008249, 2020) uses 1 µm,
1 µs and 1e-15 kg, the defaults of :class:`UnitSystem`; in them water's
density 1000 kg/m³ is 1, a dynamic viscosity of 1.5 mPa s is 1.5, a force of
1 pN is 1e-3, an energy of 1 J is 1e15 and a tension of 1 N/m is 1e3.

"Lattice units" in the PyOIF paper mean these engine units. They are not the
lattice-Boltzmann fluid's own units (agrid, tau); for those see
:func:`lb_lattice_viscosity`.

    >>> u = UnitSystem()                  # 1 µm, 1 µs, 1e-15 kg
    >>> u.to_lattice(1.5e-3, "Pa s")      # plasma's dynamic viscosity
    1.5
    >>> u.to_si(0.005, "N/m")             # the paper's ks as a tension
    5e-06

Unit strings: products and quotients of m, s, g (kg), N, Pa, J, W with SI
prefixes (p, n, u or µ, m, c, k, M, G) and integer powers (``m^2``, ``m**2``,
``s^-1``); factors separated by a space or ``*``, ``/`` divides by the factor
(or parenthesised group) after it: ``"kg/m^3"``, ``"Pa s"``, ``"mPa*s"``,
``"m^2/s"``, ``"N/m"``, ``"kg m/s^2"``, ``"J/(m^2)"``, ``"1/s"``.

The membrane moduli (:func:`oif_moduli_from_si`, :func:`si_moduli_from_oif`)
are in the docstring of :func:`oif_moduli_from_si`.
"""
import math
import numbers
import re
from fractions import Fraction

import numpy as np

__all__ = ["UnitSystem", "parse_unit", "oif_moduli_from_si", "si_moduli_from_oif", "lb_lattice_viscosity"]

# symbol -> (value in SI base units, exponents of (length, time, mass))
# (exact fractions: the scales are decimal numbers, and 1000 kg/m^3 should be
# 1, not 0.9999999999999998, in µm, µs, 1e-15 kg)
_UNITS = {
    "m": (Fraction(1), (1, 0, 0)),
    "s": (Fraction(1), (0, 1, 0)),
    "g": (Fraction(1, 1000), (0, 0, 1)),
    "N": (Fraction(1), (1, -2, 1)),  # kg m / s^2
    "Pa": (Fraction(1), (-1, -2, 1)),  # N / m^2
    "J": (Fraction(1), (2, -2, 1)),  # N m
    "W": (Fraction(1), (2, -3, 1)),  # J / s
}
_PREFIXES = {"p": Fraction(1, 10**12), "n": Fraction(1, 10**9), "u": Fraction(1, 10**6),
             "µ": Fraction(1, 10**6), "μ": Fraction(1, 10**6), "m": Fraction(1, 1000), "c": Fraction(1, 100),
             "k": Fraction(1000), "M": Fraction(10**6), "G": Fraction(10**9)}
_ACCEPTED = ("products and quotients of m, s, g, N, Pa, J, W with the prefixes p n u µ m c k M G and integer "
             "powers, e.g. 'm/s', 'kg/m^3', 'Pa s', 'mPa*s', 'm^2/s', 'N/m', 'pN', 'um', '1/s'")
_TOKEN = re.compile(r"\s*(?:(?P<name>[A-Za-zµμ]+)|(?P<one>1)(?![0-9.])|(?P<pow>\^|\*\*)|(?P<op>[*/()]))")
_EXPONENT = re.compile(r"\s*(?P<sign>[+-]?)\s*(?P<digits>[0-9]+)")


def _symbol(name, unit):
    """(SI factor, exponents) of one symbol such as 'kg', 'um', 'mPa'."""
    if name in _UNITS:
        return _UNITS[name]
    if len(name) > 1 and name[0] in _PREFIXES and name[1:] in _UNITS:
        factor, dims = _UNITS[name[1:]]
        return _PREFIXES[name[0]] * factor, dims
    raise ValueError(f"unit {unit!r}: unknown unit symbol {name!r}; accepted: {_ACCEPTED}")


def parse_unit(unit):
    """(factor, (l, t, m)) of a unit string: a value in `unit` times factor is
    the value in SI base units (m, s, kg), of dimension length^l time^t
    mass^m. ``parse_unit("mPa s")`` is ``(0.001, (-1, -1, 1))``."""
    factor, dims = _parse_exact(unit)
    return float(factor), dims


def _parse_exact(unit):
    """parse_unit with the factor as an exact Fraction."""
    if not isinstance(unit, str):
        raise TypeError(f"unit must be a string such as 'm/s', got {unit!r}")
    if not unit.strip():
        raise ValueError(f"unit must not be empty; for a dimensionless value use '1'; accepted: {_ACCEPTED}")
    pos = 0
    tokens = []
    text = unit.replace("·", "*")
    while pos < len(text):
        if text[pos:].strip() == "":
            break
        match = _TOKEN.match(text, pos)
        if match is None:
            raise ValueError(f"unit {unit!r}: cannot read {text[pos:].strip()!r}; accepted: {_ACCEPTED}")
        pos = match.end()
        if match.group("pow"):
            exp = _EXPONENT.match(text, pos)
            if exp is None:
                raise ValueError(f"unit {unit!r}: a power needs an integer exponent; accepted: {_ACCEPTED}")
            pos = exp.end()
            tokens.append(("pow", int(exp.group("sign") + exp.group("digits"))))
        elif match.group("name"):
            tokens.append(("name", match.group("name")))
        elif match.group("one"):
            tokens.append(("one", None))
        else:
            tokens.append((match.group("op"), None))

    def error(what):
        return ValueError(f"unit {unit!r}: {what}; accepted: {_ACCEPTED}")

    def group(i, depth):
        """Reads factors from token i to the end or to a ')'; returns
        (factor, dims, next index)."""
        factor, dims = Fraction(1), [0, 0, 0]
        divided = False  # a '/' at this level: an implicit product after it is ambiguous
        expect_factor = True
        op = "*"
        while i < len(tokens):
            kind, value = tokens[i]
            if kind == ")":
                if depth == 0:
                    raise error("unmatched ')'")
                break
            if kind in ("*", "/"):
                if expect_factor:
                    raise error(f"'{kind}' without a unit before it")
                op = kind
                divided = divided or kind == "/"
                expect_factor = True
                i += 1
                continue
            if kind == "pow":
                raise error("a power without a unit before it")
            if not expect_factor:  # two factors side by side: an implicit product
                if divided:
                    raise error("ambiguous: after '/', write the denominator in parentheses, e.g. 'kg/(m s)'")
                op = "*"
            if kind == "(":
                f, d, i = group(i + 1, depth + 1)
                if i >= len(tokens) or tokens[i][0] != ")":
                    raise error("'(' without ')'")
                i += 1
            elif kind == "one":
                f, d = Fraction(1), [0, 0, 0]
                i += 1
            else:
                f, d = _symbol(value, unit)
                i += 1
            power = 1
            if i < len(tokens) and tokens[i][0] == "pow":
                power = tokens[i][1]
                i += 1
            sign = 1 if op == "*" else -1
            factor *= f ** (sign * power)
            dims = [a + sign * power * b for a, b in zip(dims, d)]
            expect_factor = False
        if expect_factor:
            raise error("a unit is missing at the end" if tokens else "no unit")
        return factor, dims, i

    factor, dims, i = group(0, 0)
    if i != len(tokens):
        raise error("unmatched ')'")
    return factor, tuple(dims)


def _positive_scale(name, value):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"UnitSystem: parameter '{name}' must be a number (SI units), got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"UnitSystem: parameter '{name}' must be positive and finite (SI units), got {value!r}")
    return value


def _values(where, value):
    """value as a float (scalar input) or a float array; TypeError for what is
    not numeric, ValueError for NaN and infinities."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{where} must be a number or an array of numbers, got {value!r}")
    if isinstance(value, numbers.Real):
        result = float(value)
        if not math.isfinite(result):
            raise ValueError(f"{where} must be finite, got {value!r}")
        return result
    try:
        array = np.asarray(value)
    except Exception as exc:  # ragged nested lists
        raise TypeError(f"{where} must be a number or an array of numbers, got {value!r}") from exc
    if array.dtype.kind not in "iuf" or array.dtype == object:
        raise TypeError(f"{where} must be a number or an array of numbers, got {value!r}")
    array = array.astype(float)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{where} must be finite, got {value!r}")
    return array if array.ndim else float(array)


class UnitSystem:
    """The engine's units in SI: `length` in m, `time` in s, `mass` in kg
    (defaults: the PyOIF paper's 1 µm, 1 µs, 1e-15 kg).

    ``to_lattice(value, unit)`` turns a value in the SI unit `unit` (a
    string, see the module's doc) into the engine's units, ``to_si(value,
    unit)`` the other way; `value` may be a number or an array (elementwise).
    """

    def __init__(self, length=1e-6, time=1e-6, mass=1e-15):
        self._length = _positive_scale("length", length)
        self._time = _positive_scale("time", time)
        self._mass = _positive_scale("mass", mass)
        # the scales as the decimal numbers they print as (1e-6 is 10^-6, not
        # the nearest binary float): scale() rounds once, at the end
        self._exact_length = Fraction(repr(self._length))
        self._exact_time = Fraction(repr(self._time))
        self._exact_mass = Fraction(repr(self._mass))

    @property
    def length(self):
        """The engine's unit of length in m."""
        return self._length

    @property
    def time(self):
        """The engine's unit of time in s."""
        return self._time

    @property
    def mass(self):
        """The engine's unit of mass in kg."""
        return self._mass

    @property
    def velocity(self):
        """The engine's unit of velocity in m/s."""
        return self.scale("m/s")

    @property
    def force(self):
        """The engine's unit of force in N."""
        return self.scale("N")

    @property
    def energy(self):
        """The engine's unit of energy in J."""
        return self.scale("J")

    def _exact_scale(self, unit):
        factor, (l, t, m) = _parse_exact(unit)
        return self._exact_length**l * self._exact_time**t * self._exact_mass**m / factor

    def scale(self, unit):
        """How many SI `unit`s make one engine unit of the same dimension:
        ``to_si(x, unit) == x * scale(unit)``; ``scale("N")`` is the unit of
        force in N."""
        return float(self._exact_scale(unit))

    def to_lattice(self, value, unit):
        """`value` given in the SI unit `unit`, in the engine's units."""
        value = _values("to_lattice: value", value)
        return value * float(1 / self._exact_scale(unit))

    def to_si(self, value, unit):
        """`value` given in the engine's units, in the SI unit `unit`."""
        value = _values("to_si: value", value)
        return value * float(self._exact_scale(unit))

    def __eq__(self, other):
        return isinstance(other, UnitSystem) and (self.length, self.time, self.mass) == (
            other.length, other.time, other.mass)

    def __hash__(self):
        return hash((self.length, self.time, self.mass))

    def __repr__(self):
        return f"UnitSystem(length={self.length!r}, time={self.time!r}, mass={self.mass!r})"


# The OIF membrane's continuum moduli (doc/model.md eqs. 3-7, energies in
# doc/interactions.md).
_SQRT3 = math.sqrt(3.0)
# OIF coefficient, its unit in SI, and the factor c with  coefficient = c * modulus
_OIF_OF_MODULUS = {
    "shear_modulus": ("ks", "N/m", 4.0 / _SQRT3),
    "bending_modulus": ("kb", "J", 2.0 / _SQRT3),
    "local_area_modulus": ("kal", "N/m", 2.0),
    "global_area_modulus": ("kag", "N/m", 2.0),
    "volume_modulus": ("kv", "Pa", 1.0),
    "membrane_viscosity": ("kvisc", "kg/s", 4.0 / _SQRT3),
}


def _units_argument(where, units):
    if units is None:
        return UnitSystem()
    if not isinstance(units, UnitSystem):
        raise TypeError(f"{where}: parameter 'units' must be a lbmd.units.UnitSystem (or None for the "
                        f"paper's µm, µs, 1e-15 kg), got {units!r}")
    return units


def _nonnegative(where, name, value):
    value = _values(f"{where}: parameter '{name}'", value)
    if np.any(np.asarray(value) < 0):
        raise ValueError(f"{where}: parameter '{name}' must be >= 0, got {value!r}")
    return value


def oif_moduli_from_si(units=None, *, shear_modulus=None, bending_modulus=None, local_area_modulus=None,
                       global_area_modulus=None, volume_modulus=None, membrane_viscosity=None):
    """The OIF coefficients (ks, kb, kal, kag, kv, kvisc) in the engine's
    units for continuum moduli in SI; only the moduli given appear in the
    returned dict. `units`: a :class:`UnitSystem` (None: the paper's).

    ================  =====================  ========================================
    SI modulus        OIF coefficient        relation
    ================  =====================  ========================================
    shear_modulus µ0  ks (eq. 3, N/m)        µ0 = (√3/4) ks
    bending_modulus   kb (eq. 4, J)          kc = (√3/2) kb
    local area        kal (eq. 5, N/m)       K_local = kal/2
    global area       kag (eq. 6, N/m)       K_global = kag/2
    volume_modulus    kv (eq. 7, Pa)         kv (a bulk modulus of the enclosed volume)
    membrane_visc.    kvisc (kg/s)           η_m = (√3/4) kvisc (2-D, Pa s m)
    ================  =====================  ========================================

    The relations hold for small deformations of a regular triangulation
    (equilateral triangles); on a real mesh they are estimates (a spring
    network's area modulus exceeds √3 ks/2 on any other mesh, by 1 % on
    the shipped sphere642).

    - Shear: a triangular network of linear springs of constant k has the
      in-plane shear modulus µ0 = √3 k/4 and area-expansion modulus
      K = 2 µ0 = √3 k/2 (H. S. Seung, D. R. Nelson, Phys. Rev. A 38, 1005,
      1988; M. Dao, J. Li, S. Suresh, Mater. Sci. Eng. C 26, 1232, 2006;
      D. A. Fedosov, B. Caswell, G. E. Karniadakis, Biophys. J. 98,
      2215, 2010). The OIF stretching force (eq. 3) F = ks κ(λ)(l − l0) has
      κ(1) = 1, so its small-strain spring constant is ks and µ0 = √3 ks/4.
    - Bending: for the energy Σ kb (1 − cos(θ − θ0)) over the mesh's edges
      the bending rigidity is kc = √3 kb/2 (H. S. Seung, D. R. Nelson,
      Phys. Rev. A 38, 1005, 1988; G. Gompper, D. M. Kroll, J. Phys. I
      France 6, 1305, 1996; Fedosov et al. 2010: kb = 2 kc/√3). OIF's
      energy kb/2 (θ − θ0)² (doc/interactions.md) equals it to second order
      in θ − θ0, so the same factor applies. Checked with the engine's
      angle function on a cylinder of equilateral triangles, edges along its
      axis or around it (testsuite/python/test_units.py).
    - Area: Fedosov et al. 2010 write K = 2 µ0 + ka + kd for the global and
      local area energies ka (A − A0)²/(2 A0) and kd Σ_j (A_j − A0)²/(2 A0).
      OIF's local area energy (the work of eq. 5 along a dilation,
      doc/interactions.md) is kal/2 (S − S0 − S0 ln(S/S0)) ≈ kal (S − S0)²/(4 S0)
      per triangle, and the global one kag (S − S0)²/(4 S0): half of the
      Fedosov forms, so K_local = kal/2 and K_global = kag/2, and the
      membrane's area-expansion modulus is K = √3 ks/2 + kal/2 + kag/2
      (:func:`si_moduli_from_oif` returns it as ``area_expansion_modulus``).
    - Volume: eq. 7's energy kv/2 (V − V0)²/V0 is that of a bulk modulus kv
      of the enclosed volume, in Pa.
    - Membrane viscosity: dashpots along the edges (ESPResSo's OIF
      membrane viscosity, F = kvisc Δv·p) act like the springs above with
      rates for strains: η_m = √3 kvisc/4 (Fedosov et al. 2010's
      η_m = √3 γ_T + √3 γ_C/4 with only the central γ_C = kvisc).

    Example, the PyOIF paper's red blood cell (ks 0.005, kb 0.02, kal 0.007,
    kag 0.7, kv 0.9 in µm, µs, 1e-15 kg): ks = 5 µN/m, µ0 = 2.17 µN/m;
    kb = 2e-17 J, kc = 1.73e-17 J; kv = 900 Pa.
    """
    units = _units_argument("oif_moduli_from_si", units)
    given = dict(shear_modulus=shear_modulus, bending_modulus=bending_modulus,
                 local_area_modulus=local_area_modulus, global_area_modulus=global_area_modulus,
                 volume_modulus=volume_modulus, membrane_viscosity=membrane_viscosity)
    result = {}
    for name, value in given.items():
        if value is None:
            continue
        value = _nonnegative("oif_moduli_from_si", name, value)
        key, unit, factor = _OIF_OF_MODULUS[name]
        result[key] = units.to_lattice(factor * value, unit)
    if not result:
        raise TypeError("oif_moduli_from_si: give at least one of " + ", ".join(given))
    return result


def si_moduli_from_oif(units=None, *, ks=None, kb=None, kal=None, kag=None, kv=None, kvisc=None):
    """The continuum moduli in SI for OIF coefficients in the engine's
    units, the inverse of :func:`oif_moduli_from_si` (same relations and
    sources). Returns a dict with the moduli of the coefficients given
    (``shear_modulus`` N/m, ``bending_modulus`` J, ``local_area_modulus``
    and ``global_area_modulus`` N/m, ``volume_modulus`` Pa,
    ``membrane_viscosity`` Pa s m) and, when any of ks, kal, kag is given,
    ``area_expansion_modulus`` K = √3 ks/2 + kal/2 + kag/2 in N/m (the terms
    not given count zero); with ks also ``young_modulus``
    Y = 4 K µ0/(K + µ0) in N/m (Dao et al. 2006)."""
    units = _units_argument("si_moduli_from_oif", units)
    given = dict(ks=ks, kb=kb, kal=kal, kag=kag, kv=kv, kvisc=kvisc)
    result = {}
    for name, (key, unit, factor) in _OIF_OF_MODULUS.items():
        value = given[key]
        if value is None:
            continue
        value = _nonnegative("si_moduli_from_oif", key, value)
        result[name] = units.to_si(value, unit) / factor
    if all(v is None for v in given.values()):
        raise TypeError("si_moduli_from_oif: give at least one of " + ", ".join(given))
    if any(given[k] is not None for k in ("ks", "kal", "kag")):
        shear = result.get("shear_modulus", 0.0)
        area = 2.0 * shear + result.get("local_area_modulus", 0.0) + result.get("global_area_modulus", 0.0)
        result["area_expansion_modulus"] = area
        if ks is not None:
            result["young_modulus"] = 4.0 * area * shear / (area + shear)
    return result


def lb_lattice_viscosity(visc, agrid, tau):
    """The lattice-Boltzmann fluid's kinematic viscosity in its own lattice
    units (agrid = tau = 1): visc tau / agrid², all three in the engine's
    units (doc/lb.md); the BGK shear relaxation rate is
    1/(3 ν_lattice + 1/2)."""
    visc = _values("lb_lattice_viscosity: parameter 'visc'", visc)
    for name, value in (("agrid", agrid), ("tau", tau)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TypeError(f"lb_lattice_viscosity: parameter '{name}' must be a number, got {value!r}")
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"lb_lattice_viscosity: parameter '{name}' must be positive and finite, got {value!r}")
    return visc * tau / agrid**2
