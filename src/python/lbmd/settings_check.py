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
#: the Mach numbers past which the speed watch warns (once each)
MACH_WARN_LEVELS = (MACH_ADVISED, MACH_LIMIT, 0.4, 0.8)
#: Poiseuille compressibility error of MRT against Mach (measured)
MACH_ERROR = ((0.03, 7.5e-7), (0.043, 1.2e-5), (0.17, 3e-3))


class Setting:
    """One choice: its name, value, the limit it is held against, the error
    to expect, whether a cheaper setting would do, ok (False: past the
    measured limit, warned) and advised (False: within the measured limit
    but past the advice, printed as a note, never as "ok")."""

    def __init__(self, name, value, limit, expected, cheaper="", ok=True, advised=True):
        self.name, self.value, self.limit = name, value, limit
        self.expected, self.cheaper, self.ok = expected, cheaper, ok
        self.advised = bool(ok and advised)

    def __repr__(self):
        return (f"Setting({self.name!r}, value={self.value!r}, ok={self.ok}, advised={self.advised})")

    def line(self):
        flag = "WARN" if not self.ok else "ok  " if self.advised else "note"
        text = f"[{flag}] {self.name}: {self.value}; limit {self.limit}; expect {self.expected}"
        if self.cheaper:
            text += f"; cheaper: {self.cheaper}"
        return text


class SettingsReport(list):
    """The settings of a scene (a list of Setting); printed as a table."""

    def warnings(self):
        return [s for s in self if not s.ok]

    def notes(self):
        """Settings within the measured limits but past the advice."""
        return [s for s in self if s.ok and not s.advised]

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
            ok=collision in ("MRT", "TRT"), advised=False))
    else:
        report.append(Setting("relaxation time tau*", f"{tau_star:.4g} ({collision})",
                              f"advised {lo}..{hi}", "stable; wall and drag as charted"))
    # the fluid's fastest node now (collective)
    speed = float(np.linalg.norm(fluid[:, :, :].velocity, axis=-1).max())
    c_s = fluid.agrid / fluid.tau / math.sqrt(3.0)
    mach = float(speed / c_s)
    expected = "fluid at rest now: check again once it flows" if mach == 0 else _mach_error(mach)
    report.append(Setting("Mach number (fastest node now)", f"{mach:.3g}",
                          f"advised <= {MACH_ADVISED}, at most {MACH_LIMIT}", expected,
                          ok=mach <= MACH_ADVISED))
    highest = system.__dict__.get("_mach_highest")
    if highest is not None:
        # what the speed watch saw during the runs so far (every
        # fluid.speed_watch_every updates)
        m, node, update = highest
        report.append(Setting("Mach number (fastest node seen during the runs)", f"{m:.3g}",
                              f"advised <= {MACH_ADVISED}, at most {MACH_LIMIT}",
                              f"{_mach_error(m)} (node {node}, after lattice update {update})",
                              ok=m <= MACH_ADVISED))
    single = bool(getattr(fluid, "single_precision", False))
    report.append(Setting("precision", "single" if single else "double", "",
                          "round-off about 1e-6 of the speeds (float deviations from rest)" if single
                          else "round-off about 1e-15",
                          "" if single else "single_precision=True updates the lattice 2.3x as "
                          "fast (128^3, one core) with errors of 1e-6 to 1e-5 of the speeds "
                          "(Poiseuille, Couette, coupling: doc/lb.md)"))


#: share of a constraint's lattice nodes that are fluid (or of a lattice
#: boundary's nodes outside every constraint) from which the two are
#: reported as not the same wall; the surface's own nodes can go either way
WALL_MISMATCH_SHARE = 0.5
#: lattice nodes the wall comparison samples at most (a regular subset)
WALL_SAMPLE_NODES = 400_000


