"""The settings check's lines for cells (lbmd's system.check_settings()
calls them through lbmd.cell_registry: OifCell.settings_check): each cell
type's mesh, time step and coupling against the measured limits of
doc/accuracy.md, the contacts between the cells' particle types, and the
membrane trial (one cell alone at the scene's time step, node mass and
friction), which oif.pack_cells also uses. The limits and why are listed in
lbmd.settings_check's docstring."""
import warnings

import numpy as np

import lbmd
from lbmd.settings_check import Setting

#: advice and measured limits (doc/accuracy.md)
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


def cell_settings(system, cells, fluid, gamma, langevin, report):
    """Append the cells' lines to report (a lbmd.settings_check.SettingsReport):
    cells are the scene's OifCells, fluid the active LBFluid or None, gamma
    the coupling's and langevin the Langevin thermostat's friction."""
    from . import contacts
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
                if r_nodes > 12 else "", ok=r_nodes >= 2.0, advised=r_nodes >= 4.0))
            ratio = edge / fluid.agrid
            lo, hi = EDGE_PER_AGRID
            report.append(Setting(
                f"{label}: mean edge / agrid", f"{ratio:.3g}", f"advised {lo}..{hi}",
                "fluid passes between the membrane's nodes" if ratio > hi else
                "the membrane and the lattice resolve each other",
                "a coarser mesh would do for the coupling" if ratio < lo else "", ok=ratio <= hi,
                advised=ratio >= lo))
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
    cell_types = sorted({int(t) for c in cells for t in np.unique(c.particles.type)})
    # a fluid the cells do not feel (no thermostat.set_lb): they stay where
    # they are while it flows
    if fluid is not None:
        report.append(Setting(
            "cells coupled to the fluid", f"gamma {gamma:g}" if gamma else "no (thermostat.set_lb not called)",
            "system.thermostat.set_lb(LB_fluid=..., gamma=...)",
            "the cells move with the fluid and push it back" if gamma else
            "the cells feel no drag and stay where they are while the fluid flows past (and through) "
            "them: call system.thermostat.set_lb(LB_fluid=lbf, gamma=cell_type.suggest_LBgamma(...))",
            ok=bool(gamma)))
    _wall_contacts(system, cell_types, report)
    # contacts between the cells' particle types
    if len(cells) > 1:
        for i, a in enumerate(cell_types):
            for b in cell_types[i:]:
                pair = system.non_bonded_inter[a, b]
                if pair.hard_contact.is_active():
                    p = pair.hard_contact.get_params()
                    pair_types = [ct for ct, members in types.values()
                                  if any(int(members[0].particle_type) == t for t in (a, b))]
                    need = contacts.contact_offset(pair_types or [ct for ct, _ in types.values()])
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


def _wall_contacts(system, cell_types, report):
    """Each wall (constraint) against each particle type of the cells: the
    type must not be the wall's own (the wall's contact would act between
    the cell's nodes too, and the cell-cell contact on the wall) and must
    have a contact with it (without one the nodes enter the wall unseen)."""
    from lbmd.interactions import NONBONDED_MODELS
    for i, c in enumerate(system.constraints):
        if not hasattr(c, "shape"):
            continue
        wall_type = int(c.particle_type)
        shape = type(c.shape).__name__
        for t in cell_types:
            label = f"cells of particle type {t} against constraint {i} ({shape}, particle type {wall_type})"
            if t == wall_type:
                report.append(Setting(
                    label, "the same particle type", "a particle type of its own for each wall",
                    "the wall's contact acts between the cells' own nodes too, and the cells' contact "
                    "on the wall: give the constraint another particle_type and set the contact "
                    "between the two (oif.set_contacts(..., wall_types=...))", ok=False))
                continue
            pair = system.non_bonded_inter[t, wall_type]
            active = [name for name, cls in NONBONDED_MODELS.items() if getattr(pair, name).is_active()]
            report.append(Setting(
                label, ", ".join(active) if active else "no contact",
                "a contact between the cells' and the wall's particle types",
                "the wall pushes the cells' nodes back" if active else
                "the cells feel nothing from this wall: their nodes enter it unseen (the run stops "
                "when one is inside), or pass it where it is penetrable; add the advised contact: "
                f"oif.set_contacts(system, cell_types, particle_types=..., wall_types=[{wall_type}])",
                ok=bool(active)))


_TRIALS = {}


def membrane_trial(cell_type, dt, mass, friction, steps=None):
    """'stable' or how one cell of this type, alone in a System of its own,
    failed in `steps` steps at time step dt, node mass and Langevin friction
    (kT 0): released at rest from a TRIAL_STRETCH x stretched shape with
    noise of TRIAL_NOISE of its mean edge. Unstable: a SimulationInstability,
    non-finite positions, or the elastic energy grown tenfold. Remembered
    per (mesh, moduli, dt, mass, friction)."""
    from .oif_classes import OifCell
    System, SimulationInstability = lbmd.System, lbmd.SimulationInstability
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
    cell = OifCell(cell_type=ct, particle_type=0, origin=np.full(3, 0.5 * side) - centroid, particle_mass=mass,
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
