"""Interactions: non-bonded models per pair of particle types
(``system.non_bonded_inter[t1, t2].soft_sphere.set_params(...)``) and bonded
interactions (``system.bonded_inter.add(HarmonicBond(k=, r_0=))``).

Adding a model: its C++ header and registration, its binding in
bind_interactions.cpp, and one declaration here (a NonBondedModel subclass or a
BondedInteraction subclass).
"""
import numpy as np

from . import _lbmd
from .validation import INT32_MAX, Param, ParameterObject, integers, parse, positive, non_negative


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

    def set_params(self, *args, **kwargs):
        if args:
            raise TypeError(f"{self.name}.set_params: parameters are keywords, e.g. "
                            f"set_params({', '.join(q.name + '=...' for q in self._params)})")
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


def _contact_params(n_check, n_doc):
    """The parameters shared by the contact models: a, n, cutoff, offset."""
    return [Param("a", "float", check=non_negative, doc="energy scale"),
            Param("n", "float", check=n_check, doc=n_doc),
            Param("cutoff", "float", check=non_negative, doc="range beyond offset"),
            Param("offset", "float", 0.0, check=non_negative, doc="distance shift")]


class SoftSphereInteraction(NonBondedModel):
    """V(r) = a (r - offset)^-n for r < cutoff + offset (model eq. 8)."""

    name = "soft_sphere"
    _params = _contact_params(non_negative, "exponent")
    _core_params = staticmethod(_lbmd.SoftSphereParams)


class MembraneCollisionInteraction(NonBondedModel):
    """Membrane collision between nodes of different cells (model eq. 9):
    V(d) = a / (1 + exp(n d)), d = r - offset, for r < cutoff + offset.

    Acts only between particles of different mol_id (cells) and needs the
    nodes' outward normals (OifOutDirection bonds); the normals decide whether
    the membranes have crossed, and then the force pulls the node back."""

    name = "membrane_collision"
    _params = _contact_params(positive, "steepness (1/length)")
    _core_params = staticmethod(_lbmd.MembraneCollisionParams)


class HardContactInteraction(NonBondedModel):
    """A contact that cannot be crossed (doc/interactions.md): between nodes
    of different cells (different mol_id), and between a node and a wall,
    with the gap h = r - offset,
    F(h) = a ((cutoff / h)^n - 1) for 0 < h < cutoff, zero beyond.

    The force diverges as the gap closes, so with an offset at least the
    other cell's covering radius (``oif.contact_settings`` chooses it) no
    finite squeeze pushes a node through a membrane. At the start of every
    run the gap where the contact's stiffness outruns the time step is
    computed (``get_params()['guard_gap']``); a pair that closes below it
    stops the run with SimulationInstability "contact_overrun"."""

    name = "hard_contact"
    _params = [Param("a", "float", check=positive, doc="force scale (force at h = cutoff / 2^(1/n) is a)"),
               Param("n", "float", 2.0, check=positive, doc="exponent of the divergence"),
               Param("cutoff", "float", check=positive, doc="range of the gap"),
               Param("offset", "float", 0.0, check=non_negative, doc="node distance where the gap is 0")]
    _core_params = staticmethod(_lbmd.HardContactParams)

    def get_params(self):
        p = getattr(self._system._core, "get_" + self.name)(*self._types)
        out = {q.name: getattr(p, q.name) for q in self._params}
        out["guard_gap"] = p.guard_gap
        return out

    def deactivate(self):
        getattr(self._system._core, "set_" + self.name)(*self._types, self._core_params(a=0.0, n=2.0, cutoff=0.0,
                                                                                        offset=0.0))


class MorseInteraction(NonBondedModel):
    """Morse potential with ESPResSo's semantics (ESPResSo 4.2 user guide,
    "Morse interaction"): for r < cutoff
    U(r) = eps (exp(-2 alpha (r - rmin)) - 2 exp(-alpha (r - rmin))) - shift,
    the shift making U(cutoff) = 0; zero beyond. As in ESPResSo, ``cutoff``
    defaults to 0, which leaves the pair without interaction."""

    name = "morse"
    _params = [Param("eps", "float", check=non_negative, doc="depth of the minimum"),
               Param("alpha", "float", check=positive, doc="stiffness (1/length)"),
               Param("rmin", "float", check=non_negative, doc="distance of the minimum"),
               Param("cutoff", "float", 0.0, check=non_negative, doc="range")]
    _core_params = staticmethod(_lbmd.MorseParams)


#: name -> class of every non-bonded model, as attributes of a type pair
NONBONDED_MODELS = {SoftSphereInteraction.name: SoftSphereInteraction,
                    MembraneCollisionInteraction.name: MembraneCollisionInteraction,
                    MorseInteraction.name: MorseInteraction,
                    HardContactInteraction.name: HardContactInteraction}


def membrane_angles(nodes, angles):
    """PyOIF's angle between the triangles (A, B, C) and (B, C, D) for rows
    (A, B, C, D) of node indices (pi for a flat pair, in [0, 2 pi)): the
    reference angles phi0 of a relaxed mesh, by the bending force's own
    function (so a relaxed mesh is exactly at its reference angles)."""
    return _lbmd.membrane_angles(np.ascontiguousarray(nodes, dtype=float),
                                 np.ascontiguousarray(angles, dtype=np.int32))


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

    def __dir__(self):
        # the models, served by __getattr__, for tab completion
        return sorted(set(super().__dir__()) | set(NONBONDED_MODELS))

    def __repr__(self):
        active = [name for name, cls in NONBONDED_MODELS.items() if cls(self._system, *self._types).is_active()]
        return f"NonBondedTypePair({self._types[0]}, {self._types[1]}, active={active})"


