#!/usr/bin/env pyoif
"""Validation: the Fahraeus and the Fahraeus-Lindqvist effects of a red
blood cell suspension in a straight tube, against the in-vitro fits of
Pries et al.

    pyoif samples/validation/fahraeus_lindqvist.py [--diameters 10] [--hd 0.25] [--ht H_T]
        [--ca 10] [--strain 150] [--transient 50] [--length-ratio 4] [--gamma-factor 1]
        [--node-mass-ratio 0.3] [--kvisc 1] [--seed 1] [--packing legacy|pack]
        [--contacts legacy|hard] [--output DIR]
    pyoif samples/validation/fahraeus_lindqvist.py --combine DIR [DIR ...] --output DIR

References (D the tube diameter in um, H_D the discharge haematocrit):

- A. R. Pries, D. Neuhaus, P. Gaehtgens, "Blood viscosity in tube flow:
  dependence on diameter and hematocrit", Am. J. Physiol. 263 (Heart Circ.
  Physiol. 32), H1770-H1778 (1992), the in-vitro fit of the relative
  apparent viscosity (high shear rates):
      eta_rel = 1 + (eta_45 - 1) ((1 - H_D)^C - 1) / ((1 - 0.45)^C - 1),
      eta_45 = 220 exp(-1.3 D) + 3.2 - 2.44 exp(-0.06 D^0.645),
      C = (0.8 + exp(-0.075 D)) (-1 + 1/(1 + 1e-11 D^12)) + 1/(1 + 1e-11 D^12).
- A. R. Pries, T. W. Secomb, P. Gaehtgens, J. F. Gross, "Blood flow in
  microvascular networks: experiments and simulation", Circ. Res. 67,
  826-834 (1990), the tube haematocrit (Fahraeus effect):
      H_T / H_D = H_D + (1 - H_D) (1 + 1.7 exp(-0.415 D) - 0.6 exp(-0.011 D)).

Model (lattice units: 1 um, 1 us, 1e-15 kg; agrid 1, time step = tau 0.1):
plasma of density 1 and kinematic viscosity 1.5 (1.5 mPa s) in a straight
tube of diameter D along x, periodic in x (length about --length-ratio D),
the lumen a hollow open `shapes.Cylinder` that is both the LB boundary
(halfway bounce-back: a staircase of lattice nodes, D nodes across) and a
constraint on the membrane nodes (soft-sphere repulsion within 1 um of the
wall). Red blood cells: the project's rbc374 Evans-Fung mesh of radius
3.91 um with the PyOIF paper's moduli ks 0.005, kb 0.02, kal 0.007,
kag 0.7, kv 0.9 (Jancigova et al., PLoS Comput. Biol. 16, e1008249, 2020),
membrane_collision between cells (strength a = 0.01, cutoff 1 um; both contact
strengths raised as Ca / 2 above Ca 2: they must hold against the viscous
force, which grows with the shear rate), coupling friction gamma = suggest_LBgamma; the fluid inside a
cell is plasma (viscosity ratio 1, real cells about 5). As in the flagship
(samples/cell_flow_in_bifurcation.py): the nodes' mass m set by
gamma dt / m = 0.3 (--node-mass-ratio; m 0.51, the former mass 1 is 0.152)
and a membrane viscosity kvisc 1 (--kvisc; 0 before). With mass 1 and no
membrane viscosity, one cell folded like a taco and its membrane passed
through itself at strain 10-14 at Ca 5 and 10 (the run stopped with
SimulationInstability); with the lighter nodes and kvisc 1, Ca 5 and 10
ran 60 and 150 strain units.

Haematocrit. The number of cells is set from the tube volume: the tube
haematocrit seeded is H_T = n V_cell / (pi D^2/4 L). By default n follows
from the target discharge haematocrit --hd through the Pries 1990 ratio
(only to choose n; H_D itself is measured), and L is adjusted to a whole
number of lattice nodes so that n V_cell / (pi D^2/4 L) is as close as
possible to that H_T; --ht gives H_T directly. Tubes narrower than 12 um:
cells seeded at random (oif.seed_cells, non-overlapping, clear of the wall,
random orientations). Wider tubes (more cells): random placement jams
(D 15, 18 cells: at most 16 placed in 20000 tries), so the cells are packed
greedily on a grid (discs facing along x, y or z) and n of the packed
places drawn at random (packed_placements); the flow mixes them.
--packing pack places them with oif.pack_cells instead (force-biased
packing: it reaches the tube haematocrits of H_D 0.3-0.45, 0.32 at D 10,
where the greedy grid stops near 0.21), and --contacts hard uses the
advised hard_contact (oif.set_contacts) between the cells and with the
wall instead of membrane_collision and soft-sphere; both are what
robustness_map.py runs. The validated table in doc/validation.md is the
legacy default.

Flow. A uniform body force density f drives the fluid (a pressure gradient:
it acts on the plasma and on the fluid inside the cells alike). f is set by
the capillary number of the cell-free flow, Ca = eta gamma_w r / Gs, with
gamma_w = f D / (4 eta) the wall shear rate of Poiseuille flow, r 3.91 um
and Gs = sqrt(3) ks / 4 the membrane's shear modulus (doc/model.md). The
Pries fits are the viscosity at high shear, where it no longer depends on
the shear rate (cells deformed and aligned). The default Ca = 10 (wall
shear rate 3700 1/s, mean velocity over diameter about 410 1/s at D 10: well
above the 50 1/s usually taken as high shear). At D 10, H_T/H_D still falls
with Ca (Ca 2, 5, 10: +20 %, +18 %, +11 to +13 % above the Pries fit) while
eta_rel stays within 4 %: no plateau of the Fahraeus effect was reached
(doc/validation.md).

Measurements (per tube, the same body force):
- Q_plasma: the flow rate of a cell-free run in the same lattice tube (it
  cancels the staircase wall), checked against Poiseuille's
  pi f D^4 / (128 eta);
- Q(t) = sum over the lattice nodes of u_x agrid^3 / L (plasma and the
  fluid inside the cells), eta_rel = Q_plasma / Q;
- the discharge haematocrit H_D = (sum_cells V_cell u_cell,x / L) / Q: the
  flux of cell volume through a cross-section over the total flux, u_cell
  from the cells' displacement;
- H_T / H_D with the seeded H_T.
A time series of both (and of the cells' mean distance from the axis and
their volume) is sampled every half strain unit (gamma_w t); the averages
are taken over the strain after --transient (the time series,
doc/validation.md, shows when the suspension is steady), with the spread of
4 blocks of the window as the statistical error. A run that stops with
SimulationInstability (a membrane folded through itself: D 15 and 20 at
Ca 10 after strain 105-110) is summarised up to there when the window
holds at least 8 samples, and says so in the column `stopped`.

Writes <output>/fahraeus_lindqvist.csv (one row per run: D, L, n, H_T,
H_D, eta_rel and H_T/H_D with the Pries values and relative errors, their
block errors, Q_plasma against Poiseuille, Ca, shear rates, Reynolds
number, the cells' worst volume deviation, steps, CPU s),
fahraeus_lindqvist_timeseries.csv and fahraeus_lindqvist.png (eta_rel and
H_T/H_D against D with the Pries curves; the time series).
"""
import argparse
import csv
import math
import os
import time

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

