#!/usr/bin/env pyoif
"""Validation: a spherical capsule in simple shear flow, against the
small-deformation theory of D. Barthes-Biesel and J. M. Rallison, "The
time-dependent deformation of a capsule freely suspended in a linear shear
flow", J. Fluid Mech. 113, 251-267 (1981) (and D. Barthes-Biesel, J. Fluid
Mech. 100, 831-853, 1980).

    pyoif samples/validation/capsule_shear.py [--ca 0.0125 0.025 0.05] [--couplings 1 4 8]
        [--mesh sphere642] [--radius 6] [--height-ratio 10] [--strain 4] [--output DIR]

Theory. A spherical capsule of radius a (membrane: shear modulus Gs,
surface Poisson ratio nu_s, no bending) in a simple shear flow of rate
gamma_dot of a fluid of dynamic viscosity eta (the same inside) takes, to
first order in the capillary number Ca = eta gamma_dot a / Gs, a steady
ellipsoidal shape in the shear plane with the Taylor deformation

    D = (L - B) / (L + B) = (5/4) (2 + nu_s) / (1 + nu_s) Ca,

independent of the viscosity ratio (Barthes-Biesel & Rallison 1981; see
also D. Barthes-Biesel, Annu. Rev. Fluid Mech. 48, 25-52, 2016). A neo-Hookean membrane has, at small strain, the area
dilation modulus K = 3 Gs, i.e. nu_s = (K - Gs)/(K + Gs) = 1/2, so
D = 25/12 Ca with Ca based on Gs. The often quoted "D = 25/4 Ca" is the
same result with the capillary number based on the neo-Hookean law's
surface modulus Es = 3 Gs (Barthes-Biesel & Rallison write the law with
Es; Ca_Es = Ca / 3).

Model. OIF membrane, lattice units (agrid 1, time step 0.1, density 1,
kinematic viscosity 1.5): stretching ks gives Gs = sqrt(3)/4 ks
(doc/model.md, Units and SI); the spring network alone has K = 2 Gs, so a
local area term kal = 2 Gs raises K to 3 Gs (K = sqrt(3)/2 ks + kal/2,
nu_s = 1/2, the neo-Hookean value). A small bending (kc/(Gs a^2) = 0.005;
the theory has none) keeps the mesh smooth; a volume term kv = 2 Gs/a holds
the enclosed volume (the theory's incompressible inner fluid). The capsule
(sphere642, radius a = 6 lattice nodes, edges about one agrid) sits midway
between two walls moving at -U and +U (LB bounce-back, Couette flow),
channel height H = 10 a; the box is periodic along the flow (x, 6 a) and
the vorticity (y, 6 a). The shear rate 0.008 is the same at every Ca
(Reynolds number gamma_dot a^2 / nu = 0.19); ks sets Ca.

Coupling. The friction coupling (force gamma (u - v) on each node) lets
the membrane slip against the fluid; the theory has none. Each Ca runs at
several frictions gamma, in units of suggest_LBgamma (--couplings, default
1, 4, 8); 1/D is close to linear in 1/gamma (a resistance in series with
the fluid's), and the two largest frictions give the no-slip limit
1/gamma -> 0, compared with the theory. At suggest_LBgamma alone the
capsule deforms about 30 % less than the theory (doc/validation.md).

Measurement. D from the equivalent ellipsoid of the membrane: the second
moment of the enclosed volume (sum over the tetrahedra of the triangulated
surface and its centre), whose in-plane (x, z) eigenvalues are V L^2/5 and
V B^2/5; D is averaged over the last third of the run (4 strain units: the
shape is steady after 2.5, then oscillates by about 2 % with the discrete
membrane's tank-treading). Writes <output>/capsule_shear.csv (per run: Ca,
friction, D, its spread, D/theory, inclination angle, volume and surface
drift; and the no-slip limits) and capsule_shear.png (D against Ca with
the theory line). The default sweep takes about 65 CPU s.
"""
import argparse
import csv
import math
import os
import time

import numpy as np

import oif
from shear_flow import DENS, ETA, VISC, add_couette_flow, couette_system, taylor_deformation


def theory_d(ca, nu_s=0.5):
    """Barthes-Biesel & Rallison (1981) first-order Taylor deformation,
    Ca = eta gamma_dot a / Gs; nu_s 1/2 is the neo-Hookean membrane."""
    return 1.25 * (2.0 + nu_s) / (1.0 + nu_s) * ca


