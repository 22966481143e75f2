#!/usr/bin/env pyoif
"""Validation: the drag of a spherical cell in uniform flow against the
Stokes drag of a sphere, for the friction coupling's gamma.

    pyoif samples/validation/cell_drag.py [--mesh sphere642] [--radius 4] [--factors 0.125 ... 8]
                                          [--radii 3 6] [--agrids 0.5] [--boxes 10] [--output DIR]

A spherical cell of radius a (the mesh's nodes on the sphere), its nodes
held fixed, sits in a cubic periodic box of side 5 a; a uniform force
density f drives the fluid past it. In the steady state the cell holds
the whole driving force, F = f L^3, and the fluid's mean (superficial)
velocity U is measured. A rigid no-slip sphere of radius a in the same
box would feel the Stokes drag of the simple cubic array,
F_S = 6 pi eta a U / K(c), c = 4 pi a^3 / (3 L^3) (Hasimoto, J. Fluid
Mech. 5, 317 (1959); Sangani & Acrivos, Int. J. Multiphase Flow 8, 343
(1982); lbmd.stokes). The membrane's nodes are not a no-slip wall: each
drags the fluid with the friction gamma (u - v) (point-force coupling,
Ahlrichs & Duenweg, J. Chem. Phys. 111, 8225 (1999)), so the drag per
velocity D = F / U grows with the total friction gamma N towards that of
a sphere of some hydrodynamic radius; in series, roughly
1/D = 1/(gamma N) + 1/D_inf (Ahlrichs & Duenweg's 1/zeta_eff = 1/zeta +
1/(g eta a_lattice), for the whole shell). oif's suggest_LBgamma (PyOIF;
Busik, Slavik & Cimrak, "Dissipative coupling of fluid and immersed
objects for modelling of cells in flow", Comput. Math. Methods Med. 2018,
7842857) chose gamma so that a sphere's drag matches Stokes'.

Runs: gamma = factor x suggest_LBgamma for each --factors (at --radius
nodes, agrid 1, box 5 a), then at the suggested gamma each --radii
(nodes, agrid 1), each --agrids (the same radius in um, finer or coarser
lattice) and each --boxes (box side in radii). A run that the coupling
makes unstable (gamma N tau / (dens S agrid) well above 1, see
system.check_settings) is a row marked with the instability's cause.
Units: the PyOIF paper's (1 um, 1 us, 1e-15 kg): kinematic viscosity
1.5, density 1.025 (suggest_LBgamma's calibration point), tau 0.1.

Writes <output>/cell_drag.csv (one row a run: gamma, gamma N, U, F, the
periodic Stokes drag F_S of the radius a, F / F_S, the hydrodynamic radius
a_eff with 6 pi eta a_eff U / K(c(a_eff)) = F, steps, convergence) and
cell_drag.png (F / F_S against gamma N / the suggested one; a_eff / a).
The default runs take about 30 CPU s (the 10 a box 20 of them).
"""
import argparse
import csv
import os
import time

import numpy as np

import lbmd
import lbmd.lb
import lbmd.stokes
import oif

VISC, DENS, TAU = 1.5, 1.025, 0.1  # suggest_LBgamma's calibration point (visc 1.5, dens 1.025)
BOX_PER_RADIUS = 5.0
REYNOLDS = 0.02  # U 2a / nu of the Stokes estimate: creeping flow