AGRID, TIME_STEP, DENS, VISC = 1.0, 0.1, 1.0, 1.5  # plasma: 1.5 mPa s at density 1000 kg/m^3
ETA = DENS * VISC
RBC_RADIUS = 3.91
RBC_MODULI = dict(ks=0.005, kb=0.02, kal=0.007, kag=0.7, kv=0.9)  # PyOIF paper's RBC
GS = math.sqrt(3.0) / 4.0 * RBC_MODULI["ks"]  # membrane shear modulus (doc/model.md, Units and SI)
CELL_TYPE, WALL_TYPE = 0, 10
SAMPLE_STRAIN = 0.5  # strain units between samples of the time series
BLOCKS = 4  # blocks of the averaging window for the statistical error
NODE_MASS_RATIO = 0.3  # gamma dt / m of the membrane nodes (None: mass 1, i.e. 0.152)
KVISC = 1.0  # membrane viscosity (the edges' dashpots), as the flagship's
CONTACT_A = 0.01  # membrane_collision strength between cells up to Ca 2 (a Ca / 2 above)
WALL_A = 1e-4  # soft-sphere strength of the wall on the nodes up to Ca 2 (a Ca / 2 above)


def pries_viscosity(d_um, hd):
    """Relative apparent viscosity of blood in a tube of diameter d_um (um)
    at discharge haematocrit hd: Pries, Neuhaus & Gaehtgens, Am. J.
    Physiol. 263, H1770 (1992), in-vitro fit (their eqs. for eta_45 and C)."""
    d = np.asarray(d_um, dtype=float)
    eta45 = 220.0 * np.exp(-1.3 * d) + 3.2 - 2.44 * np.exp(-0.06 * d ** 0.645)
    s = 1.0 / (1.0 + 1e-11 * d ** 12)
    c = (0.8 + np.exp(-0.075 * d)) * (-1.0 + s) + s
    return 1.0 + (eta45 - 1.0) * ((1.0 - np.asarray(hd)) ** c - 1.0) / ((1.0 - 0.45) ** c - 1.0)


