"""``system.check_settings()``: each modelling choice of a scene against the
measured limits and errors of doc/accuracy.md, and whether a cheaper setting
would do. Run once, with warnings only, at the first ``integrator.run``.

Every limit here is a measurement (doc/accuracy.md, produced by
maintainer/benchmarks/accuracy_vs_cost.py) or a stated estimate:

- lattice relaxation time tau* = 3 nu* + 1/2 (lattice units): stable at
  Mach <= 0.2 from tau* 0.513 (MRT, TRT), 0.507 (BGK); the advice is
  0.55 <= tau* <= 3; above 3 the drag of obstacles drifts (-9 to -25 % for
  MRT_ESPRESSO, -24 to -58 % for BGK at tau* 3.5; about 1 % for MRT).
- Mach number |u| / c_s: every model stable up to 0.6 from tau* 0.55; the
  compressibility error of Poiseuille flow (MRT) is 7.5e-7 at Mach 0.03,
  1.2e-5 at 0.043 and 3e-3 at 0.17. Advice: <= 0.1, at most 0.2.
- a cell's radius in lattice nodes against the Stokes drag of a sphere of
  that many nodes: +2.1 % at 3 nodes, within -1 to -1.7 % from 6.
- the mesh's mean edge against agrid: the coupling interpolates the fluid
  over the 8 nodes around each membrane node; an edge longer than 2 agrid
  leaves lattice nodes between membrane nodes (fluid passes through the
  membrane, Cimrak et al. 2012 use edges about agrid), shorter than
  agrid / 2 adds nodes the lattice cannot resolve (cost, no accuracy).
- the time step against the membrane's stiffness: explicit velocity Verlet
  is stable for omega dt < 2 with omega^2 = k / m; k is estimated as six
  stretching springs per node (ks at rest: F = ks (l - l0), doc/model.md).
- the coupling: gamma dt / m above about 1 makes particles and fluid
  overshoot (the engine names it when the fluid blows up).
"""
import math
import warnings

import numpy as np

#: advice and measured limits (doc/accuracy.md)
TAU_STABLE_MIN = {"MRT": 0.513, "TRT": 0.513, "BGK": 0.507, "MRT_ESPRESSO": 0.5005}
TAU_ADVISED = (0.55, 3.0)
MACH_ADVISED, MACH_LIMIT = 0.1, 0.2
#: Poiseuille compressibility error of MRT against Mach (measured)
MACH_ERROR = ((0.03, 7.5e-7), (0.043, 1.2e-5), (0.17, 3e-3))
EDGE_PER_AGRID = (0.5, 2.0)
GAMMA_DT_PER_MASS_MAX = 1.0


class Setting:
    """One choice: its name, value, the limit it is held against, the error
    to expect, whether a cheaper setting would do, and ok (False: warned)."""

    def __init__(self, name, value, limit, expected, cheaper="", ok=True):
        self.name, self.value, self.limit = name, value, limit
        self.expected, self.cheaper, self.ok = expected, cheaper, ok

    def __repr__(self):
        return (f"Setting({self.name!r}, value={self.value!r}, ok={self.ok})")

    def line(self):
        flag = "ok  " if self.ok else "WARN"
        text = f"[{flag}] {self.name}: {self.value}; limit {self.limit}; expect {self.expected}"
        if self.cheaper:
            text += f"; cheaper: {self.cheaper}"
        return text


class SettingsReport(list):
    """The settings of a scene (a list of Setting); printed as a table."""

    def warnings(self):
        return [s for s in self if not s.ok]

    def __str__(self):
        if not self:
            return "check_settings: nothing to check (no fluid, no cells)"
        return "\n".join(s.line() for s in self)

    __repr__ = __str__


def _interpolate_log(table, x):
    """Log-log interpolation in a measured table, clamped at its ends."""
    xs = np.log([p[0] for p in table])
    ys = np.log([p[1] for p in table])
    return float(np.exp(np.interp(math.log(max(x, 1e-300)), xs, ys)))


def _fluid_settings(system, fluid, report):
    nu = fluid.visc * fluid.tau / fluid.agrid ** 2
    tau_star = 3.0 * nu + 0.5
    collision = fluid.collision
    lo, hi = TAU_ADVISED
    stable = TAU_STABLE_MIN.get(collision, 0.513)
    if tau_star < lo:
        report.append(Setting(
            "relaxation time tau* = 3 visc tau / agrid^2 + 1/2", f"{tau_star:.4g} ({collision})",
            f"advised {lo}..{hi}; measured unstable below {stable} at Mach 0.2",
            "runs near the stability edge: raise visc * tau / agrid^2 (a larger agrid or a "
            "shorter tau)", ok=False))
    elif tau_star > hi:
        report.append(Setting(
            "relaxation time tau*", f"{tau_star:.4g} ({collision})", f"advised {lo}..{hi}",
            "the drag of obstacles drifts with tau* (MRT about 1 %, MRT_ESPRESSO -9..-25 %, "
            "BGK -24..-58 % at 3.5); a longer tau or smaller agrid brings it back",
            ok=collision in ("MRT", "TRT")))
    else:
        report.append(Setting("relaxation time tau*", f"{tau_star:.4g} ({collision})",
                              f"advised {lo}..{hi}", "stable; wall and drag as charted"))
    # the fluid's fastest node now (collective)
    speed = float(np.linalg.norm(fluid[:, :, :].velocity, axis=-1).max())
    c_s = fluid.agrid / fluid.tau / math.sqrt(3.0)
    mach = float(speed / c_s)
    if mach == 0:
        expected = "fluid at rest now: check again once it flows"
    elif mach < MACH_ERROR[0][0]:
        expected = f"Poiseuille compressibility error below {MACH_ERROR[0][1]:.1g} of the peak speed"
    else:
        expected = (f"Poiseuille compressibility error about {_interpolate_log(MACH_ERROR, mach):.1g}"
                    f" of the peak speed")
    report.append(Setting("Mach number (fastest node now)", f"{mach:.3g}",
                          f"advised <= {MACH_ADVISED}, at most {MACH_LIMIT}", expected,
                          ok=mach <= MACH_LIMIT))
    single = bool(getattr(fluid, "single_precision", False))
    report.append(Setting("precision", "single" if single else "double", "",
                          "round-off about 1e-6 of the speeds (float deviations from rest)" if single
                          else "round-off about 1e-15",
                          "" if single else "single_precision=True halves the lattice's memory "
                          "traffic where 1e-6 suffices"))


