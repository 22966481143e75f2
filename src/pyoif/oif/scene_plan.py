"""The numbers of a scene from the SI values a researcher has
(``oif.scene_parameters``): lattice spacing, lattice update and time step,
the fluid in the engine's units, the cells' moduli, coupling friction, node
mass and contact strength, and the speed-up with the membranes stiffened to
match, each with the reason and the error to expect from the measured charts
of doc/accuracy.md.

    plan = oif.scene_parameters(narrowest=12e-6, mean_speed=1.3e-3)
    print(plan)                                   # the table: value, reason, expected error
    system = lbmd.System(box_l=plan.box([90e-6, 30e-6, 14e-6]))
    system.time_step = plan.time_step
    lbf = lbmd.lb.LBFluid(**plan.fluid)
    rbc = oif.OifCellType(*oif.mesh_files(plan.mesh), system=system, resize=plan.resize,
                          normal=True, **plan.moduli)
    system.thermostat.set_lb(LB_fluid=lbf, gamma=plan.gamma)
    oif.set_contacts(system, rbc, particle_types=0, wall_types=10, scale=plan.contact_scale)
    # cells: oif.OifCell(..., particle_mass=plan.node_mass); inlet: plan.speed

The rules (doc/concepts.md, "Choosing the numbers", with the measurements
behind each):

- lattice spacing: the largest of 2, 1, 0.5, 0.25, 0.125 um that puts 3.9
  nodes on the cell's radius and 5 across the narrowest channel (a red
  cell of radius 3.91 um: 1 um; Stokes drag within about 2 %);
- lattice update: the relaxation time tau* = 3 nu dt / dx^2 + 1/2 = 0.95,
  in the advised 0.55..3 and where the walls sit midway (MRT); the MD time
  step equals it (a shorter one buys nothing, doc/accuracy.md);
- speed-up: real flows in microchannels are slow (1 mm/s crosses a 100 um
  device in 0.1 s: a million time steps); the flow is run S times faster
  with the membranes S times stiffer, which keeps the capillary number
  Ca = eta U / mu0, so the cells deform as they would. S is at most 27 (the
  stiffest the samples held at this time step: 40x and 60x broke) and
  keeps the Reynolds number U H / nu at most 0.5 (inertia still small);
  ``speedup=1`` runs in real time;
- coupling: PyOIF's calibrated friction for the mesh (suggest_LBgamma), the
  node mass from gamma dt / m = 0.3 (the friction relaxes a node's velocity
  within a few steps; heavier nodes folded at the flagship's island);
- contacts: the advised hard_contact, stiffened with the membranes;
- stability: one cell of the plan, alone, is run at the time step and at
  1.5x it (check_settings' membrane trial); where it fails the speed-up is
  lowered, and at S = 1 the time step is halved.

The accuracy wanted (``accuracy``, a fraction: 0.05, 0.02, 0.01, ...) picks
the coarsest mesh of the cell's family whose measured shape error is within
it (rbc162 for 5 %, rbc642 for 2 %, rbc2562 below 1.3 %) and a lattice update
short enough for the time-step error (0.56 % at 0.1 us, about as tau^1.4);
the lattice spacing stays (the cells are not staircase walls; their drag
comes from the coupling). With ``duration`` (s of real flow), ``box`` (m)
and ``cells`` the plan estimates the run time on one core (and on
``cores``) from the measured costs of doc/performance.md; a ``time_budget``
(s) picks the finest accuracy of ACCURACY_LEVELS that fits it, and names
what to change when none does.
"""
import math

import numpy as np

from lbmd.units import UnitSystem, oif_moduli_from_si

from . import geometry as geo
from . import mesh_io

#: the PyOIF paper's red blood cell membrane (SI; doc/model.md)
RBC_MEMBRANE = dict(shear_modulus=2.1651e-6, bending_modulus=1.7321e-17, local_area_modulus=3.5e-6,
                    global_area_modulus=3.5e-4, volume_modulus=900.0)