def pries_ht_over_hd(d_um, hd):
    """Tube over discharge haematocrit (Fahraeus effect): Pries, Secomb,
    Gaehtgens & Gross, Circ. Res. 67, 826 (1990)."""
    d = np.asarray(d_um, dtype=float)
    hd = np.asarray(hd, dtype=float)
    return hd + (1.0 - hd) * (1.0 + 1.7 * np.exp(-0.415 * d) - 0.6 * np.exp(-0.011 * d))


def force_density(diameter, ca):
    """Body force density f of the capillary number Ca = eta gamma_w r / Gs,
    gamma_w = f D / (4 eta) the Poiseuille wall shear rate; (f, gamma_w)."""
    gamma_w = ca * GS / (ETA * RBC_RADIUS)
    return 4.0 * ETA * gamma_w / diameter, gamma_w


def tube_layout(diameter, length_ratio, ht, cell_volume):
    """(n cells, tube length L in whole agrid, H_T seeded) closest to the
    tube haematocrit ht at a length near length_ratio * D."""
    area = math.pi * diameter ** 2 / 4.0
    n = max(1, int(round(ht * area * length_ratio * diameter / cell_volume)))
    length = max(1, int(round(n * cell_volume / (ht * area) / AGRID))) * AGRID
    return n, length, n * cell_volume / (area * length)


def packed_placements(cell_type, centre, radius, length, n, seed, margin=0.5, gap=1.0, step=0.5):
    """Placements (origin, rotate) of n cells in the tube, for where random
    placement (oif.seed_cells) jams (D 15 and 20 at H_T 0.16): the cells'
    discs facing along x, y or z, packed greedily on a grid of origins (x
    step `step`, y and z step 1.5 step; nodes at least `margin` from the
    wall, `gap` from other cells, periodic in x), then n of the packed
    cells drawn at random."""
    from scipy.spatial import cKDTree
    from oif import geometry
    nodes0 = np.asarray(cell_type.mesh.positions(), dtype=float)
    angles = ([0.0, 0.0, 0.0], [math.pi / 2, 0.0, 0.0], [0.0, math.pi / 2, 0.0])  # normal z, y, x
    shapes_rot = [nodes0 @ geometry.rotation_matrix(a).T for a in angles]
    offsets = np.arange(-radius, radius + 1e-9, 1.5 * step)
    fits = []  # (y, z, orientation) whose nodes keep the margin from the wall
    for o, nodes in enumerate(shapes_rot):
        for dy in offsets:
            for dz in offsets:
                r = np.hypot(nodes[:, 1] + dy, nodes[:, 2] + dz)
                if r.max() <= radius - margin:
                    fits.append((dy, dz, o))
    fits.sort(key=lambda f: -math.hypot(f[0], f[1]))  # from the wall inwards: denser
    side = 4.0 * (radius + 1.0)
    placed, tree, all_nodes = [], None, np.empty((0, 3))
    for x in np.arange(0.0, length, step):
        for dy, dz, o in fits:
            pos = shapes_rot[o] + [x, centre[1] + dy, centre[2] + dz]
            pos[:, 0] %= length
            if tree is not None and np.isfinite(tree.query(pos, distance_upper_bound=gap)[0]).any():
                continue
            placed.append(([x, centre[1] + dy, centre[2] + dz], angles[o]))
            all_nodes = np.vstack([all_nodes, pos])
            tree = cKDTree(all_nodes, boxsize=[length, side, side])
    if len(placed) < n:
        raise RuntimeError(f"packed_placements: only {len(placed)} cells fit in the tube of radius {radius}, "
                           f"length {length}; {n} asked: lower the haematocrit")
    pick = np.random.default_rng(seed).choice(len(placed), size=n, replace=False)
    return [placed[i] for i in sorted(pick)]


def flow_rate(fluid, length):
    """Q = sum over the nodes of u_x agrid^3 / L (boundary nodes carry no flow)."""
    u = fluid[:, :, :].velocity[..., 0]
    return float(u.sum()) * AGRID ** 3 / length


