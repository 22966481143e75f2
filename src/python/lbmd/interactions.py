"""Interactions: non-bonded models per pair of particle types
(``system.non_bonded_inter[t1, t2].soft_sphere.set_params(...)``) and bonded
interactions (``system.bonded_inter.add(HarmonicBond(k=, r_0=))``).

Adding a model: its C++ header and registration, its binding in
bind_interactions.cpp, and one declaration here (a NonBondedModel subclass or a
BondedInteraction subclass).
"""
import numpy as np

from . import _lbmd
from .validation import Param, ParameterObject, parse, positive, non_negative, greater_than_one


# ---------------------------------------------------------------------------
# non-bonded
# ---------------------------------------------------------------------------
class NonBondedModel:
    """One model's parameters for one pair of types. Subclasses declare
    ``name`` (the C++ model name), ``_params`` and ``_core_params``."""

    name = None
    _params = []
    _core_params = None

    def __init__(self, system, t1, t2):
        self._system, self._types = system, (t1, t2)

    def set_params(self, **kwargs):
        values = parse(f"{self.name}[{self._types[0]}, {self._types[1]}]", self._params, kwargs)
        self._check(values)
        getattr(self._system._core, "set_" + self.name)(*self._types, self._core_params(**values))

    def _check(self, values):
        """Cross-parameter checks of a subclass."""

    def get_params(self):
        p = getattr(self._system._core, "get_" + self.name)(*self._types)
        return {q.name: getattr(p, q.name) for q in self._params}

    def is_active(self):
        return self.get_params()["cutoff"] > 0

    def deactivate(self):
        zero = {q.name: 0.0 for q in self._params}
        getattr(self._system._core, "set_" + self.name)(*self._types, self._core_params(**zero))

    def __repr__(self):
        return f"{self.name}[{self._types[0]}, {self._types[1]}]({self.get_params()})"


class SoftSphereInteraction(NonBondedModel):
    """V(r) = a (r - offset)^-n for r < cutoff + offset (model eq. 8)."""

    name = "soft_sphere"
    _params = [Param("a", "float", check=non_negative, doc="energy scale"),
               Param("n", "float", check=non_negative, doc="exponent"),
               Param("cutoff", "float", check=non_negative, doc="range beyond offset"),
               Param("offset", "float", 0.0, check=non_negative, doc="distance shift")]
    _core_params = staticmethod(_lbmd.SoftSphereParams)


#: name -> class of every non-bonded model, as attributes of a type pair
NONBONDED_MODELS = {SoftSphereInteraction.name: SoftSphereInteraction}


def register_nonbonded_model(cls):
    """Make a NonBondedModel subclass available as non_bonded_inter[t1, t2].<name>."""
    NONBONDED_MODELS[cls.name] = cls
    return cls


class NonBondedTypePair:
    def __init__(self, system, t1, t2):
        self._system, self._types = system, (t1, t2)

    def __getattr__(self, name):
        cls = NONBONDED_MODELS.get(name)
        if cls is None:
            raise AttributeError(f"no non-bonded model '{name}'; available: "
                                 f"{', '.join(NONBONDED_MODELS)}")
        return cls(self._system, *self._types)


class NonBondedInteractions:
    """``system.non_bonded_inter[t1, t2]``."""

    def __init__(self, system):
        self._system = system

    def __getitem__(self, key):
        if not (isinstance(key, tuple) and len(key) == 2):
            raise TypeError("non_bonded_inter: index with two particle types, e.g. [0, 1]")
        for t in key:
            if isinstance(t, bool) or not isinstance(t, (int, np.integer)) or t < 0:
                raise ValueError(f"non_bonded_inter: particle types must be integers >= 0, got {t!r}")
        return NonBondedTypePair(self._system, int(key[0]), int(key[1]))


# ---------------------------------------------------------------------------
# bonded
# ---------------------------------------------------------------------------
class BondedInteraction(ParameterObject):
    """Base of bonded interactions. Subclasses declare ``_params`` and
    ``_core_class`` (the bound C++ struct) and, if their bonds carry
    per-bond reference values, ``per_bond_stride``."""

    _core_class = None
    n_partners = 1
    per_bond_stride = 0

    def _core_object(self):
        return self._core_class(**self._values)

    def _default_per_bond(self, n_bonds):
        """Per-bond reference values used when add_bonds gets none."""
        return np.zeros((n_bonds, self.per_bond_stride))

    def __eq__(self, other):
        return self is other

    def __hash__(self):
        return id(self)


class HarmonicBond(BondedInteraction):
    """V(r) = k/2 (r - r_0)^2; the bond breaks (an error) beyond r_cut if r_cut > 0."""

    _params = [Param("k", "float", check=non_negative), Param("r_0", "float", check=non_negative),
               Param("r_cut", "float", 0.0, check=non_negative)]
    _core_class = _lbmd.HarmonicBond
    n_partners = 1


class BondedInteractions:
    """``system.bonded_inter``: registry of bonded interactions (id = position)."""

    def __init__(self, system):
        self._system = system
        self._list = []

    def add(self, bond):
        if not isinstance(bond, BondedInteraction):
            raise TypeError(f"bonded_inter.add: expected a bonded interaction, got {type(bond).__name__}")
        if any(b is bond for b in self._list):
            return self._id_of(bond)
        core_id = self._system._core.add_bonded_interaction(bond._core_object())
        assert core_id == len(self._list)
        self._list.append(bond)
        object.__setattr__(bond, "_bond_id", core_id)
        return core_id

    def _id_of(self, bond):
        for i, b in enumerate(self._list):
            if b is bond:
                return i
        raise ValueError(f"{type(bond).__name__} is not registered: call system.bonded_inter.add(bond) first")

    def _add_bonds(self, bond, ids, per_bond=None):
        bond_id = self._id_of(bond)
        ids = np.ascontiguousarray(np.asarray(ids, dtype=np.int32))
        k = bond.n_partners + 1
        if ids.ndim != 2 or ids.shape[1] != k:
            raise ValueError(f"{type(bond).__name__} joins {k} particles: expected an M×{k} "
                             f"array of ids, got shape {ids.shape}")
        if per_bond is None:
            per_bond = bond._default_per_bond(ids.shape[0])
        per_bond = np.ascontiguousarray(np.asarray(per_bond, dtype=float))
        self._system._core.add_bonds(bond_id, ids.ravel(), per_bond.ravel())

    def __getitem__(self, i):
        return self._list[i]

    def __len__(self):
        return len(self._list)

    def __iter__(self):
        return iter(self._list)
