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
- the mesh's node count against the error of a cell's shape (stretched
  diameters, extents in flow) relative to rbc2562: rbc162 4-5 %, rbc374
  1.2-4.5 %, rbc642 0.5-1.3 %, rbc1002 0.2-1.4 %.
- the time step against the membrane's stiffness: measured for the scene
  itself. The limit depends on the moduli, the mesh (its edge lengths),
  the node mass and above all the friction on the nodes (doc/accuracy.md:
  rbc374 at 100 x the paper's kal held dt 0.026 with friction 0.05 per
  node; ESPResSo's sphere393 of radius 12 at kb = kal = 1 holds dt 0.4
  with friction 0.7), so a table cannot cover every scene: one cell of
  each type is run alone (membrane_trial: released at rest from a 1.1 x
  stretched shape with noise of 3 % of its mean edge, TRIAL_STEPS steps,
  Langevin friction equal to the scene's coupling or Langevin gamma, the
  scene's node mass) at the scene's time step and at 1.5 x it; it warns
  when the trial at the scene's own time step fails (every warning names
  a setting that fails), and says "near the limit" when only 1.5 x fails.
- the coupling: the fluid blew up where gamma N dt / (rho S agrid) reached
  1.4-2.1 (N nodes on the cell's surface S), whatever the mesh; advised
  below 1. gamma dt / m above about 1 makes particles overshoot too.
- contacts: with the membrane_collision cutoff + offset shorter than the
  mesh's longest edge, cells cross (up to 176 nodes inside others at the
  paper's a 1e-4, cutoff 0.5, edges up to 0.85); a cutoff longer than the
  edges kept them apart at a 0.1 up to haematocrit 0.42.
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
                          "" if single else "single_precision=True updates the lattice 2.3x as "
                          "fast (128^3, one core) with errors of 1e-6 to 1e-5 of the speeds "
                          "(Poiseuille, Couette, coupling: doc/lb.md)"))


def check_settings(system, warn=False):
    """The report (SettingsReport); with warn, a RuntimeWarning per setting
    outside its limit (on rank 0 only)."""
    system.prepare()  # collective: the fluid's flags current (doc/engine.md)
    fluid = None
    for actor in system.actors:
        if hasattr(actor, "agrid") and hasattr(actor, "tau"):
            fluid = actor
    gamma = langevin = 0.0
    for state in system.thermostat.get_state():
        if state.get("type") == "LB":
            gamma = state["gamma"]
        elif state.get("type") == "LANGEVIN":
            langevin = state.get("gamma", 0.0) or 0.0
    report = SettingsReport()
    if fluid is not None:
        _fluid_settings(system, fluid, report)
    # the cells' lines come from the cell model that made them (oif), through
    # the registry: lbmd does not know the cell model (lbmd.cell_registry)
    from .cell_registry import settings_checks
    for check, cells in settings_checks(system):
        check(system, cells, fluid, gamma, langevin, report)
    if warn:
        from . import rank
        if rank == 0:
            for s in report.warnings():
                warnings.warn(f"check_settings: {s.line()}", SettingsWarning, stacklevel=3)
    return report


class SettingsWarning(RuntimeWarning):
    """A scene setting outside its measured limit (system.check_settings())."""