def run_capsule(ca, mesh="sphere642", radius=6.0, height_ratio=10.0, shear_rate=0.008, strain=4.0,
                bending=0.005, samples=40, coupling=1.0, area_ratio=3.0, progress=None):
    """One capsule in Couette flow at capillary number `ca`; returns a dict
    of the measured D (mean and spread over the last third), the theory,
    the inclination angle and the volume/surface drift."""
    if not ca > 0:
        raise ValueError(f"run_capsule: parameter 'ca' must be > 0, got {ca!r}")
    gs = ETA * shear_rate * radius / ca          # Ca = eta gamma_dot a / Gs
    ks = 4.0 * gs / math.sqrt(3.0)               # Gs = sqrt(3)/4 ks
    kal = 2.0 * (area_ratio - 2.0) * gs          # K = sqrt(3)/2 ks + kal/2 = area_ratio Gs (3: neo-Hookean)
    kb = bending * gs * radius ** 2 * 2.0 / math.sqrt(3.0)  # kc = sqrt(3)/2 kb = bending Gs a^2
    kv = 2.0 * gs / radius                       # volume modulus, pressure ~ kv dV/V against Gs/a
    height = height_ratio * radius
    lx = ly = math.ceil(6.0 * radius)
    system = couette_system(lx, ly, height)
    lz = system.box_l[2]
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(radius,) * 3,
                         ks=ks, kal=kal, kb=kb, kv=kv, normal=True)
    gamma = coupling * ct.suggest_LBgamma(visc=VISC, dens=DENS)
    # node mass: gamma dt / m <= 1/2 keeps the friction step stable (check_settings); the
    # steady shape does not depend on it
    mass = max(1.0, 2.0 * gamma * system.time_step)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[lx / 2, ly / 2, lz / 2], particle_mass=mass)
    triangles = np.asarray(ct.mesh.triangle_ids)
    add_couette_flow(system, shear_rate, gamma)
    v0, s0 = cell.volume(), cell.surface()
    total_steps = int(round(strain / shear_rate / system.time_step))
    chunk = max(1, total_steps // samples)
    history = []
    for i in range(samples):
        system.integrator.run(chunk)
        d, angle = taylor_deformation(cell.mesh.positions(), triangles)
        history.append((system.time * shear_rate, d, angle))
        if progress:
            progress(ca, history[-1])
    tail = np.array(history[-max(2, samples // 3):])
    d_mean = float(tail[:, 1].mean())
    return {"Ca": ca, "D": d_mean, "D_spread": float(tail[:, 1].max() - tail[:, 1].min()),
            "D_theory": theory_d(ca), "ratio": d_mean / theory_d(ca), "angle_deg": float(tail[:, 2].mean()),
            "volume_rel": cell.volume() / v0, "surface_rel": cell.surface() / s0,
            "Re": shear_rate * radius ** 2 / VISC, "a_over_H": radius / height, "ks": ks, "kal": kal, "kb": kb,
            "kv": kv, "gamma": gamma, "coupling": coupling, "mesh": mesh, "radius": radius, "strain": strain, "steps": chunk * samples,
            "history": history}


def no_slip_limit(rows):
    """D extrapolated to an infinite coupling friction from the runs at the
    two largest couplings: the friction coupling lets the membrane slip
    against the fluid, a resistance in series with the fluid's, so 1/D is
    close to linear in 1/gamma (measured: doc/validation.md); the theory
    assumes no slip, 1/gamma -> 0."""
    a, b = sorted(rows, key=lambda r: r["gamma"])[-2:]
    x_a, x_b, y_a, y_b = 1.0 / a["gamma"], 1.0 / b["gamma"], 1.0 / a["D"], 1.0 / b["D"]
    intercept = y_b - (y_a - y_b) / (x_a - x_b) * x_b
    return 1.0 / intercept


def plot(rows, limits, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ca = np.array(sorted(limits))
    x = np.linspace(0.0, 1.15 * ca.max(), 50)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    ax.fill_between(x, 0.9 * theory_d(x), 1.1 * theory_d(x), color="0.88", label="theory ± 10 %")
    ax.plot(x, theory_d(x), "k-", label="Barthès-Biesel & Rallison 1981: D = 25/12 Ca")
    ax.plot(ca, [limits[c] for c in ca], "o", color="tab:red", ms=7, label="PyOIF, no-slip limit (1/γ → 0)")
    markers = iter("sv^<>dp")
    for k in sorted({r["coupling"] for r in rows}):
        sel = sorted((r for r in rows if r["coupling"] == k), key=lambda r: r["Ca"])
        ax.plot([r["Ca"] for r in sel], [r["D"] for r in sel], next(markers, "x"), mfc="none", color="tab:blue",
                alpha=0.4 + 0.6 * k / max(r["coupling"] for r in rows),
                label=f"PyOIF, γ = {k:g} × suggest_LBgamma")
    r0 = rows[0]
    ax.set_xlabel("capillary number Ca = η γ̇ a / Gs")
    ax.set_ylabel("Taylor deformation D = (L − B)/(L + B)")
    ax.set_title(f"Neo-Hookean capsule in shear flow ({r0['mesh']}, a = {r0['radius']:g}, "
                 f"a/H = {r0['a_over_H']:.2f})", fontsize=9)
    ax.set_xlim(0, x[-1])
    ax.set_ylim(0, None)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ca", type=float, nargs="+", default=[0.0125, 0.025, 0.05], help="capillary numbers")
    parser.add_argument("--couplings", type=float, nargs="+", default=[1.0, 4.0, 8.0],
                        help="coupling friction in units of suggest_LBgamma (the two largest give the "
                             "no-slip limit)")
    parser.add_argument("--mesh", default="sphere642", help="shipped sphere mesh: sphere162, sphere642, ...")
    parser.add_argument("--radius", type=float, default=6.0, help="capsule radius in lattice nodes")
    parser.add_argument("--height-ratio", type=float, default=10.0, help="channel height H / a")
    parser.add_argument("--strain", type=float, default=4.0, help="run length in shear strain gamma_dot t")
    parser.add_argument("--output", default="output_capsule_shear", help="folder for the CSV and PNG")
    args = parser.parse_args()
    if any(not np.isfinite(c) or c <= 0 for c in args.ca):
        parser.error(f"--ca: expected capillary numbers > 0, got {args.ca}")
    if len(set(args.couplings)) < 2 or any(not np.isfinite(k) or k <= 0 for k in args.couplings):
        parser.error(f"--couplings: expected at least two different factors > 0, got {args.couplings}")
    if not args.radius >= 2.0:
        parser.error(f"--radius: expected at least 2 lattice nodes, got {args.radius}")
    if not args.height_ratio > 2.0:
        parser.error(f"--height-ratio: expected H / a > 2 (the capsule must fit), got {args.height_ratio}")
    if not args.strain > 0:
        parser.error(f"--strain: expected a shear strain > 0, got {args.strain}")
    os.makedirs(args.output, exist_ok=True)

    rows, limits = [], {}
    for ca in args.ca:
        for k in sorted(set(args.couplings)):
            t0 = time.process_time()
            r = run_capsule(ca, mesh=args.mesh, radius=args.radius, height_ratio=args.height_ratio,
                            strain=args.strain, coupling=k)
            r["cpu_s"] = time.process_time() - t0
            r["kind"] = "run"
            rows.append(r)
            print(f"Ca {ca:.4g}  coupling {k:g} (gamma {r['gamma']:.3g}): D {r['D']:.4f} (spread "
                  f"{r['D_spread']:.4f}), theory {r['D_theory']:.4f}, ratio {r['ratio']:.3f}, angle "
                  f"{r['angle_deg']:.1f} deg, volume {r['volume_rel']:.4f}, surface {r['surface_rel']:.4f}, "
                  f"{r['cpu_s']:.1f} CPU s", flush=True)
        limits[ca] = no_slip_limit([r for r in rows if r["Ca"] == ca])
        print(f"Ca {ca:.4g}  no-slip limit: D {limits[ca]:.4f}, theory {theory_d(ca):.4f}, "
              f"ratio {limits[ca] / theory_d(ca):.3f}", flush=True)
    stem = os.path.join(args.output, "capsule_shear")
    fields = ["kind", "Ca", "coupling", "gamma", "D", "D_spread", "D_theory", "ratio", "angle_deg", "volume_rel",
              "surface_rel", "Re", "a_over_H", "ks", "kal", "kb", "kv", "mesh", "radius", "strain", "steps", "cpu_s"]
    table = rows + [{"kind": "no_slip_limit", "Ca": ca, "coupling": "inf", "gamma": "inf", "D": d,
                     "D_theory": theory_d(ca), "ratio": d / theory_d(ca)} for ca, d in limits.items()]
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(table)
    plot(rows, limits, stem + ".png")
    print(f"no-slip limit, worst |D/theory - 1|: {max(abs(d / theory_d(c) - 1.0) for c, d in limits.items()):.3f}")
    print(f"total {sum(r['cpu_s'] for r in rows):.1f} CPU s")
    print("wrote", stem + ".csv", stem + ".png")


if __name__ == "__main__":
    main()