def run_tube(diameter, ca=10.0, hd_target=0.25, ht=None, length_ratio=4.0, strain=150.0, transient=50.0,
             gamma_factor=1.0, seed=1, node_mass_ratio=NODE_MASS_RATIO, kvisc=KVISC, progress=None, vtk=None,
             packing="legacy", contacts="legacy"):
    """One tube: the cell-free run, then the suspension. Returns (summary
    dict, time series list of dicts).

    packing: "legacy" (random seeding, or the greedy grid in wider tubes;
    the validated default) or "pack" (oif.pack_cells: force-biased packing,
    reaches the haematocrits of H_D 0.3-0.45); contacts: "legacy"
    (membrane_collision and soft-sphere, as validated) or "hard" (the
    advised hard_contact, oif.set_contacts, scaled like the legacy ones)."""
    for name, value in (("diameter", diameter), ("ca", ca), ("length_ratio", length_ratio), ("strain", strain),
                        ("gamma_factor", gamma_factor)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"run_tube: parameter '{name}' must be a finite number > 0, got {value!r}")
    if node_mass_ratio is not None and not (isinstance(node_mass_ratio, (int, float))
                                            and math.isfinite(node_mass_ratio) and 0 < node_mass_ratio <= 1):
        raise ValueError(f"run_tube: parameter 'node_mass_ratio' (gamma dt / m) must be in (0, 1] or None, "
                         f"got {node_mass_ratio!r}")
    if packing not in ("legacy", "pack"):
        raise ValueError(f"run_tube: parameter 'packing' must be 'legacy' or 'pack', got {packing!r}")
    if contacts not in ("legacy", "hard"):
        raise ValueError(f"run_tube: parameter 'contacts' must be 'legacy' or 'hard', got {contacts!r}")
    if not (isinstance(kvisc, (int, float)) and math.isfinite(kvisc) and kvisc >= 0):
        raise ValueError(f"run_tube: parameter 'kvisc' must be a finite number >= 0, got {kvisc!r}")
    if not 2.0 * RBC_RADIUS + 1.0 < diameter:
        raise ValueError(f"run_tube: parameter 'diameter' {diameter} must exceed the cell's diameter "
                         f"{2 * RBC_RADIUS} + 1 um (the cells must fit)")
    if not 0 <= transient < strain:
        raise ValueError(f"run_tube: parameter 'transient' {transient!r} must be in [0, strain {strain})")
    if ht is None:
        if not 0 < hd_target < 0.6:
            raise ValueError(f"run_tube: parameter 'hd_target' must be in (0, 0.6), got {hd_target!r}")
        ht_aim = hd_target * float(pries_ht_over_hd(diameter, hd_target))
    else:
        if not 0 < ht < 0.5:
            raise ValueError(f"run_tube: parameter 'ht' must be in (0, 0.5), got {ht!r}")
        ht_aim = ht
    radius = diameter / 2.0
    width = (math.ceil(diameter / AGRID) + 2) * AGRID  # a layer of wall nodes around the lumen
    # the cell volume before the system exists: a throw-away type on a scratch system
    scratch = lbmd.System(box_l=[100.0, 100.0, 100.0])
    v_cell = oif.OifCellType(*oif.mesh_files("rbc374"), system=scratch, resize=(RBC_RADIUS,) * 3).volume0
    del scratch
    n_cells, length, ht_seeded = tube_layout(diameter, length_ratio, ht_aim, v_cell)
    f, gamma_w = force_density(diameter, ca)

    system = lbmd.System(box_l=[length, width, width])
    system.time_step = TIME_STEP
    system.cell_system.skin = 0.3
    centre = [length / 2.0, width / 2.0, width / 2.0]
    # open and three box lengths long: it runs through the periodic box (positions are folded)
    tube = shapes.Cylinder(center=centre, axis=[1, 0, 0], radius=radius, length=3.0 * length, direction=-1,
                           open=True)
    fluid = lb.LBFluid(agrid=AGRID, dens=DENS, visc=VISC, tau=TIME_STEP, ext_force_density=[f, 0, 0])
    system.actors.add(fluid)
    system.lbboundaries.add(lbboundaries.LBBoundary(shape=tube))
    lumen_nodes = int((fluid[:, :, :].boundary == 0).sum())

    # cell-free: Q_plasma of this lattice tube, against Poiseuille's pi f D^4 / (128 eta)
    t0 = time.process_time()
    q_prev, plasma_steps = 0.0, 0
    chunk = max(20, int(0.1 * radius ** 2 / VISC / TIME_STEP))
    while True:
        system.integrator.run(chunk)
        plasma_steps += chunk
        q_plasma = flow_rate(fluid, length)
        if abs(q_plasma - q_prev) < 1e-7 * abs(q_plasma):
            break
        q_prev = q_plasma
    q_poiseuille = math.pi * f * diameter ** 4 / (128.0 * ETA)
    plasma_cpu = time.process_time() - t0

    # the suspension, from the developed plasma flow
    ct = oif.OifCellType(*oif.mesh_files("rbc374"), system=system, resize=(RBC_RADIUS,) * 3, normal=True,
                         kvisc=kvisc, **RBC_MODULI)
    gamma = gamma_factor * ct.suggest_LBgamma(visc=VISC, dens=DENS)
    node_mass = 1.0 if node_mass_ratio is None else gamma * TIME_STEP / node_mass_ratio
    cells = None
    if packing == "pack":
        clearance = oif.contacts.packing_clearance(ct, scale=max(1.0, ca / 2.0), time_step=TIME_STEP,
                                                   node_mass=node_mass)  # the contacts' scale below
        cells = list(oif.pack_cells(system, ct, counts=n_cells, boundaries=[tube], particle_types=[CELL_TYPE],
                                    particle_mass=node_mass, seed=seed, clearance=clearance))
    for attempt in range(20 if diameter < 12.0 and cells is None else 0):  # random placement in a narrow tube may need another seed
        try:
            cells = oif.seed_cells(system, ct, counts=n_cells, boundaries=[tube], particle_types=[CELL_TYPE],
                                   seed=seed + 1000 * attempt, particle_mass=node_mass)
            break
        except oif.SeedingError:
            continue
    if cells is None:  # wider tubes (more cells): random placement jams; packed, then drawn at random
        cells = [oif.OifCell(cell_type=ct, particle_type=CELL_TYPE, origin=origin, rotate=rotate,
                             particle_mass=node_mass)
                 for origin, rotate in packed_placements(ct, centre, radius, length, n_cells, seed)]
    system.thermostat.set_lb(LB_fluid=fluid, gamma=gamma)
    system.constraints.add(shape=tube, particle_type=WALL_TYPE)
    # contacts: repulsion strong against the viscous force on a node, eta gamma_w x (area per node, 0.36 um^2)
    # (set for Ca 2), both scaled with the shear rate above Ca 2 (at Ca 10 unscaled, two membranes passed
    # through each other after strain 107 at D 10); the cells' contact reaches 1.0 um, beyond the mesh's
    # longest edge, 0.85 um (doc/accuracy.md, Contacts; at 0.8 and Ca 10 two membranes still crossed)
    scale = max(1.0, ca / 2.0)
    if contacts == "hard":
        contact = oif.set_contacts(system, [ct], particle_types=[CELL_TYPE], wall_types=[WALL_TYPE],
                                   scale=scale)["cell"]["a"]
    else:
        system.non_bonded_inter[CELL_TYPE, WALL_TYPE].soft_sphere.set_params(a=WALL_A * scale, n=1.2,
                                                                           cutoff=0.5, offset=0.0)
        contact = CONTACT_A * scale
        system.non_bonded_inter[CELL_TYPE, CELL_TYPE].membrane_collision.set_params(a=contact, n=4.0,
                                                                                  cutoff=1.0, offset=0.0)
    v0 = np.array([c.volume() for c in cells])
    s0 = np.array([c.surface() for c in cells])
    worst_surface = 0.0
    chunk = max(1, int(round(SAMPLE_STRAIN / (gamma_w * TIME_STEP))))
    n_samples = int(math.ceil(strain / SAMPLE_STRAIN))
    series = []
    x_prev = np.array([c.get_origin()[0] for c in cells])
    q_prev = flow_rate(fluid, length)
    worst_volume = 0.0
    cell_series = oif.CellSeries(vtk) if vtk else None
    t0 = time.process_time()
    stopped = ""
    for k in range(n_samples):
        try:
            system.integrator.run(chunk)
        except lbmd.SimulationInstability as e:
            # a membrane folded through itself (D 15 and 20 at Ca 10, after strain 100 or so): with at
            # least 2 samples per block of the window the run is summarised up to here and says so
            n_window = sum(1 for r in series if r["strain"] > transient + 1e-9)
            if n_window < 2 * BLOCKS:
                raise
            stopped = f"strain {series[-1]['strain']:.1f}: {getattr(e, 'cause', '')}: {str(e)[:400]}"
            break
        if cell_series:
            cell_series.write(cells, system.time)
        q = flow_rate(fluid, length)
        origins = np.array([c.get_origin() for c in cells])
        vols = np.array([c.volume() for c in cells])
        worst_volume = max(worst_volume, float(np.max(np.abs(vols / v0 - 1.0))))
        surface_dev = float(np.max(np.abs(np.array([c.surface() for c in cells]) / s0 - 1.0)))
        worst_surface = max(worst_surface, surface_dev)
        dt = chunk * TIME_STEP
        u_cells = (origins[:, 0] - x_prev) / dt
        x_prev = origins[:, 0]
        q_mean = 0.5 * (q + q_prev)  # over the interval: the cells' displacement is over it too
        q_prev = q
        cell_flux = float(np.dot(vols, u_cells)) / length
        r_off = np.hypot(origins[:, 1] - centre[1], origins[:, 2] - centre[2])
        nodes = np.concatenate([c.particles.pos for c in cells])
        r_nodes = np.hypot(nodes[:, 1] - centre[1], nodes[:, 2] - centre[2])
        row = {"diameter": diameter, "time": system.time, "strain": gamma_w * chunk * TIME_STEP * (k + 1),
               "Q": q, "Q_interval": q_mean, "cell_flux": cell_flux, "eta_rel": q_plasma / q_mean,
               "H_D": cell_flux / q_mean, "mean_axis_offset_over_R": float(r_off.mean()) / radius,
               "worst_volume_dev": float(np.max(np.abs(vols / v0 - 1.0))), "worst_surface_dev": surface_dev,
               "min_wall_gap": radius - float(r_nodes.max())}
        series.append(row)
        if progress:
            progress(row)
    cpu = time.process_time() - t0

    window = [r for r in series if r["strain"] > transient + 1e-9]
    q_w = np.array([r["Q_interval"] for r in window])
    flux_w = np.array([r["cell_flux"] for r in window])
    eta_rel = q_plasma / float(q_w.mean())
    hd = float(flux_w.mean() / q_w.mean())
    blocks = np.array_split(np.arange(len(window)), BLOCKS)
    eta_blocks = np.array([q_plasma / q_w[b].mean() for b in blocks])
    hd_blocks = np.array([flux_w[b].mean() / q_w[b].mean() for b in blocks])
    eta_pries = float(pries_viscosity(diameter, hd))
    ratio_pries = float(pries_ht_over_hd(diameter, hd))
    u_mean = float(q_w.mean()) / (math.pi * radius ** 2)
    summary = {
        "diameter": diameter, "length": length, "n_cells": n_cells, "cell_volume": v_cell,
        "lumen_nodes_per_agrid": lumen_nodes / (length / AGRID), "lumen_nominal": math.pi * radius ** 2,
        "H_T": ht_seeded, "H_D": hd, "H_D_err": float(hd_blocks.std(ddof=1) / math.sqrt(BLOCKS)),
        "eta_rel": eta_rel, "eta_rel_err": float(eta_blocks.std(ddof=1) / math.sqrt(BLOCKS)),
        "eta_rel_pries": eta_pries, "eta_rel_error": eta_rel / eta_pries - 1.0,
        "HT_over_HD": ht_seeded / hd, "HT_over_HD_pries": ratio_pries,
        "HT_over_HD_error": ht_seeded / hd / ratio_pries - 1.0,
        "Q_plasma": q_plasma, "Q_poiseuille": q_poiseuille, "Q_plasma_over_poiseuille": q_plasma / q_poiseuille,
        "Q_suspension": float(q_w.mean()), "force_density": f, "Ca": ca, "wall_shear_rate": gamma_w,
        "wall_shear_rate_per_s": gamma_w * 1e6, "pseudo_shear_rate_per_s": u_mean / diameter * 1e6,
        "mean_velocity": u_mean, "Re": DENS * u_mean * diameter / ETA, "gamma": gamma,
        "gamma_factor": gamma_factor, "node_mass": node_mass,
        "gamma_dt_over_m": gamma * TIME_STEP / node_mass, "kvisc": kvisc, "contact_a": contact,
        "strain": series[-1]["strain"], "transient": transient,
        "window_samples": len(window), "stopped": stopped, "worst_volume_dev": worst_volume,
        "worst_surface_dev": worst_surface, "packing": packing, "contacts": contacts,
        "final_axis_offset_over_R": series[-1]["mean_axis_offset_over_R"],
        "steps": chunk * len(series), "plasma_steps": plasma_steps, "cpu_s": cpu, "plasma_cpu_s": plasma_cpu,
        "seed": seed}
    return summary, series


