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
- contacts: the advised hard_contact, stiffened with the membranes.
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
    if name in ("narrowest", "cell_radius") and value > 1e-2:
        raise ValueError(f"scene_parameters: parameter '{name}' is {value:g}: SI, in metres, is expected "
                         f"(a {name.replace('_', ' ')} of {value:g} um is {value * 1e-6:g} m)")
    return float(value)


def scene_parameters(narrowest, mean_speed, *, cell_radius=RBC_RADIUS, mesh="rbc374", membrane=None,
                     membrane_viscosity=RBC_MEMBRANE_VISCOSITY, plasma_viscosity=1.5e-3, plasma_density=1000.0,
                     speedup=None, units=None):
    """The plan of a scene (ScenePlan) from SI inputs: `narrowest` the
    narrowest channel dimension (m), `mean_speed` the real mean flow speed
    there (m/s), the cells' radius (m), shipped mesh and membrane moduli
    (a dict of lbmd.units.oif_moduli_from_si's SI keywords; default the
    PyOIF paper's red cell) and membrane viscosity (Pa s m), the plasma's
    dynamic viscosity (Pa s) and density (kg/m^3); `speedup` None (chosen:
    module docstring) or a factor >= 1; `units` a lbmd.units.UnitSystem
    (default: um, us, 1e-15 kg)."""
    units = units or UnitSystem()
    narrowest = _positive("narrowest", narrowest)
    mean_speed = _positive("mean_speed", mean_speed)
    cell_radius = _positive("cell_radius", cell_radius)
    plasma_viscosity = _positive("plasma_viscosity", plasma_viscosity)
    plasma_density = _positive("plasma_density", plasma_density)
    membrane = dict(RBC_MEMBRANE if membrane is None else membrane)
    if speedup is not None and not (isinstance(speedup, (int, float)) and math.isfinite(speedup) and speedup >= 1):
        raise ValueError(f"scene_parameters: parameter 'speedup' must be a number >= 1 (or None: chosen), "
                         f"got {speedup!r}")
    if cell_radius * 2 > narrowest * 1.5:
        raise ValueError(f"scene_parameters: a cell {2e6 * cell_radius:g} um wide does not pass a channel "
                         f"{1e6 * narrowest:g} um wide (it could squeeze through one down to 2/3 of its width)")
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
    # lattice update = time step
    dt = (TAU_STAR - 0.5) * dx ** 2 / (3.0 * nu_si)
    rows.append(("lattice update tau = time step", f"{dt * 1e6:.4g} us",
                 f"relaxation time tau* = 3 nu tau / agrid^2 + 1/2 = {TAU_STAR} (advised 0.55..3: walls "
                 f"midway, stable to Mach 0.6); a time step shorter than tau buys nothing",
                 "time step 0.1 us: shapes within about 1 % of a 4x shorter one"))
    # speed-up and the membranes
    height = narrowest
    reynolds = mean_speed * height / nu_si
    if speedup is None:
        speedup = max(1.0, min(MAX_SPEEDUP, MAX_REYNOLDS / reynolds))
        why = (f"min({MAX_SPEEDUP:g}: the stiffest membranes the samples held at this time step, "
               f"{MAX_REYNOLDS}/Re = {MAX_REYNOLDS / reynolds:.3g}: inertia kept small), at least 1")
    else:
        speedup = float(speedup)
        why = "asked"
    rows.append(("speed-up S (membranes S x stiffer)", f"{speedup:.3g}", why,
                 f"the capillary number, so the cells' deformation, as at the real speed; Re {reynolds:.3g} -> "
                 f"{reynolds * speedup:.3g}"))
    moduli = oif_moduli_from_si(units, **{k: speedup * v for k, v in membrane.items()},
                                membrane_viscosity=membrane_viscosity)
    shear = membrane.get("shear_modulus")
    capillary = plasma_viscosity * mean_speed / shear if shear else float("nan")
    rows.append(("membrane coefficients", ", ".join(f"{k} {v:.4g}" for k, v in moduli.items()),
                 f"the moduli x S (oif_moduli_from_si); the membrane viscosity unscaled (it is relative to the "
                 f"plasma's, which stays)", f"Ca = eta U / mu0 = {capillary:.3g} at either speed"))
    # the mesh and its friction
    nodes_file, triangles_file = _mesh_files(mesh)
    data = mesh_io.read_mesh(nodes_file, triangles_file)
    size = _tidy(units.to_lattice(cell_radius, "m"))
    nodes = np.asarray(data.nodes, dtype=float) * size  # the shipped meshes have radius 1: resize = radius
    resize = (size, size, size)
    surface = float(geo.surface(nodes, np.asarray(data.triangles)))
    visc, dens = _tidy(units.to_lattice(nu_si, "m^2/s")), _tidy(units.to_lattice(plasma_density, "kg/m^3"))
    from .oif_classes import lb_gamma
    gamma = float(lb_gamma(len(nodes), surface, visc, dens))
    # the shape error against the finest mesh, from the table check_settings holds (doc/accuracy.md)
    from .settings_check import MESH_ERROR
    error = float(np.interp(len(nodes), [p[0] for p in MESH_ERROR], [p[1] for p in MESH_ERROR]))
    rows.append(("mesh", f"{mesh}", f"{len(nodes)} nodes, resize {size:.4g}",
                 f"cell shapes within about {100 * error:.1f} % of the finest mesh"))
    rows.append(("coupling gamma", f"{gamma:.4g}", "PyOIF's calibrated friction for this mesh density "
                 "(suggest_LBgamma)", "the drag of the calibration's sphere; keep gamma N when changing the mesh"))
    time_step = _tidy(units.to_lattice(dt, "s"))
    node_mass = gamma * time_step / GAMMA_DT_PER_MASS
    rows.append(("node mass", f"{node_mass:.4g}", f"gamma dt / m = {GAMMA_DT_PER_MASS}: the friction relaxes a "
                 "node's velocity within a few steps", "heavier nodes folded membranes at the flagship's island"))
    rows.append(("contacts", f"scale {speedup:.3g}", "oif.set_contacts(..., scale=S): the advised hard_contact "
                 "stiffened with the membranes", "cannot be crossed; a push too hard for the time step stops "
                 "the run with contact_overrun"))
    speed = units.to_lattice(mean_speed * speedup, "m/s")
    mach = speed * 2.0 * time_step / units.to_lattice(dx, "m") * math.sqrt(3.0)  # the peak about twice the mean
    rows.append(("mean speed in the scene", f"{speed:.4g}", f"{mean_speed * 1e3:g} mm/s x S",
                 f"Mach about {mach:.3g} at the peak (advised <= 0.1)"))
    return ScenePlan(units=units, agrid=_tidy(units.to_lattice(dx, "m")), tau=time_step, time_step=time_step,
                     dens=dens, visc=visc, speed=speed, speedup=speedup, moduli=moduli, mesh=mesh, resize=resize,
                     gamma=gamma, node_mass=node_mass, contact_scale=speedup, reynolds=reynolds * speedup,
                     capillary=capillary, mach=mach, rows=rows)


def _tidy(value):
    """value to 12 significant digits: 0.1 for 0.09999999999999998 (a time
    step the fluid's tau is an exact multiple of)."""
    return float(f"{value:.12g}")


def _mesh_files(mesh):
    from . import mesh_files
    return mesh_files(mesh)