def drag_run(mesh="sphere642", radius=4.0, agrid=1.0, gamma_factor=1.0, gamma=None, box_per_radius=BOX_PER_RADIUS,
             tolerance=1e-3, max_chunks=40):
    """One fixed spherical cell of radius `radius` (um) in a periodic box of
    side box_per_radius * radius, fluid driven past it; a row (module
    docstring). gamma: the coupling friction per node (default gamma_factor
    times suggest_LBgamma). Steady state: the mean velocity changes by less
    than `tolerance` (relative) over one relaxation time of the mean flow."""
    length = box_per_radius * radius
    n_lattice = length / agrid
    if abs(n_lattice - round(n_lattice)) > 1e-9:
        raise ValueError(f"drag_run: the box side {length} must be a multiple of 'agrid' {agrid}")
    system = lbmd.System(box_l=[length] * 3)
    system.time_step = TAU
    system.cell_system.skin = 0.2 * agrid
    eta = VISC * DENS
    centre = np.array([length / 2] * 3)
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(radius,) * 3, normal=True,
                         ks=0.0, kb=0.0, kal=0.0, kag=0.0, kv=0.0)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=centre)
    n = cell.get_n_nodes()
    suggested = ct.suggest_LBgamma(visc=VISC, dens=DENS)
    if gamma is None:
        gamma = gamma_factor * suggested
    # the Stokes estimate of the flow, with the friction in series with the
    # rigid sphere's resistance (module docstring): the run starts near it
    stokes_coeff = lbmd.stokes.periodic_stokes_drag(eta, radius, 1.0, length)
    u_stokes = REYNOLDS * VISC / (2 * radius)
    f_total = stokes_coeff * u_stokes
    u_start = f_total * (1.0 / (gamma * n) + 1.0 / stokes_coeff)
    lbf = lbmd.lb.LBFluid(agrid=agrid, dens=DENS, visc=VISC, tau=TAU,
                          ext_force_density=[f_total / length ** 3, 0, 0])
    system.actors.add(lbf)
    cell.particles.fix = [True, True, True]
    cell.particles.v = np.zeros((n, 3))
    system.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
    lbf[:, :, :].velocity = [u_start, 0, 0]
    # the mean flow relaxes on m_fluid / D (D = F / U), the disturbance on L^2 / (4 pi^2 nu)
    relax_time = max(DENS * length ** 3 * u_start / f_total, length ** 2 / (4 * np.pi ** 2 * VISC))
    chunk = max(int(relax_time / TAU), 20)

    def mean_velocity():
        return float(np.mean(lbf[:, :, :].velocity[..., 0]))

    row = {"mesh": mesh, "nodes": n, "radius": radius, "agrid": agrid, "radius_nodes": radius / agrid,
           "box_per_radius": box_per_radius, "box": length,
           "volume_fraction": lbmd.stokes.sphere_volume_fraction(radius, length), "gamma": gamma,
           "gamma_suggested": suggested, "gamma_factor": gamma / suggested, "gamma_N": gamma * n}
    t0 = time.process_time()
    u_prev, steps, converged = mean_velocity(), 0, False
    for _ in range(max_chunks):
        try:
            system.integrator.run(chunk)
        except lbmd.SimulationInstability as err:
            # e.g. gamma N tau / (dens S agrid) past the coupling's stability limit (check_settings warns)
            nan = float("nan")
            row.update({k: nan for k in ("mean_velocity", "reynolds", "drag", "coupling_force", "stokes_drag",
                                         "drag_ratio", "drag_per_velocity", "a_eff", "a_eff_over_a",
                                         "a_eff_minus_a_over_agrid", "last_change")})
            row.update(steps=steps + chunk, viscous_times=(steps + chunk) * TAU * VISC / radius ** 2,
                       converged=False, cpu_s=time.process_time() - t0, unstable=err.cause)
            return row
        steps += chunk
        u = mean_velocity()
        change = abs(u / u_prev - 1)
        u_prev = u
        if change < tolerance:
            converged = True
            break
    cpu = time.process_time() - t0
    drag = f_total  # the cell holds the whole driving force in the steady state
    coupling = cell.total_fluid_force(lbf, gamma)[0]  # sum of gamma (u - v) over the nodes: cross-check
    f_stokes = lbmd.stokes.periodic_stokes_drag(eta, radius, u, length)
    a_eff = lbmd.stokes.hydrodynamic_radius(drag, eta, u, length)
    row.update({"mean_velocity": u, "reynolds": u * 2 * radius / VISC, "drag": drag, "coupling_force": coupling,
            "stokes_drag": f_stokes, "drag_ratio": drag / f_stokes, "drag_per_velocity": drag / u,
            "a_eff": a_eff, "a_eff_over_a": a_eff / radius, "a_eff_minus_a_over_agrid": (a_eff - radius) / agrid,
            "steps": steps, "viscous_times": steps * TAU * VISC / radius ** 2, "last_change": change,
            "converged": converged, "cpu_s": cpu, "unstable": ""})
    return row


def series_fit(rows):
    """D_inf of the series model 1/D = 1/(gamma N) + 1/D_inf, least squares in
    1/D over the gamma sweep; returns D_inf."""
    resid = np.array([1 / r["drag_per_velocity"] - 1 / r["gamma_N"] for r in rows])
    return 1.0 / float(np.mean(resid))


