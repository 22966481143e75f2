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
EDGE_PER_AGRID = (0.5, 2.0)
GAMMA_DT_PER_MASS_MAX = 1.0
#: shape error against rbc2562 (stretch and flow, largest of both) by nodes
MESH_ERROR = ((162, 0.05), (374, 0.045), (642, 0.013), (1002, 0.014), (2562, 0.0))
#: the membrane trial: steps, stretch, noise (share of the mean edge), and the
#: factor on the time step that must still be stable
TRIAL_STEPS, TRIAL_STRETCH, TRIAL_NOISE, TRIAL_MARGIN = 400, 1.1, 0.03, 1.5
#: gamma N dt / (rho S agrid): measured fluid blow-up from 1.4
COUPLING_ADVISED, COUPLING_FAILED = 1.0, 1.4
#: membrane_collision's a from which cells stayed apart (with a reach longer
#: than the mesh's edges, up to 2 nN per cell and haematocrit 0.42); the
#: paper's a = 1e-4 acted like no contact at all
CONTACT_A_MIN = 0.1
#: cell types under one coupling gamma whose node densities (nodes per
#: surface) differ by more than this factor feel a different friction per area
NODE_DENSITY_RATIO_MAX = 2.0


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


def _cell_settings(system, fluid, gamma, langevin, report):
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
        # mesh resolution against the measured shape error
        err = float(np.interp(nodes, [p[0] for p in MESH_ERROR], [p[1] for p in MESH_ERROR]))
        report.append(Setting(
            f"{label}: mesh resolution", f"{nodes} nodes", "rbc374 for 1-5 %, 642+ below 1.5 %",
            f"shape (diameters, extents in flow) within about {100 * err:.1f} % of the finest mesh"
            if nodes < 2562 else "the finest mesh measured",
            "rbc1002 is within 0.2-1.4 % at a quarter of rbc2562's cost" if nodes > 1002 else ""))
        # time step against the membrane: measured on the spot, one cell of
        # this type alone at the scene's time step, node mass and friction
        # (membrane_trial), and at TRIAL_MARGIN x the time step
        friction = (gamma or 0.0) + langevin  # the nodes' friction: coupling and Langevin
        at_dt = membrane_trial(cell_type, dt, mass, friction)
        at_margin = membrane_trial(cell_type, TRIAL_MARGIN * dt, mass, friction) if at_dt == "stable" else at_dt
        report.append(Setting(
            f"{label}: time step against the membrane (kb, kal)", f"{dt:.3g}",
            f"a cell of this type alone, released from a stretched, noisy shape, at this time step, "
            f"node mass {mass:.3g} and friction {friction:.3g}: {at_dt} at dt, {at_margin} at {TRIAL_MARGIN:g} dt",
            f"stable with a factor {TRIAL_MARGIN:g} to spare" if at_margin == "stable" else
            (f"stable, but near the limit (unstable at {TRIAL_MARGIN:g} x the time step: keep it)"
             if at_dt == "stable" else
             "past the membrane's stability limit: lower the time step or the moduli (kb, kal, kvisc), "
             "or raise the node mass"),
            ok=at_dt == "stable"))
        if gamma:
            kick = gamma * dt / mass
            report.append(Setting(
                f"{label}: coupling gamma * time_step / mass", f"{kick:.3g}",
                f"< {GAMMA_DT_PER_MASS_MAX}",
                f"total friction of a cell gamma N = {gamma * nodes:.4g} (keep it when changing "
                f"the mesh: oif's suggest_LBgamma)", ok=kick < GAMMA_DT_PER_MASS_MAX))
            if fluid is not None:
                tau = fluid.tau
                density = gamma * nodes * tau / (fluid.dens * cell_type.surface0 * fluid.agrid)
                report.append(Setting(
                    f"{label}: coupling gamma N tau / (dens S agrid)", f"{density:.3g}",
                    f"advised < {COUPLING_ADVISED}; the fluid blew up from {COUPLING_FAILED}",
                    "stable" if density < COUPLING_ADVISED else "near the coupling's stability limit",
                    ok=density < COUPLING_ADVISED))
    # one gamma for cell types of different node density: the friction per
    # membrane area (gamma N / S) differs by their ratio
    if gamma and len(types) > 1:
        dens = sorted((ct.mesh.get_n_nodes() / ct.surface0, ct.mesh.get_n_nodes(), ct.surface0)
                      for ct, _ in types.values())
        lo, hi = dens[0], dens[-1]
        ratio = hi[0] / lo[0]
        report.append(Setting(
            "cell types under one gamma: node density ratio", f"{ratio:.3g}",
            f"< {NODE_DENSITY_RATIO_MAX:g} (nodes per surface: {hi[1]} nodes on {hi[2]:.4g} against "
            f"{lo[1]} nodes on {lo[2]:.4g})",
            "the denser cell type feels that much more friction per area from the fluid: "
            "use meshes of similar node density (the coupling has one gamma for all particles)",
            ok=ratio < NODE_DENSITY_RATIO_MAX))
    # contacts between the cells' particle types
    cell_types = sorted({int(t) for c in cells for t in np.unique(c.particles.type)})
    if len(cells) > 1:
        for i, a in enumerate(cell_types):
            for b in cell_types[i:]:
                pair = system.non_bonded_inter[a, b]
                if pair.hard_contact.is_active():
                    p = pair.hard_contact.get_params()
                    pair_types = [ct for ct, members in types.values()
                                  if any(int(members[0].particle_type) == t for t in (a, b))]
                    need = oif.contacts.contact_offset(pair_types or [ct for ct, _ in types.values()])
                    report.append(Setting(
                        f"contact between cell types {a} and {b}",
                        f"hard_contact a {p['a']:g}, n {p['n']:g}, cutoff {p['cutoff']:g}, offset {p['offset']:g}",
                        f"offset >= the meshes' covering radius {need:.3g} (no node passes a membrane)",
                        "cannot be crossed; a push the time step cannot follow stops with contact_overrun"
                        if p["offset"] >= need - 1e-9 else
                        "a node can pass through the other cell's largest triangles: raise the offset "
                        "(oif.contact_settings)", ok=p["offset"] >= need - 1e-9))
                elif pair.membrane_collision.is_active():
                    p = pair.membrane_collision.get_params()
                    reach = p["cutoff"] + p["offset"]
                    edge = max(float(np.max(ct.r0)) for ct, _ in types.values())
                    weak = p["a"] < CONTACT_A_MIN
                    report.append(Setting(
                        f"contact between cell types {a} and {b}",
                        f"membrane_collision a {p['a']:g}, cutoff + offset {reach:g}",
                        f"reach > longest mesh edge {edge:.3g}; a >= {CONTACT_A_MIN:g}",
                        "measured: cells kept apart up to haematocrit 0.42" if reach > edge and not weak
                        else "measured: cells cross each other (the engine stops the run with "
                        "membrane_crossing): a cutoff longer than the edges and a >= 0.1 held them",
                        ok=reach > edge and not weak))
                elif not pair.soft_sphere.is_active():
                    report.append(Setting(
                        f"contact between cell types {a} and {b}", "none", "a pair contact",
                        "the cells pass through each other unseen (no crossing check without a "
                        "contact): add the advised hard_contact (oif.set_contacts)", ok=False))