def _walls_settings(system, fluid, report):
    """Constraints (what particles feel) against lattice boundaries (what
    the fluid feels), compared on the lattice nodes: a constraint whose
    inside is mostly fluid lets the fluid flow through a wall the cells
    cannot pass; a lattice boundary outside every constraint stops the fluid
    but lets particles in. Collective (the boundary flags of every rank)."""
    constraints = [c for c in system.constraints if hasattr(c, "shape")]
    boundaries = list(system.lbboundaries)
    if not constraints and not boundaries:
        return
    flags = np.asarray(fluid[:, :, :].boundary)
    step = max(1, int(math.ceil((flags.size / WALL_SAMPLE_NODES) ** (1.0 / 3.0))))
    flags = flags[::step, ::step, ::step]
    idx = np.indices(flags.shape).reshape(3, -1).T * step
    points = (idx + 0.5) * fluid.agrid
    flags = flags.reshape(-1)
    covered = np.zeros(len(points), dtype=bool)
    for i, c in enumerate(constraints):
        inside = c.shape.signed_distances(points) < 0.0
        if not c.penetrable:
            covered |= inside
        n_inside = int(inside.sum())
        if n_inside == 0 or c.penetrable:
            continue
        fluid_share = float(np.count_nonzero(flags[inside] == 0)) / n_inside
        name = f"constraint {i} ({type(c.shape).__name__}) against the lattice boundaries"
        if fluid_share > WALL_MISMATCH_SHARE:
            report.append(Setting(
                name, f"{100 * fluid_share:.0f} % of the lattice nodes inside it are fluid",
                "a wall is both a constraint (for the particles) and a lattice boundary (for the fluid)",
                "the fluid flows through this wall while the cells cannot pass it (a fluid "
                "between walls only as constraints accelerates without limit): add "
                "system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(shape=<the same shape>))",
                ok=False))
        else:
            report.append(Setting(name, "a lattice boundary too", "", "the fluid and the particles see one wall"))
    if not len(system.part):
        return  # a boundary no particle can reach is the fluid's own business
    for i, b in enumerate(boundaries):
        mine = flags == i + 1
        n_mine = int(mine.sum())
        if n_mine == 0:
            continue
        outside = float(np.count_nonzero(~covered[mine])) / n_mine
        if outside > WALL_MISMATCH_SHARE:
            report.append(Setting(
                f"lattice boundary {i} ({type(b.shape).__name__}) against the constraints",
                f"{100 * outside:.0f} % of its nodes are inside no constraint",
                "a wall is both a lattice boundary (for the fluid) and a constraint (for the particles)",
                "the fluid stops at this wall but the particles (cells) feel nothing and pass into it: "
                "add system.constraints.add(shape=<the same shape>, particle_type=<a wall type>) and a "
                "contact between the cells' and the wall's types (oif.set_contacts(..., wall_types=...))",
                ok=False))


def _mach_error(mach):
    if mach < MACH_ERROR[0][0]:
        return f"Poiseuille compressibility error below {MACH_ERROR[0][1]:.1g} of the peak speed"
    if mach > MACH_ERROR[-1][0]:
        return (f"Poiseuille compressibility error above {MACH_ERROR[-1][1]:.1g} of the peak speed "
                f"(measured at Mach {MACH_ERROR[-1][0]}; faster not charted)")
    return f"Poiseuille compressibility error about {_interpolate_log(MACH_ERROR, mach):.1g} of the peak speed"


def watch_fluid_speed(system, fluid):
    """After a run (collective): the fastest node the fluid's speed watch saw
    in it (a pass every ``fluid.speed_watch_every`` updates); a SettingsWarning
    (rank 0) naming the node, the update and the time when it is past the
    advised Mach number, once for each of MACH_WARN_LEVELS it passes. The
    highest seen is kept for check_settings."""
    seen = fluid._core.take_speed_watch()
    if seen is None:
        return
    mach, node, update = seen
    d = system.__dict__
    if mach > d.get("_mach_highest", (0.0,))[0]:
        d["_mach_highest"] = (mach, tuple(int(n) for n in node), int(update))
    # one warning per level passed: the advice, the limit, then each doubling
    level = sum(mach > m for m in MACH_WARN_LEVELS)
    if level <= d.get("_mach_warned", 0):
        return
    d["_mach_warned"] = level
    from . import rank
    if rank == 0:
        where = ", ".join(f"{(n + 0.5) * fluid.agrid:g}" for n in node)
        warnings.warn(
            f"check_settings: the fluid reached Mach {mach:.3g} (advised <= {MACH_ADVISED}, at most "
            f"{MACH_LIMIT}) at lattice node ({', '.join(str(int(n)) for n in node)}), position ({where}), "
            f"after lattice update {update} (time {update * fluid.tau:g}): {_mach_error(mach)}; "
            f"lower the driving force, pressure drop or inlet speed, or make the lattice's sound speed "
            f"larger against the flow (a shorter tau at the same viscosity)", SettingsWarning, stacklevel=3)


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
        _walls_settings(system, fluid, report)
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