#: membrane viscosity of the samples (Pa s m: kvisc 1.0 in the paper's units)
RBC_MEMBRANE_VISCOSITY = 4.33e-10
RBC_RADIUS = 3.91e-6
#: lattice spacings tried, largest first (m)
SPACINGS = (2e-6, 1e-6, 0.5e-6, 0.25e-6, 0.125e-6)
NODES_PER_RADIUS, NODES_ACROSS = 3.9, 5
TAU_STAR = 0.95
#: the stiffest membranes (times the given moduli) the samples held at a
#: time step of 0.1 us, and the largest Reynolds number a speed-up may reach
MAX_SPEEDUP, MAX_REYNOLDS = 27.0, 0.5
#: gamma dt / m: the node mass that gives it
GAMMA_DT_PER_MASS = 0.3
#: the time-step error of cells in flow at a lattice update of 0.1 us (the
#: stiffest membranes measured, ks 0.5) and its growth with tau
#: (doc/accuracy.md, "Time step and lattice interval")
TIME_ERROR_AT_0_1_US, TIME_ERROR_EXPONENT = 0.0056, 1.4
#: the smallest relaxation time a halved lattice update may reach
TAU_STAR_MIN = 0.55
#: accuracies a time budget chooses between, finest first
ACCURACY_LEVELS = (0.01, 0.02, 0.05)
#: measured costs on one quiet core (doc/performance.md, the flagship's
#: benchmark bifurcation_cost.py): a lattice node update of a walled scene
#: (1.36 s per 1000 steps for its 140 800 nodes: 9.7 ns) and a cell per mesh
#: node per step (36 us per rbc374 with its coupling, 40 RBCs); 0.9 of linear
#: speed per added rank (1.9x on 2; the paper's scene measured 1.8-2.0x on
#: a quiet host). A busy or older machine takes 2-3x longer.
SECONDS_PER_NODE_UPDATE, SECONDS_PER_CELL_NODE_STEP, RANK_EFFICIENCY = 10e-9, 40e-6 / 374, 0.9


class ScenePlan:
    """The chosen numbers (attributes) and, per choice, the reason and the
    error to expect (``rows``: (name, value, reason, expected)); str() is
    the table."""

    def __init__(self, **values):
        self.__dict__.update(values)

    @property
    def fluid(self):
        """Keyword arguments of lbmd.lb.LBFluid."""
        return dict(agrid=self.agrid, dens=self.dens, visc=self.visc, tau=self.tau)

    def length(self, metres):
        """A length in metres in the engine's units."""
        return self.units.to_lattice(float(metres), "m")

    def box(self, lengths):
        """box_l in the engine's units for box lengths in metres, each
        rounded up to a whole number of lattice spacings."""
        return [math.ceil(self.length(v) / self.agrid - 1e-9) * self.agrid for v in lengths]

    def slit_force(self, height):
        """The body force density (engine units) that drives the plan's mean
        speed between two plane walls `height` metres apart: plane Poiseuille
        flow, U = f H^2 / (12 rho nu). Walls across the flow slow it (a duct
        of square section reaches about 0.42 of it; measure and scale, as
        the flagship's drive_flow does, where the speed matters)."""
        h = self.length(_positive("height", height))
        return 12.0 * self.dens * self.visc * self.speed / h ** 2

    def __str__(self):
        width = max(len(r[0]) for r in self.rows)
        lines = [f"{'setting':<{width}}  value           reason; expected error"]
        for name, value, reason, expected in self.rows:
            lines.append(f"{name:<{width}}  {value:<15} {reason}; {expected}")
        return "\n".join(lines)

    __repr__ = __str__