_TRIALS = {}


def membrane_trial(cell_type, dt, mass, friction, steps=None):
    """'stable' or how one cell of this type, alone in a System of its own,
    failed in `steps` steps at time step dt, node mass and Langevin friction
    (kT 0): released at rest from a TRIAL_STRETCH x stretched shape with
    noise of TRIAL_NOISE of its mean edge. Unstable: a SimulationInstability,
    non-finite positions, or the elastic energy grown tenfold. Remembered
    per (mesh, moduli, dt, mass, friction)."""
    import oif
    from . import System, SimulationInstability
    steps = steps or TRIAL_STEPS
    # the type by its content, not its id (an id is reused after the type
    # is gone): the relaxed mesh and the moduli
    nodes = np.asarray(cell_type.mesh._nodes, dtype=float)
    moduli = tuple(float(getattr(cell_type, k)) for k in ("ks", "kslin", "kb", "kal", "kag", "kv", "kvisc"))
    key = (nodes.tobytes(), np.asarray(cell_type.mesh._topo.triangles).tobytes(), moduli,
           bool(cell_type.normal), float(dt), float(mass), float(friction), steps)
    if key in _TRIALS:
        return _TRIALS[key]
    nodes = nodes - nodes.mean(axis=0)
    side = 3.0 * float(np.ptp(nodes, axis=0).max()) + 10.0
    s = System(box_l=[side] * 3)
    s.__dict__["_settings_checked"] = True  # the trial's own first run checks nothing
    s.time_step = dt
    s.cell_system.skin = 0.4
    ct = cell_type.copy_to(s)
    centroid = np.asarray(cell_type.mesh._nodes, dtype=float).mean(axis=0)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=np.full(3, 0.5 * side) - centroid, particle_mass=mass,
                       check_overlaps=False)
    x = cell.particles.pos
    c = x.mean(axis=0)
    edge = float(np.mean(ct.r0)) if len(ct.r0) else 0.1
    noise = np.random.default_rng(3).normal(scale=TRIAL_NOISE * edge, size=x.shape)
    stretch = np.array([TRIAL_STRETCH, TRIAL_STRETCH ** -0.5, TRIAL_STRETCH ** -0.5])
    cell.particles.pos = c + (x - c) * stretch + noise
    if friction > 0:
        s.thermostat.set_langevin(kT=0.0, gamma=friction, seed=1)
    s.cell_drift_tolerance = 1e9  # the trial judges the outcome itself, without warnings
    e0 = cell.get_energies()["total"]
    outcome = "stable"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s.integrator.run(steps)
        e1 = cell.get_energies()["total"]
        if not (np.all(np.isfinite(cell.particles.pos)) and np.isfinite(e1)):
            outcome = "unstable (non-finite)"
        elif e1 > 10.0 * e0:
            outcome = "unstable (energy grew tenfold)"
    except SimulationInstability as err:
        outcome = f"unstable ({err.cause})"
    _TRIALS[key] = outcome
    return outcome


def check_settings(system, warn=False):
    """The report (SettingsReport); with warn, a RuntimeWarning per setting
    outside its limit (on rank 0 only)."""
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
    _cell_settings(system, fluid, gamma, langevin, report)
    if warn:
        from . import rank
        if rank == 0:
            for s in report.warnings():
                warnings.warn(f"check_settings: {s.line()}", SettingsWarning, stacklevel=3)
    return report


class SettingsWarning(RuntimeWarning):
    """A scene setting outside its measured limit (system.check_settings())."""