def plot(rows, series, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.2))
    d_all = np.array([r["diameter"] for r in rows])
    dd = np.linspace(min(8.0, d_all.min()), max(30.0, d_all.max() + 5.0), 200)
    hds = sorted({round(r["H_D"], 2) for r in rows})

    def pries_panel(ax, fit, fit_hds, ours, errors, pries_key, label, ylabel, title, legend_at):
        """The fit's curves at several H_D (solid at the measured ones), ours
        with error bars and the fit at our H_D."""
        for h in sorted(set(fit_hds + hds)):
            style = "-" if h in hds else ":"
            ax.plot(dd, fit(dd, h), style, color="0.4" if h in hds else "0.7", lw=1.0)
            ax.annotate(f"H_D {h:.2f}", (dd[-1], float(fit(dd[-1], h))), fontsize=7, ha="right", va="bottom")
        ax.errorbar(d_all, ours, yerr=errors, fmt="o", color="tab:red", label="PyOIF")
        ax.plot(d_all, [r[pries_key] for r in rows], "x", color="k", ms=8, label=label)
        ax.set_xlabel("tube diameter D (µm)")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7, loc=legend_at)

    pries_panel(axes[0], pries_viscosity, [0.15, 0.30, 0.45], [r["eta_rel"] for r in rows],
                [r["eta_rel_err"] for r in rows], "eta_rel_pries", "Pries 1992 at the measured H_D",
                "relative apparent viscosity η_rel", "Fåhræus–Lindqvist (Pries et al. 1992, in vitro)", "upper left")
    pries_panel(axes[1], pries_ht_over_hd, [0.15, 0.45], [r["HT_over_HD"] for r in rows],
                [r["HT_over_HD"] * r["H_D_err"] / r["H_D"] for r in rows], "HT_over_HD_pries",
                "Pries 1990 at the measured H_D", "H_T / H_D", "Fåhræus effect (Pries et al. 1990)", "lower right")
    ax = axes[2]
    for r in rows:
        s = [q for q in series if q["diameter"] == r["diameter"] and q.get("Ca", r["Ca"]) == r["Ca"]]
        x = [q["strain"] for q in s]
        tag = f"D {r['diameter']:g}, Ca {r['Ca']:g}"
        line, = ax.plot(x, [q["eta_rel"] for q in s], "-", lw=1.0, label=f"η_rel, {tag}")
        ax.plot(x, [q["H_D"] for q in s], "--", lw=1.0, color=line.get_color(), label=f"H_D, {tag}")
        ax.axvline(r["transient"], color=line.get_color(), lw=0.6, ls=":")
    ax.set_xlabel("strain γ_w t (wall shear rate of the plasma flow)")
    ax.set_ylabel("η_rel (solid), H_D (dashed)")
    ax.set_title("time series; averages right of the dotted line", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--diameters", type=float, nargs="+", default=[10.0], help="tube diameters in um (10-20)")
    parser.add_argument("--hd", type=float, default=0.25,
                        help="target discharge haematocrit: sets the number of cells through Pries 1990")
    parser.add_argument("--ht", type=float, default=None, help="tube haematocrit to seed (instead of --hd)")
    parser.add_argument("--ca", type=float, nargs="+", default=[10.0],
                        help="capillary number(s) eta gamma_w r / Gs of the driving (plasma wall shear rate)")
    parser.add_argument("--strain", type=float, default=150.0, help="run length in wall strain units gamma_w t")
    parser.add_argument("--transient", type=float, default=50.0,
                        help="strain discarded before averaging (see the time series)")
    parser.add_argument("--length-ratio", type=float, default=4.0, help="tube length / diameter (about)")
    parser.add_argument("--gamma-factor", type=float, default=1.0, help="coupling friction / suggest_LBgamma")
    parser.add_argument("--seed", type=int, default=1, help="seed of the cells' placement")
    parser.add_argument("--node-mass-ratio", type=float, default=NODE_MASS_RATIO,
                        help="gamma dt / m of the membrane nodes: sets their mass m from the coupling "
                             "friction gamma (0.152 gives the former mass 1)")
    parser.add_argument("--kvisc", type=float, default=KVISC, help="membrane viscosity kvisc (lattice units)")
    parser.add_argument("--packing", choices=("legacy", "pack"), default="legacy",
                        help="cells placed by random seeding / a greedy grid (legacy) or oif.pack_cells (pack)")
    parser.add_argument("--contacts", choices=("legacy", "hard"), default="legacy",
                        help="membrane_collision + soft-sphere (legacy) or the advised hard_contact (hard)")
    parser.add_argument("--combine", nargs="+", default=None, metavar="DIR",
                        help="run nothing: join the CSVs of earlier runs' output folders into --output "
                             "(tables and figure)")
    parser.add_argument("--output", default="output_fahraeus_lindqvist", help="folder for the CSV and PNG")
    args = parser.parse_args()
    if args.combine:
        return combine(args.combine, args.output)
    if any(not np.isfinite(d) or not 2.0 * RBC_RADIUS + 1.0 < d <= 60.0 for d in args.diameters):
        parser.error(f"--diameters: expected diameters in ({2 * RBC_RADIUS + 1:g}, 60] um, got {args.diameters}")
    if not 0 < args.hd < 0.6:
        parser.error(f"--hd: expected a discharge haematocrit in (0, 0.6), got {args.hd}")
    if args.ht is not None and not 0 < args.ht < 0.5:
        parser.error(f"--ht: expected a tube haematocrit in (0, 0.5), got {args.ht}")
    if any(not np.isfinite(c) or c <= 0 for c in args.ca):
        parser.error(f"--ca: expected capillary numbers > 0, got {args.ca}")
    if not args.strain > 0 or not np.isfinite(args.strain):
        parser.error(f"--strain: expected a strain > 0, got {args.strain}")
    if not 0 <= args.transient < args.strain:
        parser.error(f"--transient: expected a strain in [0, --strain {args.strain}), got {args.transient}")
    if not args.length_ratio >= 1.5 or not np.isfinite(args.length_ratio):
        parser.error(f"--length-ratio: expected at least 1.5, got {args.length_ratio}")
    if not args.gamma_factor > 0 or not np.isfinite(args.gamma_factor):
        parser.error(f"--gamma-factor: expected a factor > 0, got {args.gamma_factor}")
    if args.node_mass_ratio is not None and not 0 < args.node_mass_ratio <= 1:
        parser.error(f"--node-mass-ratio: expected gamma dt / m in (0, 1], got {args.node_mass_ratio}")
    if not args.kvisc >= 0 or not np.isfinite(args.kvisc):
        parser.error(f"--kvisc: expected a membrane viscosity >= 0, got {args.kvisc}")
    if args.seed < 0:
        parser.error(f"--seed: expected an integer >= 0, got {args.seed}")
    os.makedirs(args.output, exist_ok=True)

    rows, series = [], []
    for d in args.diameters:
        for ca in args.ca:
            def progress(r, d=d, ca=ca):
                print(f"  D {d:g} Ca {ca:g} strain {r['strain']:6.1f}: eta_rel {r['eta_rel']:.4f}  H_D "
                      f"{r['H_D']:.4f}  axis offset/R {r['mean_axis_offset_over_R']:.3f}  volume dev "
                      f"{r['worst_volume_dev']:.4f}  wall gap {r['min_wall_gap']:.3f}", flush=True)
            s, ts = run_tube(d, ca=ca, hd_target=args.hd, ht=args.ht, length_ratio=args.length_ratio,
                             strain=args.strain, transient=args.transient, gamma_factor=args.gamma_factor,
                             seed=args.seed, node_mass_ratio=args.node_mass_ratio, kvisc=args.kvisc,
                             progress=progress, packing=args.packing, contacts=args.contacts)
            for r in ts:
                r["Ca"] = ca
            rows.append(s)
            series.extend(ts)
            print(f"D {d:g} um, Ca {ca:g}: {s['n_cells']} cells, L {s['length']:g}, H_T {s['H_T']:.4f}; "
                  f"Q_plasma/Poiseuille {s['Q_plasma_over_poiseuille']:.4f}; "
                  f"eta_rel {s['eta_rel']:.4f} +- {s['eta_rel_err']:.4f} (Pries {s['eta_rel_pries']:.4f}, "
                  f"{100 * s['eta_rel_error']:+.1f} %); H_D {s['H_D']:.4f} +- {s['H_D_err']:.4f}; "
                  f"H_T/H_D {s['HT_over_HD']:.4f} (Pries {s['HT_over_HD_pries']:.4f}, "
                  f"{100 * s['HT_over_HD_error']:+.1f} %); Re {s['Re']:.3f}; worst volume dev "
                  f"{s['worst_volume_dev']:.4f}; {s['steps']} steps, {s['cpu_s']:.1f} CPU s"
                  + (f"; STOPPED at {s['stopped']}" if s["stopped"] else ""), flush=True)
    write_results(rows, series, args.output)


def write_results(rows, series, output):
    """The two CSVs, the figure and the worst errors into the folder output."""
    os.makedirs(output, exist_ok=True)
    stem = os.path.join(output, "fahraeus_lindqvist")
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, restval="")
        w.writeheader()
        w.writerows(rows)
    with open(stem + "_timeseries.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["diameter", "Ca"] + [k for k in series[0] if k not in ("diameter", "Ca")])
        w.writeheader()
        w.writerows(series)
    plot(rows, series, stem + ".png")
    print(f"worst |eta_rel / Pries - 1| {max(abs(r['eta_rel_error']) for r in rows):.3f}, "
          f"worst |(H_T/H_D) / Pries - 1| {max(abs(r['HT_over_HD_error']) for r in rows):.3f}")
    print(f"total {sum(float(r['cpu_s']) + float(r['plasma_cpu_s']) for r in rows):.1f} CPU s")
    print("wrote", stem + ".csv", stem + "_timeseries.csv", stem + ".png")


def combine(folders, output):
    """Join the results of earlier runs (their output folders) into one
    table, time series and figure in output."""
    def number(v):
        try:
            return float(v)
        except ValueError:
            return v

    rows, series = [], []
    for folder in folders:
        stem = os.path.join(folder, "fahraeus_lindqvist")
        for name, target in ((stem + ".csv", rows), (stem + "_timeseries.csv", series)):
            try:
                with open(name, newline="") as f:
                    target.extend({k: number(v) for k, v in r.items()} for r in csv.DictReader(f))
            except OSError as e:
                raise OSError(f"--combine: cannot read {name}: {e.strerror}") from e
    if not rows:
        raise ValueError(f"--combine: no runs in {folders}")
    rows.sort(key=lambda r: (r["diameter"], r["Ca"]))
    write_results(rows, series, output)


if __name__ == "__main__":
    main()