def _positive(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"scene_parameters: parameter '{name}' must be a number, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"scene_parameters: parameter '{name}' must be positive and finite, got {value!r}")
    if (name in ("narrowest", "cell_radius", "height") or name.startswith("box[")) and value > 1e-2:
        raise ValueError(f"scene_parameters: parameter '{name}' is {value:g}: SI, in metres, is expected "
                         f"(a length of {value:g} um is {value * 1e-6:g} m)")
    return float(value)


def scene_parameters(narrowest, mean_speed, *, cell_radius=RBC_RADIUS, mesh=None, membrane=None,
                     membrane_viscosity=RBC_MEMBRANE_VISCOSITY, plasma_viscosity=1.5e-3, plasma_density=1000.0,
                     speedup=None, accuracy=None, duration=None, box=None, cells=0, time_budget=None, cores=1,
                     units=None):
    """The plan of a scene (ScenePlan) from SI inputs: `narrowest` the
    narrowest channel dimension (m), `mean_speed` the real mean flow speed
    there (m/s), the cells' radius (m), shipped mesh (default rbc374, or the
    one `accuracy` picks) and membrane moduli (a dict of
    lbmd.units.oif_moduli_from_si's SI keywords; default the PyOIF paper's
    red cell) and membrane viscosity (Pa s m), the plasma's dynamic
    viscosity (Pa s) and density (kg/m^3); `speedup` None (chosen: module
    docstring) or a factor >= 1; `accuracy` the error wanted on the cells'
    shapes (a fraction, e.g. 0.02); `duration` the real flow time to run
    (s), `box` the box lengths (m) and `cells` the number of cells, for the
    estimated run time on `cores` cores; `time_budget` (s) the longest run
    wanted: the finest of ACCURACY_LEVELS that fits (or the `accuracy`
    given, checked); `units` a lbmd.units.UnitSystem (default: um, us,
    1e-15 kg)."""
    if time_budget is not None:
        time_budget = _positive("time_budget", time_budget)
        if duration is None or box is None:
            raise ValueError("scene_parameters: a 'time_budget' needs the 'duration' of real flow (s) and the "
                             "'box' lengths (m) to estimate the run time")
        asked = dict(narrowest=narrowest, mean_speed=mean_speed, cell_radius=cell_radius, mesh=mesh,
                     membrane=membrane, membrane_viscosity=membrane_viscosity, plasma_viscosity=plasma_viscosity,
                     plasma_density=plasma_density, speedup=speedup, duration=duration, box=box, cells=cells,
                     cores=cores, units=units)
        tried = []
        for level in ((accuracy,) if accuracy is not None else ACCURACY_LEVELS):
            try:
                plan = scene_parameters(accuracy=level, **asked)
            except ValueError as e:  # e.g. the finest mesh fails the membrane trial: the next level
                if accuracy is not None:
                    raise
                tried.append(f"accuracy {level:g}: {e}")
                continue
            if not plan.accuracy_met:
                tried.append(f"accuracy {level:g}: not reached ({plan.accuracy_shortfall})")
                if accuracy is None:
                    continue
            tried.append(f"accuracy {level:g}: about {_hours(plan.estimated_seconds)}")
            if plan.estimated_seconds <= time_budget:
                plan.rows.append(("time budget", _hours(time_budget), f"the finest accuracy that fits of "
                                  f"{', '.join(f'{a:g}' for a in ACCURACY_LEVELS)}" if accuracy is None else
                                  "the plan for the accuracy asked fits" + (
                                      "" if plan.accuracy_met else f" (the accuracy NOT met: "
                                      f"{plan.accuracy_shortfall})"), "; ".join(tried)))
                plan.time_budget = time_budget
                return plan
        raise ValueError(f"scene_parameters: no plan fits the time_budget of {_hours(time_budget)} on {cores} "
                         f"core(s) ({'; '.join(tried)}): ask a coarser accuracy, a shorter duration "
                         f"({duration:g} s), a smaller box, fewer cells, or more cores")
    units = units or UnitSystem()
    narrowest = _positive("narrowest", narrowest)
    mean_speed = _positive("mean_speed", mean_speed)
    cell_radius = _positive("cell_radius", cell_radius)
    plasma_viscosity = _positive("plasma_viscosity", plasma_viscosity)
    plasma_density = _positive("plasma_density", plasma_density)
    if accuracy is not None:
        accuracy = _positive("accuracy", accuracy)
        if accuracy >= 1:
            raise ValueError(f"scene_parameters: parameter 'accuracy' is the error wanted as a fraction (0.02 "
                             f"for 2 %), got {accuracy:g}")
    membrane = dict(RBC_MEMBRANE if membrane is None else membrane)
    if speedup is not None and not (isinstance(speedup, (int, float)) and math.isfinite(speedup) and speedup > 0):
        raise ValueError(f"scene_parameters: parameter 'speedup' must be a positive number (or None: chosen; "
                         f"below 1 runs slower than real time with softer membranes), got {speedup!r}")
    if cell_radius * 2 > narrowest * 1.5:
        raise ValueError(f"scene_parameters: a cell {2e6 * cell_radius:g} um wide does not pass a channel "
                         f"{1e6 * narrowest:g} um wide (it could squeeze through one down to 2/3 of its width)")
    if box is not None:
        box = [_positive(f"box[{i}]", v) for i, v in enumerate(_lengths3(box))]
    if duration is not None:
        duration = _positive("duration", duration)
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)) or cells < 0:
        raise ValueError(f"scene_parameters: parameter 'cells' must be a whole number >= 0, got {cells!r}")
    if isinstance(cores, bool) or not isinstance(cores, (int, np.integer)) or cores < 1:
        raise ValueError(f"scene_parameters: parameter 'cores' must be a whole number >= 1, got {cores!r}")
    rows = []
    nu_si = plasma_viscosity / plasma_density  # m^2/s
    # lattice spacing
    for dx in SPACINGS:
        if cell_radius / dx >= NODES_PER_RADIUS - 1e-9 and narrowest / dx >= NODES_ACROSS - 1e-9:
            break
    rows.append(("lattice spacing agrid", f"{dx * 1e6:g} um",
                 f"the largest of {', '.join(f'{s * 1e6:g}' for s in SPACINGS)} um with {NODES_PER_RADIUS} "
                 f"nodes on the cell's radius ({cell_radius / dx:.3g}) and {NODES_ACROSS} across the narrowest "
                 f"channel ({narrowest / dx:.3g})",
                 "Stokes drag of the cell within about 2 % (+2.1 % at 3 nodes, -1 to -1.7 % from 6); "
                 "Poiseuille flow within 0.2 % from 5 nodes across"))
    # lattice update = time step: tau* = TAU_STAR, halved for the accuracy asked
    dt = (TAU_STAR - 0.5) * dx ** 2 / (3.0 * nu_si)
    why_dt = (f"relaxation time tau* = 3 nu tau / agrid^2 + 1/2 = {TAU_STAR} (advised 0.55..3: walls midway, "
              f"stable to Mach 0.6); a time step shorter than tau buys nothing")
    if accuracy is not None:
        while _time_error(dt) > accuracy and _tau_star(0.5 * dt, dx, nu_si) >= TAU_STAR_MIN:
            dt *= 0.5
            why_dt = (f"halved for the accuracy asked ({accuracy:g}); tau* {_tau_star(dt, dx, nu_si):.3g} (at "
                      f"least {TAU_STAR_MIN})")
    # the mesh: asked, or the coarsest of the family within the accuracy
    if mesh is None:
        mesh, why_mesh = "rbc374", "the default (the paper's): flow extents within 0.4-1.6 %"
        if accuracy is not None:
            mesh, why_mesh = _mesh_for(accuracy, "rbc")
    else:
        why_mesh = "asked"
        if not isinstance(mesh, str):
            raise TypeError(f"scene_parameters: parameter 'mesh' must be a shipped mesh's name, got {mesh!r}")
    nodes_file, triangles_file = _mesh_files(mesh)
    data = mesh_io.read_mesh(nodes_file, triangles_file)
    size = _tidy(units.to_lattice(cell_radius, "m"))
    resize = (size, size, size)
    nodes = np.asarray(data.nodes, dtype=float) * size  # the shipped meshes have radius 1: resize = radius
    surface = float(geo.surface(nodes, np.asarray(data.triangles)))
    visc, dens = _tidy(units.to_lattice(nu_si, "m^2/s")), _tidy(units.to_lattice(plasma_density, "kg/m^3"))
    from .oif_classes import lb_gamma
    gamma = float(lb_gamma(len(nodes), surface, visc, dens))
    # speed-up: the largest the limits allow, lowered (then the time step
    # halved) until one cell of the plan passes the membrane trial
    reynolds = mean_speed * narrowest / nu_si
    asked_speedup = speedup
    if speedup is None:
        speedup = max(1.0, min(MAX_SPEEDUP, MAX_REYNOLDS / reynolds))
        why = (f"min({MAX_SPEEDUP:g}: the stiffest membranes the samples held at this time step, "
               f"{MAX_REYNOLDS}/Re = {MAX_REYNOLDS / reynolds:.3g}: inertia kept small), at least 1")
    else:
        speedup = float(speedup)
        why = "asked"
    while True:
        moduli = oif_moduli_from_si(units, **{k: speedup * v for k, v in membrane.items()},
                                    membrane_viscosity=membrane_viscosity)
        time_step = _tidy(units.to_lattice(dt, "s"))
        node_mass = gamma * time_step / GAMMA_DT_PER_MASS
        trial = _membrane_trial(nodes_file, triangles_file, resize, moduli, time_step, node_mass, gamma)
        if trial == "stable":
            break
        if asked_speedup is None and speedup > 1.0:  # (an asked one is kept: the time step gives way)
            speedup = max(1.0, speedup / 1.5)
            why = (f"lowered until one cell passes the membrane trial at this time step and 1.5x it "
                   f"(at the higher speed-up: {trial})")
        elif _tau_star(0.5 * dt, dx, nu_si) >= TAU_STAR_MIN:
            dt *= 0.5
            why_dt = (f"halved until one cell at these moduli passes the membrane trial ({trial}); tau* "
                      f"{_tau_star(dt, dx, nu_si):.3g}")
        else:
            raise ValueError(f"scene_parameters: one {mesh} cell at these moduli (x{speedup:g}) fails the "
                             f"membrane trial even at the shortest lattice update ({trial}): ask a coarser mesh "
                             f"or softer membranes")
    rows.append(("lattice update tau = time step", f"{dt * 1e6:.4g} us", why_dt,
                 f"cells' time-step error about {100 * _time_error(dt):.2g} % (0.56 % at 0.1 us, as tau^1.4)"))
    rows.append(("speed-up S (membranes S x stiffer)", f"{speedup:.3g}", why,
                 f"the capillary number, so the cells' deformation, as at the real speed; Re {reynolds:.3g} -> "
                 f"{reynolds * speedup:.3g}"))
    shear = membrane.get("shear_modulus")
    capillary = plasma_viscosity * mean_speed / shear if shear else float("nan")
    rows.append(("membrane coefficients", ", ".join(f"{k} {v:.4g}" for k, v in moduli.items()),
                 "the moduli x S (oif_moduli_from_si); the membrane viscosity unscaled (it is relative to the "
                 "plasma's, which stays)", f"Ca = eta U / mu0 = {capillary:.3g} at either speed"))
    error = _mesh_error(len(nodes))
    rows.append(("mesh", f"{mesh}", f"{len(nodes)} nodes, resize {size:.4g}; {why_mesh}",
                 f"cell shapes within about {100 * error:.1f} % of the finest mesh"))
    rows.append(("coupling gamma", f"{gamma:.4g}", "PyOIF's calibrated friction for this mesh density "
                 "(suggest_LBgamma)", "the drag of the calibration's sphere; keep gamma N when changing the mesh"))
    rows.append(("node mass", f"{node_mass:.4g}", f"gamma dt / m = {GAMMA_DT_PER_MASS}: the friction relaxes a "
                 "node's velocity within a few steps", "heavier nodes folded membranes at the flagship's island"))
    rows.append(("contacts", f"scale {speedup:.3g}", "oif.set_contacts(..., scale=S): the advised hard_contact "
                 "stiffened with the membranes", "cannot be crossed; a push too hard for the time step stops "
                 "the run with contact_overrun"))
    speed = units.to_lattice(mean_speed * speedup, "m/s")
    mach = speed * 2.0 * time_step / units.to_lattice(dx, "m") * math.sqrt(3.0)  # the peak about twice the mean
    rows.append(("mean speed in the scene", f"{speed:.4g}", f"{mean_speed * 1e3:.3g} mm/s x S",
                 f"Mach about {mach:.3g} at the peak (advised <= 0.1)"))
    shortfall = []
    if accuracy is not None:
        if error > accuracy:
            shortfall.append(f"the mesh's shape error {100 * error:.2g} % (a finer mesh)")
        if _time_error(dt) > accuracy:
            shortfall.append(f"the time-step error {100 * _time_error(dt):.2g} % (tau* at its floor "
                             f"{TAU_STAR_MIN}: a finer lattice)")
        rows.append(("accuracy asked", f"{100 * accuracy:g} %",
                     "met by the mesh and the lattice update above" if not shortfall else
                     "NOT met: " + "; ".join(shortfall),
                     f"shapes {100 * error:.1f} %, time step {100 * _time_error(dt):.2g} %; the fluid's drag "
                     f"about 2 % at this spacing"))
    steps = estimated = None
    if duration is not None:
        steps = int(math.ceil(duration / speedup / dt - 1e-9))
        rows.append(("steps", f"{steps}", f"{duration * 1e3:g} ms of real flow / S / time step",
                     f"{duration / speedup * 1e3:.4g} ms in the scene"))
        if box is not None:
            node_count = float(np.prod([math.ceil(v / dx - 1e-9) for v in box]))
            one_core = steps * (node_count * SECONDS_PER_NODE_UPDATE + cells * len(nodes) * SECONDS_PER_CELL_NODE_STEP)
            estimated = one_core / (1.0 + RANK_EFFICIENCY * (cores - 1))
            rows.append(("estimated run time", _hours(estimated), f"{node_count:.3g} lattice nodes and {cells} "
                         f"cells of {len(nodes)} nodes, {steps} steps on {cores} core(s), at the costs measured in "
                         "doc/performance.md (a quiet core)", "a busy or older machine takes 2-3x longer"))
    return ScenePlan(units=units, agrid=_tidy(units.to_lattice(dx, "m")), tau=time_step, time_step=time_step,
                     dens=dens, visc=visc, speed=speed, speedup=speedup, moduli=moduli, mesh=mesh, resize=resize,
                     gamma=gamma, node_mass=node_mass, contact_scale=speedup, reynolds=reynolds * speedup,
                     capillary=capillary, mach=mach, accuracy=accuracy, shape_error=error,
                     time_error=_time_error(dt), steps=steps, estimated_seconds=estimated, time_budget=None,
                     accuracy_met=not shortfall, accuracy_shortfall="; ".join(shortfall), rows=rows)