def plot(sweep, others, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.5, 4.0))
    x = np.array([r["gamma_factor"] for r in sweep])
    ax1.semilogx(x, [r["drag_ratio"] for r in sweep], "o-", label="PyOIF: F / F_Stokes (radius a)")
    if len(sweep) > 1:
        d_inf = series_fit(sweep)
        xs = np.geomspace(x.min(), x.max(), 100)
        gn = xs * sweep[0]["gamma_N"] / sweep[0]["gamma_factor"]
        # F / F_S = D / D_S with D_S = 6 pi eta a / K, the same for every run of the sweep
        d_stokes = sweep[0]["drag_per_velocity"] / sweep[0]["drag_ratio"]
        ax1.semilogx(xs, 1 / (1 / gn + 1 / d_inf) / d_stokes, "--", color="grey",
                     label="series 1/D = 1/(gamma N) + 1/D_inf")
    ax1.axhline(1.0, color="k", lw=0.8, label="periodic Stokes drag (Hasimoto)")
    ax1.axvline(1.0, color="tab:red", lw=0.8, ls=":", label="suggest_LBgamma")
    ax1.set_xlabel(f"gamma / suggest_LBgamma (gamma N = {sweep[0]['gamma_N'] / sweep[0]['gamma_factor']:.0f} at 1)")
    ax1.set_ylabel("drag / periodic Stokes drag of radius a")
    ax1.set_title(f"{sweep[0]['mesh']}, a = {sweep[0]['radius_nodes']:g} agrid, box {BOX_PER_RADIUS:g} a",
                  fontsize=9)
    ax1.legend(fontsize=7)
    ax2.semilogx(x, [r["a_eff_over_a"] for r in sweep], "o-", label="gamma sweep")
    for r in others:
        ax2.semilogx([r["gamma_factor"]], [r["a_eff_over_a"]], "s", ms=6,
                     label=f"a = {r['radius_nodes']:g} agrid (agrid {r['agrid']:g}), box {r['box_per_radius']:g} a")
    ax2.axhline(1.0, color="k", lw=0.8)
    ax2.axvline(1.0, color="tab:red", lw=0.8, ls=":")
    ax2.set_xlabel("gamma / suggest_LBgamma")
    ax2.set_ylabel("hydrodynamic radius a_eff / a")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def positive_list(parser, name, values):
    if any(not np.isfinite(v) or v <= 0 for v in values):
        parser.error(f"--{name}: expected positive numbers, got {values}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default="sphere642", help="shipped sphere mesh: sphere162, sphere642, sphere2562")
    parser.add_argument("--radius", type=float, default=4.0, help="the cell's radius in lattice nodes (agrid 1)")
    parser.add_argument("--factors", type=float, nargs="+", default=[0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0],
                        help="gamma / suggest_LBgamma of the sweep")
    parser.add_argument("--radii", type=float, nargs="*", default=[3.0, 6.0],
                        help="further radii (nodes, agrid 1) at the suggested gamma")
    parser.add_argument("--agrids", type=float, nargs="*", default=[0.5],
                        help="further lattice spacings at --radius um and the suggested gamma")
    parser.add_argument("--boxes", type=float, nargs="*", default=[10.0],
                        help="further box sides (in radii) at --radius nodes and the suggested gamma")
    parser.add_argument("--output", default="output_cell_drag", help="folder for the CSV and PNG")
    args = parser.parse_args()
    if not args.mesh.startswith("sphere"):
        parser.error(f"--mesh: expected a sphere mesh (sphere162, sphere642, sphere2562), got {args.mesh!r}")
    positive_list(parser, "radius", [args.radius])
    positive_list(parser, "factors", args.factors)
    positive_list(parser, "radii", args.radii)
    positive_list(parser, "agrids", args.agrids)
    positive_list(parser, "boxes", args.boxes)
    os.makedirs(args.output, exist_ok=True)

    def show(r):
        if r["unstable"]:
            print(f"{r['mesh']} a {r['radius']:g} agrid {r['agrid']:g}: gamma {r['gamma']:.4g} "
                  f"(x{r['gamma_factor']:.3g}) gamma N {r['gamma_N']:7.1f}: UNSTABLE ({r['unstable']})", flush=True)
            return
        print(f"{r['mesh']} a {r['radius']:g} agrid {r['agrid']:g}: gamma {r['gamma']:.4g} "
              f"(x{r['gamma_factor']:.3g}) gamma N {r['gamma_N']:7.1f}  U {r['mean_velocity']:.5g}  "
              f"F/F_Stokes {r['drag_ratio']:.4f}  a_eff/a {r['a_eff_over_a']:.4f}  "
              f"coupling/F {r['coupling_force'] / r['drag']:.4f}  Re {r['reynolds']:.3f}  "
              f"{r['steps']} steps ({r['viscous_times']:.1f} a^2/nu) "
              f"{'converged' if r['converged'] else 'NOT converged'}  {r['cpu_s']:.1f} CPU s", flush=True)

    sweep = []
    for fac in sorted(args.factors):
        sweep.append(drag_run(args.mesh, radius=args.radius, gamma_factor=fac))
        show(sweep[-1])
    others = []
    for a in args.radii:
        others.append(drag_run(args.mesh, radius=a))
        show(others[-1])
    for h in args.agrids:
        others.append(drag_run(args.mesh, radius=args.radius, agrid=h))
        show(others[-1])
    for b in args.boxes:
        others.append(drag_run(args.mesh, radius=args.radius, box_per_radius=b))
        show(others[-1])

    rows = sweep + others
    path = os.path.join(args.output, "cell_drag")
    with open(path + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot([r for r in sweep if not r["unstable"]], [r for r in others if not r["unstable"]], path + ".png")
    stable = [r for r in sweep if not r["unstable"]]
    if len(stable) > 1:
        d_inf = series_fit(stable)
        r0 = stable[0]
        a_inf = lbmd.stokes.hydrodynamic_radius(d_inf, VISC * DENS, 1.0, r0["box"])
        print(f"series fit: D_inf {d_inf:.1f}, hydrodynamic radius at infinite friction {a_inf:.3f} "
              f"= a + {(a_inf - r0['radius']) / r0['agrid']:.3f} agrid")
    print("wrote", path + ".csv", path + ".png")


if __name__ == "__main__":
    main()