def _cell_settings(system, fluid, gamma, report):
    try:
        import oif
    except ImportError:
        return
    cells = oif.oif_classes.live_cells(system)
    types = {}
    for c in cells:
        types.setdefault(id(c.cell_type), (c.cell_type, []))[1].append(c)
    dt = system.time_step
    for cell_type, members in types.values():
        nodes = cell_type.mesh.get_n_nodes()
        edge = float(np.mean(cell_type.r0)) if len(cell_type.r0) else 0.0
        radius = 0.5 * float(max(members[0].diameter(), 0.0)) if hasattr(members[0], "diameter") else 0.0
        label = f"cells of {nodes} nodes ({len(members)})"
        mass = float(np.min(members[0].particles.mass))
        if fluid is not None:
            r_nodes = radius / fluid.agrid
            drag = ("+2 % or worse" if r_nodes < 4 else "within 1-2 %")
            report.append(Setting(
                f"{label}: radius / agrid", f"{r_nodes:.3g} nodes", "advised >= 4",
                f"drag of a sphere of that many nodes {drag} (charted)",
                "a coarser lattice (larger agrid) would resolve the cells as well"
                if r_nodes > 12 else "", ok=r_nodes >= 2.0))
            ratio = edge / fluid.agrid
            lo, hi = EDGE_PER_AGRID
            report.append(Setting(
                f"{label}: mean edge / agrid", f"{ratio:.3g}", f"advised {lo}..{hi}",
                "fluid passes between the membrane's nodes" if ratio > hi else
                "the membrane and the lattice resolve each other",
                "a coarser mesh would do for the coupling" if ratio < lo else "", ok=ratio <= hi))
        # time step against the stiffest elastic response of a node
        k = 6.0 * (cell_type.ks + cell_type.kslin)
        if k > 0:
            dt_max = 2.0 * math.sqrt(mass / k)
            report.append(Setting(
                f"{label}: time step against ks", f"{dt:.3g}",
                f"estimated limit 2 sqrt(m / 6 ks) = {dt_max:.3g}",
                "stable" if dt < 0.5 * dt_max else "near the stability limit of the membrane",
                f"the membrane would stay stable up to a time step of about {0.5 * dt_max:.3g} "
                f"(tau of the fluid a multiple of it)" if dt < 0.05 * dt_max else "",
                ok=dt < 0.5 * dt_max))
        if gamma:
            kick = gamma * dt / mass
            report.append(Setting(
                f"{label}: coupling gamma * time_step / mass", f"{kick:.3g}",
                f"< {GAMMA_DT_PER_MASS_MAX}",
                f"total friction of a cell {gamma * nodes:.4g} (gamma x nodes; keep it when "
                f"changing the mesh)", ok=kick < GAMMA_DT_PER_MASS_MAX))
    # contacts between the cells' particle types
    cell_types = sorted({int(t) for c in cells for t in np.unique(c.particles.type)})
    if len(cells) > 1:
        for i, a in enumerate(cell_types):
            for b in cell_types[i:]:
                pair = system.non_bonded_inter[a, b]
                if not (pair.membrane_collision.is_active() or pair.soft_sphere.is_active()):
                    report.append(Setting(
                        f"contact between cell types {a} and {b}", "none", "a pair contact",
                        "the cells pass through each other unseen (no crossing check without a "
                        "contact): add membrane_collision (cell types with normal=True)", ok=False))


def check_settings(system, warn=False):
    """The report (SettingsReport); with warn, a RuntimeWarning per setting
    outside its limit (on rank 0 only)."""
    fluid = None
    for actor in system.actors:
        if hasattr(actor, "agrid") and hasattr(actor, "tau"):
            fluid = actor
    gamma = 0.0
    for state in system.thermostat.get_state():
        if state.get("type") == "LB":
            gamma = state["gamma"]
        elif state.get("type") == "LANGEVIN":
            gamma = gamma or 0.0
    report = SettingsReport()
    if fluid is not None:
        _fluid_settings(system, fluid, report)
    _cell_settings(system, fluid, gamma, report)
    if warn:
        from . import rank
        if rank == 0:
            for s in report.warnings():
                warnings.warn(f"check_settings: {s.line()}", SettingsWarning, stacklevel=3)
    return report


class SettingsWarning(RuntimeWarning):
    """A scene setting outside its measured limit (system.check_settings())."""