def _time_error(dt):
    """The cells' time-step error at a lattice update dt (s)."""
    return TIME_ERROR_AT_0_1_US * (dt / 1e-7) ** TIME_ERROR_EXPONENT


def _tau_star(dt, dx, nu):
    return 3.0 * nu * dt / dx ** 2 + 0.5


def _mesh_error(node_count):
    from .settings_check import MESH_ERROR  # the table check_settings holds (doc/accuracy.md)
    return float(np.interp(node_count, [p[0] for p in MESH_ERROR], [p[1] for p in MESH_ERROR]))


def _mesh_for(accuracy, family):
    """The coarsest shipped mesh of the family within the accuracy (or the finest)."""
    from . import available_meshes
    sizes = sorted(int(name[len(family):]) for name in available_meshes()
                   if name.startswith(family) and name[len(family):].isdigit())
    for n in sizes:
        if _mesh_error(n) <= accuracy:
            return f"{family}{n}", f"the coarsest mesh whose shape error is within the accuracy asked ({accuracy:g})"
    return f"{family}{sizes[-1]}", f"the finest mesh (none is measured within {accuracy:g})"


def _membrane_trial(nodes_file, triangles_file, resize, moduli, time_step, node_mass, gamma):
    """check_settings' trial of one cell alone at the time step and at
    TRIAL_MARGIN x it: 'stable' or how it failed."""
    import lbmd
    from .oif_classes import OifCellType
    from .settings_check import TRIAL_MARGIN, membrane_trial
    scratch = lbmd.System(box_l=[100.0] * 3)
    cell_type = OifCellType(nodes_file, triangles_file, system=scratch, resize=resize, normal=True, **moduli)
    outcome = membrane_trial(cell_type, time_step, node_mass, gamma)
    if outcome == "stable":
        outcome = membrane_trial(cell_type, TRIAL_MARGIN * time_step, node_mass, gamma)
        if outcome != "stable":
            outcome = f"at {TRIAL_MARGIN:g}x the time step: {outcome}"
    return outcome


def _lengths3(box):
    try:
        values = [v for v in box]
    except TypeError:
        raise TypeError(f"scene_parameters: parameter 'box' must be three lengths in metres, got {box!r}") from None
    if len(values) != 3:
        raise ValueError(f"scene_parameters: parameter 'box' must be three lengths in metres, got {box!r}")
    return values


def _hours(seconds):
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _tidy(value):
    """value to 12 significant digits: 0.1 for 0.09999999999999998 (a time
    step the fluid's tau is an exact multiple of)."""
    return float(f"{value:.12g}")


def _mesh_files(mesh):
    from . import mesh_files
    return mesh_files(mesh)