class NonBondedInteractions:
    """``system.non_bonded_inter[t1, t2]``."""

    def __init__(self, system):
        self._system = system

    def __getitem__(self, key):
        if not (isinstance(key, tuple) and len(key) == 2):
            raise TypeError("non_bonded_inter: index with two particle types, e.g. [0, 1]")
        for t in key:
            if (isinstance(t, bool) or not isinstance(t, (int, np.integer))
                    or not 0 <= t <= _lbmd.MAX_PARTICLE_TYPE):
                raise ValueError(f"non_bonded_inter: particle types must be integers in "
                                 f"0..{_lbmd.MAX_PARTICLE_TYPE}, got {t!r}")
        return NonBondedTypePair(self._system, int(key[0]), int(key[1]))

    def __repr__(self):
        return f"NonBondedInteractions(non_bonded_inter[t1, t2].<model>; models: {', '.join(NONBONDED_MODELS)})"


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


_TWO_PI = 2.0 * np.pi


class OifLocalForces(BondedInteraction):
    """OIF moduli on a pair of triangles sharing an edge (one bond per pair):
    stretching of the shared edge (model eq. 3: neo-Hookean ``ks``, linear
    ``kslin``), bending (eq. 4, ``kb``), local area of both triangles (eq. 5,
    ``kal``, each triangle weighted 1/3 per pair as it is in three pairs) and
    membrane viscosity on the edge (``kvisc``).

    Bond: for PyOIF's Angle(A, B, C, D) with shared edge BC, the particle B
    owns the bond with partners A, C, D: ``B.add_bond((bond, A, C, D))``, or in
    bulk ``system.part.add_bonds(bond, ids, per_bond)`` with rows (B, A, C, D).
    The reference values r0 = ``|BC|``, phi0 = angle_btw_triangles(A, B, C, D),
    A01 = area ABC, A02 = area BCD are per bond (``per_bond`` rows
    (r0, phi0, A01, A02)), so one instance serves a whole cell type; without
    ``per_bond`` every bond gets this instance's r0, phi0, A01, A02 (the
    ESPResSo way: one instance per angle).
    """

    _params = [Param("r0", "float", 0.0, check=non_negative, doc="relaxed edge length"),
               Param("ks", "float", 0.0, check=non_negative, doc="neo-Hookean stretching"),
               Param("kslin", "float", 0.0, check=non_negative, doc="linear stretching"),
               Param("phi0", "float", 0.0,
                     check=(lambda x: 0.0 <= x <= _TWO_PI, "in [0, 2 pi]"),
                     doc="relaxed angle between the triangles"),
               Param("kb", "float", 0.0, check=non_negative, doc="bending"),
               Param("A01", "float", 0.0, check=non_negative, doc="relaxed area of ABC"),
               Param("A02", "float", 0.0, check=non_negative, doc="relaxed area of BCD"),
               Param("kal", "float", 0.0, check=non_negative, doc="local area"),
               Param("kvisc", "float", 0.0, check=non_negative, doc="membrane viscosity")]
    _core_class = _lbmd.OifLocalForces
    n_partners = 3
    per_bond_stride = 4

    def _core_object(self):
        v = self._values
        return self._core_class(ks=v["ks"], kslin=v["kslin"], kb=v["kb"], kal=v["kal"],
                                kvisc=v["kvisc"])

    def _default_per_bond(self, n_bonds):
        v = self._values
        for name in ("r0", "A01", "A02"):
            if not v[name] > 0:
                raise ValueError(f"OifLocalForces: parameter '{name}' must be > 0 for bonds "
                                 f"added without per-bond reference values, got {v[name]!r}")
        return np.tile([v["r0"], v["phi0"], v["A01"], v["A02"]], (n_bonds, 1))


class OifGlobalForces(BondedInteraction):
    """Global area (model eq. 6, ``ka_g``) and volume (eq. 7, ``kv``) of each
    cell: one bond per triangle (A, B, C), ``A.add_bond((bond, B, C))``. A cell
    is the mol_id of the triangle's first particle; one instance serves all
    cells of a type (A0_g, V0 its relaxed surface and volume). The cells'
    surfaces and volumes are summed once per step for all cells together."""

    _params = [Param("A0_g", "float", check=positive, doc="relaxed cell surface"),
               Param("ka_g", "float", 0.0, check=non_negative, doc="global area"),
               Param("V0", "float", check=positive, doc="relaxed cell volume"),
               Param("kv", "float", 0.0, check=non_negative, doc="volume")]
    _core_class = _lbmd.OifGlobalForces
    n_partners = 2


class OifOutDirection(BondedInteraction):
    """Outward unit normals of membrane nodes, for membrane_collision: one bond
    per triangle (A, B, C) of each cell, ``A.add_bond((bond, B, C))``. Before
    the pair forces of every step the node normals are set to the
    area-weighted mean of their triangles' normals, pointing out of the cell
    whatever the triangles' orientation. No forces. (ESPResSo's version is a
    4-particle bond with three neighbours; this one uses the triangles.)"""

    _params = []
    _core_class = _lbmd.OifOutDirection
    n_partners = 2


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
        # whole numbers in the id range only: 0.5 or 2**32 + 1 must not become another particle
        ids = integers("add_bonds", "ids", ids, 0, INT32_MAX - 1)
        if np.ndim(ids) == 1 and np.size(ids) == 0:
            ids = ids.reshape(0, bond.n_partners + 1)
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

    def __repr__(self):
        return f"BondedInteractions({len(self._list)} bonds: " + ", ".join(
            f"{i}: {type(b).__name__}" for i, b in enumerate(self._list)) + ")"
