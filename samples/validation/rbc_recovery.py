#!/usr/bin/env pyoif
"""Validation: a red blood cell's shape recovery after stretching, against
the measurement of Hochmuth, Worthy & Evans, "Red cell extensional recovery
and the determination of membrane viscosity", Biophys. J. 26, 101-114
(1979): released from micropipettes, cells recover their shape with the
time constant t_c = eta_m / mu = 0.10-0.13 s, mu = 6 uN/m the membrane's
shear modulus and eta_m = (6-8)e-7 N s/m its surface viscosity.

    pyoif samples/validation/rbc_recovery.py [--mesh rbc374]
        [--shear-modulus 6e-6] [--membrane-viscosity 7e-7] [--force 0.03]
        [--time-step 50] [--output DIR]

The cell (the Evans-Fung RBC of radius 3.91 um, the PyOIF paper's kb, kal,
kag, kv) gets its shear modulus and membrane viscosity from the SI values
(lbmd.units.oif_moduli_from_si: ks = 4 mu / sqrt(3), kvisc =
4 eta_m / sqrt(3)); the viscosity is the engine's implicit one (doc/
interactions.md, Membrane viscosity), here at dt kvisc / m about 8, fifty
times the explicit dashpots' limit. Two opposite forces (nN, on the nodes
within 1 um of the rim's ends, as in rbc_stretching.py) stretch it to rest,
then it is released and its axis ratio lambda = L/W (L along the force, W
across it in the disc's plane) is recorded. Fitted as the experiment was
(Evans & Hochmuth 1976, the form Hochmuth et al. 1979 use):

    (lambda - lambda_inf) / (lambda + lambda_inf)
        = (lambda_0 - lambda_inf) / (lambda_0 + lambda_inf) exp(-t / t_c),

lambda_inf the relaxed cell's ratio, by least squares on the logarithm
while the left side is between 80 % and 3 % of its start.

No fluid: the plasma and the haemoglobin add a drag of order eta R
(1.2e-3 Pa s x 4 um = 5e-9 N s/m), under 1 % of the membrane's eta_m, which
the experiment's analysis neglects too. Node mass 1e4 (x 1e-15 kg): the
inertial time m / kvisc, 6 us, is 2e4 times shorter than t_c, so the
recovery is overdamped as in the experiment, and the time step 50 us is
safe for the bending modes.

Writes <output>/rbc_recovery_<mesh>.csv (t, lambda, the fitted curve) and
rbc_recovery_<mesh>.png; prints t_c against eta_m / mu and against the
measured 0.10-0.13 s.
"""
import argparse
import csv
import math
import os
import time

import numpy as np

import lbmd
import lbmd.units
import oif
from oif.stretching import RBC_MODULI, RBC_RADIUS, contact_patches

HOCHMUTH_TC = (0.10, 0.13)  # s, Hochmuth, Worthy & Evans 1979
US = 1e-6  # the engine's time unit, s


def recovery(mesh="rbc374", shear_modulus=6e-6, membrane_viscosity=7e-7, force=0.03, time_step=50.0,
             node_mass=1e4, progress=None):
    """Stretch, release, fit. Returns a dict: t_c_s (fitted), t_c_model_s
    (eta_m / mu), lambda0, lambda_inf, series [(t_s, lambda)], fit (a, b of
    ln y = a - t / t_c), volume_rel and surface_rel (worst), steps,
    viscous_iterations (mean per solve)."""
    for name, value in (("shear_modulus", shear_modulus), ("membrane_viscosity", membrane_viscosity),
                        ("force", force), ("time_step", time_step), ("node_mass", node_mass)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"recovery: parameter '{name}' must be a finite number > 0, got {value!r}")
    moduli = dict(RBC_MODULI)
    moduli.update(lbmd.units.oif_moduli_from_si(shear_modulus=shear_modulus,
                                                membrane_viscosity=membrane_viscosity))
    t_c_model = membrane_viscosity / shear_modulus  # s
    box = np.array([48.0, 32.0, 32.0])
    centre = box / 2
    system = lbmd.System(box_l=list(box))
    system.time_step = time_step
    system.cell_system.skin = 0.4
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(RBC_RADIUS,) * 3, **moduli)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=list(centre), particle_mass=node_mass)
    n = ct.mesh.get_n_nodes()
    parts = system.part.by_ids(np.asarray(cell.particles.id))
    plus, minus = contact_patches(cell.particles.pos, centre, RBC_RADIUS, 1.0)

    def ratio():
        # the disc's in-plane axis ratio from its two largest principal
        # extents (the gyration tensor's eigenvalues): blind to a turn of
        # the released cell in its plane, which the free cell may make
        x = np.asarray(cell.particles.pos)
        x = x - x.mean(axis=0)
        g = np.sort(np.linalg.eigvalsh(x.T @ x / len(x)))
        return math.sqrt(g[2] / g[1])

    lambda_inf = ratio()
    steps_per_tc = t_c_model / US / time_step
    chunk = max(1, int(round(steps_per_tc / 50)))
    worst = {"volume": 0.0, "surface": 0.0}

    def note():
        worst["volume"] = max(worst["volume"], abs(cell.volume() / ct.volume0 - 1))
        worst["surface"] = max(worst["surface"], abs(cell.surface() / ct.surface0 - 1))

    # stretched to rest: at most 12 t_c, done when lambda moves less than 1e-4 per t_c / 5
    f = np.zeros((n, 3))
    f[plus, 0] = force / plus.sum()
    f[minus, 0] = -force / minus.sum()
    parts.ext_force = f
    last, steps = ratio(), 0
    for _ in range(60):
        system.integrator.run(10 * chunk)
        steps += 10 * chunk
        note()
        now = ratio()
        if abs(now - last) < 1e-4:
            break
        last = now
    lambda0 = ratio()
    counts0 = system._core.membrane_counts()
    # released: recorded every t_c / 50 for 5 t_c
    parts.ext_force = np.zeros((n, 3))
    t0 = system.time
    series = [(0.0, lambda0)]
    for _ in range(250):
        system.integrator.run(chunk)
        steps += chunk
        note()
        series.append(((system.time - t0) * US, ratio()))
        if progress is not None:
            progress(series[-1])
    counts = system._core.membrane_counts()
    solves = counts["viscous_solves"] - counts0["viscous_solves"]
    iterations = (counts["viscous_iterations"] - counts0["viscous_iterations"]) / max(1, solves)

    t = np.array([s[0] for s in series])
    lam = np.array([s[1] for s in series])
    y = (lam - lambda_inf) / (lam + lambda_inf)
    y0 = y[0]
    window = (y < 0.8 * y0) & (y > 0.03 * y0)
    if window.sum() < 5:
        raise RuntimeError(f"recovery: only {int(window.sum())} samples in the fitting window "
                           f"(lambda0 {lambda0:.4f}, lambda_inf {lambda_inf:.4f}); stretch harder")
    slope, intercept = np.polyfit(t[window], np.log(y[window]), 1)
    return {"t_c_s": -1.0 / slope, "t_c_model_s": t_c_model, "lambda0": lambda0, "lambda_inf": lambda_inf,
            "series": series, "fit": (intercept, slope), "window": (float(t[window][0]), float(t[window][-1])),
            "volume_rel": worst["volume"], "surface_rel": worst["surface"], "steps": steps,
            "viscous_iterations": iterations, "ks": moduli["ks"], "kvisc": moduli["kvisc"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", default="rbc374", choices=oif.available_meshes())
    parser.add_argument("--shear-modulus", type=float, default=6e-6, help="mu, N/m (Hochmuth et al.: 6e-6)")
    parser.add_argument("--membrane-viscosity", type=float, default=7e-7,
                        help="eta_m, N s/m (Hochmuth et al.: 6e-7 to 8e-7)")
    parser.add_argument("--force", type=float, default=0.03, help="force on each end, nN")
    parser.add_argument("--time-step", type=float, default=50.0, help="us")
    parser.add_argument("--output", default="rbc_recovery_output")
    args = parser.parse_args()
    os.makedirs(args.output, exist_ok=True)
    cpu = time.process_time()
    r = recovery(args.mesh, args.shear_modulus, args.membrane_viscosity, args.force, args.time_step)
    cpu = time.process_time() - cpu
    low, high = HOCHMUTH_TC
    print(f"{args.mesh}: mu {args.shear_modulus:.3g} N/m (ks {r['ks']:.4g}), eta_m {args.membrane_viscosity:.3g} "
          f"N s/m (kvisc {r['kvisc']:.4g}); stretched to lambda {r['lambda0']:.3f} (relaxed "
          f"{r['lambda_inf']:.3f})")
    print(f"  recovery time t_c = {r['t_c_s']:.4f} s (fit over {r['window'][0]:.3f}-{r['window'][1]:.3f} s); "
          f"eta_m / mu = {r['t_c_model_s']:.4f} s (ratio {r['t_c_s'] / r['t_c_model_s']:.3f}); "
          f"Hochmuth et al. 1979 measured {low}-{high} s")
    print(f"  worst volume change {100 * r['volume_rel']:.2f} %, surface {100 * r['surface_rel']:.2f} %; "
          f"{r['steps']} steps, {r['viscous_iterations']:.1f} CG iterations per solve, {cpu:.1f} CPU s")
    a, b = r["fit"]
    path = os.path.join(args.output, f"rbc_recovery_{args.mesh}.csv")
    with open(path, "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(["t_s", "lambda", "fit_lambda"])
        for t, lam in r["series"]:
            yf = math.exp(a + b * t)
            w.writerow([f"{t:.6g}", f"{lam:.6g}", f"{r['lambda_inf'] * (1 + yf) / (1 - yf):.6g}"])
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no chart")
        return
    t = np.array([s[0] for s in r["series"]])
    lam = np.array([s[1] for s in r["series"]])
    y = (lam - r["lambda_inf"]) / (lam + r["lambda_inf"])
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogy(t, y / y[0], "o", ms=3, label="model (rbc374, implicit membrane viscosity)")
    ax.semilogy(t, np.exp(a + b * t) / y[0], "-", label=f"fit: t_c = {r['t_c_s']:.3f} s")
    for tc, style in zip(HOCHMUTH_TC, ("--", ":")):
        ax.semilogy(t, np.exp(-t / tc), "k" + style, lw=1, label=f"exp(-t/{tc} s), Hochmuth et al. 1979")
    ax.set_ylim(1e-2, 1.2)
    ax.set_xlabel("time after release (s)")
    ax.set_ylabel("(λ − λ∞)/(λ + λ∞), normalised")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.output, f"rbc_recovery_{args.mesh}.png"), dpi=120)
    print(f"wrote {path} and the chart")


if __name__ == "__main__":
    main()
