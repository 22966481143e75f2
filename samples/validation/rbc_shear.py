#!/usr/bin/env pyoif
"""Validation: a red blood cell in simple shear flow, its tank-treading
frequency and inclination angle against the measurements of T. M. Fischer &
R. Korzeniewski, "Angle of inclination of tank-treading red cells:
dependence on shear rate and suspending medium", Biophys. J. 108,
1352-1360 (2015) (data/fischer2015_ttf.csv, data/fischer2015_angle.csv).

    pyoif samples/validation/rbc_shear.py [--shear-rates 158 326 624 1256 2535 4971] [--mesh rbc374]
        [--coupling 2] [--box 24 16 20] [--strain 60] [--sim-rate 0.004] [--max-scale 40] [--output DIR]

The cell: the Evans-Fung RBC of radius 3.91 um with the project's moduli
ks 0.005, kb 0.02, kal 0.007, kag 0.7, kv 0.9 (1 um, 1 us, 1e-15 kg; the
published set, oif.stretching.RBC_MODULI, as rbc_stretching.py --moduli
paper; not fitted here), disc initially flat in the
flow-vorticity plane, midway between two LB walls moving at -U and +U
(Couette flow, shear_flow.py; box 24 x 16 um, channel height 20 um, i.e.
a/H = 0.2), fluid of dynamic viscosity 1.5 mPa s (plasma), the same inside
and outside the cell (viscosity ratio 1).

Time scale. A physical shear rate of a few hundred 1/s needs ~1e6 LB steps
for the 30-60 strain units of a few tank-treading periods. The run instead
shears at a lattice rate g_sim (default 0.004 per us, Reynolds number
g_sim a^2 / nu = 0.04) with every elastic modulus multiplied by
s = g_sim / g_phys: the capillary number eta g a / Gs, the bending and
area/volume moduli relative to Gs, and the viscosity ratio are those of the
physical rate g_phys, so the dimensionless motion (f / g, angle, shape) is
too (no membrane viscosity, whose ratio would need scaling as well); time
in the results is shear strain g t. s is at most 40 (--max-scale; stable at
time step 0.1), g_sim is lowered below that.

Measurement (every 0.1 strain unit): the equivalent ellipsoid of the
enclosed volume (its section in the shear plane gives the long axis's
inclination angle theta and D = (L - B)/(L + B)), and the polar angle
phi = atan2(z, x) about the centroid of the membrane nodes that start
within 1 um of the shear plane. Relative to the long axis, psi = -(phi -
theta) grows by pi each time a node passes from one flat side to the other:
after the transient (first third of the run) each node's rate is the number
of half-turns between its first and last crossing of psi = pi/2 + k pi over
the time between them (exact for a periodic motion, whatever the swinging),
the cell's the median over the nodes; f = omega / (2 pi), reported as
f / shear rate. Tumbling: the unwrapped theta turns by more than 180 deg
after the transient (then the shape itself rotates and the node rate is the
flipping, not a tank-treading, frequency; the sample reports "tumbling").

Comparison: f / shear rate at the same shear stress tau = eta_out g (the
elastic deformation scales with tau a / Gs): each default rate is the
experiment's (28.9 mPa s, six rates 8-258 1/s) times 28.9 / 1.5. The
experiment's viscosity ratio is about 0.2 (cytoplasm ~6 mPa s against
28.9), the model's 1; doc/validation.md discusses what that means.

Writes <output>/rbc_shear.csv (per shear rate: stress, Ca, mode, f/g,
its spread over the nodes, half-turns counted, angle mean/min/max, D,
volume drift, the experiment's mean/sd/range at that stress) and
rbc_shear.png (f / g and the angle against shear stress, with the data).
The six default rates take about 130 CPU s (22 s each).
"""
import argparse
import csv
import math
import os
import time

import numpy as np

import oif
from shear_flow import DENS, ETA, VISC, add_couette_flow, couette_system, shear_plane_ellipse

HERE = os.path.dirname(os.path.abspath(__file__))
TTF_DATA = os.path.join(HERE, "data", "fischer2015_ttf.csv")
ANGLE_DATA = os.path.join(HERE, "data", "fischer2015_angle.csv")
EXPERIMENT_VISCOSITY = 28.9e-3      # Pa s, the medium of the TTF data
MODEL_VISCOSITY = ETA * 1e-3        # Pa s: lattice eta 1.5 (1e-15 kg / (um us)) is 1.5 mPa s
RBC_RADIUS = oif.stretching.RBC_RADIUS
RBC_MODULI = oif.stretching.RBC_MODULI
# the experiment's six shear rates (1/s, the means of the groups of data/fischer2015_ttf.csv)
EXPERIMENT_RATES = (8.2, 16.9, 32.4, 65.2, 131.6, 258.0)
DEFAULT_RATES = tuple(round(g * EXPERIMENT_VISCOSITY / MODEL_VISCOSITY) for g in EXPERIMENT_RATES)


def read_ttf(path=TTF_DATA):
    """(shear rates 1/s, f / shear rate) of every cell in the data file."""
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    return (np.array([float(r["shear_rate_per_s"]) for r in rows]),
            np.array([float(r["ttf_over_shear_rate"]) for r in rows]))


def read_angles(path=ANGLE_DATA):
    """{medium viscosity mPa s: (shear rates 1/s, angles deg)}."""
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    out = {}
    for r in rows:
        out.setdefault(float(r["medium_viscosity_mPa_s"]), []).append(
            (float(r["shear_rate_per_s"]), float(r["angle_deg"])))
    return {k: tuple(np.array(c) for c in zip(*v)) for k, v in out.items()}


def experiment_groups(rates, ttf):
    """The data's cells grouped by shear rate (the six rates of the
    experiment, each spread over about +-10 %): per group the mean rate,
    the shear stress (Pa) and f / g's mean, standard deviation, min, max, n."""
    order = np.argsort(rates)
    groups, current = [], [order[0]]
    for i in order[1:]:
        if rates[i] > 1.3 * rates[current[0]]:
            groups.append(current)
            current = []
        current.append(i)
    groups.append(current)
    out = []
    for g in groups:
        v = ttf[g]
        rate = float(rates[g].mean())
        out.append({"rate": rate, "stress": EXPERIMENT_VISCOSITY * rate, "mean": float(v.mean()),
                    "sd": float(v.std(ddof=1)), "min": float(v.min()), "max": float(v.max()), "n": len(g)})
    return out


def half_turn_rate(t, psi):
    """Rate (rad per time) of a growing angle psi(t) from its crossings of
    pi/2 + k pi: (number of half-turns between the first and the last
    crossing) * pi / (time between them), crossing times interpolated
    linearly; None with fewer than two crossings. psi must be unwrapped."""
    k = np.floor((psi - 0.5 * np.pi) / np.pi)
    idx = np.nonzero(np.diff(k) != 0)[0]
    if len(idx) < 2:
        return None, 0
    times = []
    for i in idx:
        level = 0.5 * np.pi + np.pi * max(k[i], k[i + 1])
        frac = (level - psi[i]) / (psi[i + 1] - psi[i])
        times.append(t[i] + frac * (t[i + 1] - t[i]))
    turns = k[idx[-1] + 1] - k[idx[0] + 1]
    if times[-1] <= times[0]:
        return None, 0
    return float(turns * np.pi / (times[-1] - times[0])), int(abs(turns))


def analyse(strain, phi, theta_deg, transient=1.0 / 3.0):
    """Tank-treading and tumbling rates from the history: strain (T,),
    node polar angles phi (T, K) in rad (atan2(z, x) about the centroid),
    long-axis angles theta_deg (T,) in (-90, 90]. Returns a dict: mode
    ("tank-treading", "tumbling" or "undetermined"), omega (membrane rate
    relative to the long axis, per unit strain, median over the nodes),
    its spread (max - min over the nodes), half-turns counted (median),
    tumbling rate (per unit strain, 0 without tumbling) and the angle's
    mean/min/max after the transient."""
    start = int(len(strain) * transient)
    t = np.asarray(strain)[start:]
    theta = np.unwrap(np.radians(np.asarray(theta_deg)), period=np.pi)[start:]
    phi = np.unwrap(np.asarray(phi), axis=0)[start:]
    psi = -(phi - theta[:, None])          # the flow turns clockwise in (x, z): psi grows
    rates, turns = [], []
    for j in range(psi.shape[1]):
        r, n = half_turn_rate(t, psi[:, j])
        if r is not None:
            rates.append(r)
            turns.append(n)
    tumble_turn = abs(theta[-1] - theta[0]) if len(theta) else 0.0
    tumbling = bool(np.ptp(theta) > np.pi) if len(theta) else False
    tumble_rate = 0.0
    if tumbling:
        r, _ = half_turn_rate(t, -theta)
        tumble_rate = r if r is not None else tumble_turn / (t[-1] - t[0])
    if tumbling:
        mode = "tumbling"
    elif len(rates) >= max(3, psi.shape[1] // 2):
        mode = "tank-treading"
    else:
        mode = "undetermined"
    ang = np.degrees(theta) if not tumbling else np.asarray(theta_deg)[start:]
    ang = ang - 180.0 * np.round(ang.mean() / 180.0)   # a flip during the transient shifts the unwrapped angle
    return {"mode": mode, "omega": float(np.median(rates)) if rates else float("nan"),
            "omega_spread": float(np.ptp(rates)) if rates else float("nan"),
            "half_turns": int(np.median(turns)) if turns else 0, "nodes_counted": len(rates),
            "tumble_rate": float(tumble_rate), "angle_mean": float(ang.mean()), "angle_min": float(ang.min()),
            "angle_max": float(ang.max())}


def run_rbc(shear_rate, mesh="rbc374", coupling=2.0, box=(24, 16, 20), sim_rate=0.004, max_scale=40.0,
            strain=60.0, sample_strain=0.1, band=1.0, node_mass=None, progress=None):
    """One RBC in Couette flow at the physical shear rate `shear_rate`
    (1/s, plasma 1.5 mPa s); returns the measured dict (see analyse) with
    the set-up and the history."""
    if not (np.isfinite(shear_rate) and shear_rate > 0):
        raise ValueError(f"run_rbc: parameter 'shear_rate' must be > 0 (1/s), got {shear_rate!r}")
    if not (np.isfinite(coupling) and coupling > 0):
        raise ValueError(f"run_rbc: parameter 'coupling' must be > 0, got {coupling!r}")
    g_phys = shear_rate * 1e-6                      # per us
    g_sim = min(sim_rate, max_scale * g_phys)
    scale = g_sim / g_phys
    lx, ly, height = box
    system = couette_system(lx, ly, height)
    lz = system.box_l[2]
    moduli = {k: v * scale for k, v in RBC_MODULI.items()}
    ct = oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(RBC_RADIUS,) * 3, normal=True, **moduli)
    gamma = coupling * ct.suggest_LBgamma(visc=VISC, dens=DENS)
    # node mass: gamma dt / m = 0.3, the friction relaxes a node's velocity within a few steps (an overdamped
    # node, as in the inertia-free membrane); heavier nodes (gamma dt / m <= 0.18) let this membrane fold
    # through itself within 20 strain units at 1256 1/s (measured, doc/validation.md)
    mass = gamma * system.time_step / 0.3 if node_mass is None else node_mass
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[lx / 2, ly / 2, lz / 2], particle_mass=mass)
    triangles = np.asarray(ct.mesh.triangle_ids)
    add_couette_flow(system, g_sim, gamma)
    pos = cell.mesh.positions()
    nodes = np.nonzero(np.abs(pos[:, 1] - pos[:, 1].mean()) < band)[0]
    v0, s0 = cell.volume(), cell.surface()
    chunk = max(1, int(round(sample_strain / g_sim / system.time_step)))
    samples = int(math.ceil(strain / (chunk * g_sim * system.time_step)))
    hist_t, hist_phi, hist_theta, hist_d, hist_vol = [], [], [], [], []
    for i in range(samples):
        system.integrator.run(chunk)
        pos = cell.mesh.positions()
        length, b, axis, centroid = shear_plane_ellipse(pos, triangles)
        theta = math.degrees(math.atan2(axis[1], axis[0]))
        theta = (theta + 90.0) % 180.0 - 90.0
        p = pos[nodes] - centroid
        hist_t.append(system.time * g_sim)
        hist_phi.append(np.arctan2(p[:, 2], p[:, 0]))
        hist_theta.append(theta)
        hist_d.append((length - b) / (length + b))
        hist_vol.append(cell.volume() / v0)
        if progress and (i + 1) % max(1, samples // 10) == 0:
            progress(shear_rate, hist_t[-1], hist_theta[-1], hist_d[-1])
    r = analyse(np.array(hist_t), np.array(hist_phi), np.array(hist_theta))
    start = len(hist_t) // 3
    r.update({"shear_rate": shear_rate, "stress_Pa": MODEL_VISCOSITY * shear_rate,
              "Ca": ETA * g_phys * RBC_RADIUS / (math.sqrt(3.0) / 4.0 * RBC_MODULI["ks"]),
              # the membrane's rate relative to the shape is a tank-treading frequency only without tumbling
              "f_over_rate": r["omega"] / (2.0 * math.pi) if r["mode"] == "tank-treading" else float("nan"),
              "f_spread": r["omega_spread"] / (2.0 * math.pi),
              "tumble_f_over_rate": r["tumble_rate"] / (2.0 * math.pi),
              "D_mean": float(np.mean(hist_d[start:])),
              "volume_rel_max_dev": float(np.max(np.abs(np.array(hist_vol) - 1.0))),
              "surface_rel": cell.surface() / s0, "scale": scale, "sim_rate": g_sim,
              "Re": g_sim * RBC_RADIUS ** 2 / VISC, "a_over_H": RBC_RADIUS / height, "gamma": gamma,
              "coupling": coupling, "mesh": mesh, "box": "x".join(f"{v:g}" for v in box), "strain": hist_t[-1],
              "nodes_tracked": len(nodes), "steps": chunk * samples,
              "history": (hist_t, hist_theta, hist_d)})
    return r


def compare(r, groups):
    """The experiment's group at the shear stress nearest to the run's (log
    scale), and where the run's f / g lies relative to it."""
    g = min(groups, key=lambda x: abs(math.log(x["stress"] / r["stress_Pa"])))
    f = r["f_over_rate"]
    return {"exp_stress_Pa": g["stress"], "exp_rate": g["rate"], "exp_mean": g["mean"], "exp_sd": g["sd"],
            "exp_min": g["min"], "exp_max": g["max"], "exp_n": g["n"],
            "ratio_to_exp_mean": f / g["mean"] if r["mode"] == "tank-treading" else float("nan"),
            "sd_from_exp_mean": (f - g["mean"]) / g["sd"] if r["mode"] == "tank-treading" else float("nan")}


def plot(rows, rates, ttf, groups, angles, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4.2))
    ax.plot(EXPERIMENT_VISCOSITY * rates, ttf, ".", color="0.6", ms=4,
            label="Fischer & Korzeniewski 2015, single cells\n(28.9 mPa s, viscosity ratio ≈ 0.2)")
    ax.errorbar([g["stress"] for g in groups], [g["mean"] for g in groups], yerr=[g["sd"] for g in groups],
                fmt="s", color="k", mfc="none", capsize=3, label="their mean ± sd")
    ax.axhline(1.0 / (4.0 * math.pi), color="0.3", ls=":", lw=1, label="sphere, any viscosity ratio: 1/(4π)")
    tt = [r for r in rows if r["mode"] == "tank-treading"]
    tb = [r for r in rows if r["mode"] == "tumbling"]
    r0 = rows[0]
    ax.errorbar([r["stress_Pa"] for r in tt], [r["f_over_rate"] for r in tt],
                yerr=[0.5 * r["f_spread"] for r in tt], fmt="o-", color="tab:red", capsize=3,
                label=f"PyOIF {r0['mesh']}, tank-treading (viscosity ratio 1)")
    if tb:
        ax.plot([r["stress_Pa"] for r in tb], [r["tumble_f_over_rate"] for r in tb], "x", color="tab:blue", ms=8,
                label="PyOIF, tumbling (flip frequency / rate)")
    ax.set_xscale("log")
    ax.set_xlabel("shear stress η_out γ̇ (Pa)")
    ax.set_ylabel("f / γ̇  (tank-treading frequency / shear rate)")
    top = ax.secondary_xaxis("top", functions=(lambda t: t / MODEL_VISCOSITY, lambda g: g * MODEL_VISCOSITY))
    top.set_xlabel("model's shear rate, plasma 1.5 mPa s (1/s); the experiment's is 28.9/1.5 times lower",
                   fontsize=8)
    ax.set_ylim(0, 0.09)
    ax.legend(fontsize=7, loc="upper right")
    markers = {10.7: "^", 23.9: "v"}
    for visc, (g, a) in sorted(angles.items()):
        bx.plot(visc * 1e-3 * g, a, markers.get(visc, "."), color="0.55", mfc="none", ms=5,
                label=f"Fischer & Korzeniewski 2015, {visc:g} mPa s")
    bx.errorbar([r["stress_Pa"] for r in tt], [r["angle_mean"] for r in tt],
                yerr=[[r["angle_mean"] - r["angle_min"] for r in tt], [r["angle_max"] - r["angle_mean"] for r in tt]],
                fmt="o-", color="tab:red", capsize=3, label="PyOIF, mean (bars: swinging range)")
    bx.set_xscale("log")
    bx.set_xlabel("shear stress η_out γ̇ (Pa)")
    bx.set_ylabel("inclination angle of the long axis (deg)")
    bx.legend(fontsize=7)
    fig.suptitle(f"RBC in shear flow ({r0['mesh']}, a/H = {r0['a_over_H']:.2f}, coupling {r0['coupling']:g} × "
                 f"suggest_LBgamma)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shear-rates", type=float, nargs="+", default=list(DEFAULT_RATES),
                        help="physical shear rates in 1/s (plasma 1.5 mPa s); default: the experiment's stresses")
    parser.add_argument("--mesh", default="rbc374", help="shipped RBC mesh: rbc374, rbc642, ...")
    parser.add_argument("--coupling", type=float, default=2.0, help="friction in units of suggest_LBgamma")
    parser.add_argument("--box", type=float, nargs=3, default=[24.0, 16.0, 20.0],
                        help="box along the flow, along the vorticity, channel height (um)")
    parser.add_argument("--strain", type=float, default=60.0, help="run length in shear strain")
    parser.add_argument("--sim-rate", type=float, default=0.004, help="lattice shear rate (per us)")
    parser.add_argument("--max-scale", type=float, default=40.0, help="largest modulus scale factor")
    parser.add_argument("--output", default="output_rbc_shear", help="folder for the CSV and PNG")
    args = parser.parse_args()
    if any(not np.isfinite(g) or g <= 0 for g in args.shear_rates):
        parser.error(f"--shear-rates: expected rates > 0 in 1/s, got {args.shear_rates}")
    if not (np.isfinite(args.coupling) and args.coupling > 0):
        parser.error(f"--coupling: expected a factor > 0, got {args.coupling}")
    if args.box[0] < 12 or args.box[1] < 10 or args.box[2] < 10:
        parser.error(f"--box: the cell (diameter 7.8 um) needs at least 12 x 10 x 10 um, got {args.box}")
    if not args.strain >= 10:
        parser.error(f"--strain: expected at least 10 strain units, got {args.strain}")
    if not (0 < args.sim_rate <= 0.02):
        parser.error(f"--sim-rate: expected 0 < rate <= 0.02 per us (Reynolds number), got {args.sim_rate}")
    if not args.max_scale >= 1:
        parser.error(f"--max-scale: expected >= 1, got {args.max_scale}")
    os.makedirs(args.output, exist_ok=True)
    rates, ttf = read_ttf()
    groups = experiment_groups(rates, ttf)
    angles = read_angles()

    def progress(rate, strain, theta, d):
        print(f"  {rate:g} 1/s: strain {strain:5.1f}  angle {theta:6.1f} deg  D {d:.3f}", flush=True)

    rows = []
    for g in args.shear_rates:
        t0 = time.process_time()
        r = run_rbc(g, mesh=args.mesh, coupling=args.coupling, box=tuple(args.box), sim_rate=args.sim_rate,
                    max_scale=args.max_scale, strain=args.strain, progress=progress)
        r["cpu_s"] = time.process_time() - t0
        r.update(compare(r, groups))
        rows.append(r)
        if r["mode"] == "tank-treading":
            what = (f"f/rate {r['f_over_rate']:.4f} (nodes {r['nodes_counted']}, spread {r['f_spread']:.4f}, "
                    f"{r['half_turns']} half-turns); experiment at {r['exp_stress_Pa']:.2f} Pa: {r['exp_mean']:.4f} "
                    f"+- {r['exp_sd']:.4f} (range {r['exp_min']:.4f}-{r['exp_max']:.4f}), ratio "
                    f"{r['ratio_to_exp_mean']:.3f}, {r['sd_from_exp_mean']:+.2f} sd")
        elif r["mode"] == "tumbling":
            what = f"flip frequency / rate {r['tumble_f_over_rate']:.4f}"
        else:
            what = "no full half-turn measured: run longer (--strain)"
        print(f"rate {g:g} 1/s (stress {r['stress_Pa']:.3f} Pa, Ca {r['Ca']:.2f}, scale {r['scale']:.1f}): "
              f"{r['mode']}: {what}; angle {r['angle_mean']:.1f} ({r['angle_min']:.1f} to {r['angle_max']:.1f}) deg, "
              f"D {r['D_mean']:.3f}, volume within {r['volume_rel_max_dev']:.4f}, {r['cpu_s']:.1f} CPU s", flush=True)
    stem = os.path.join(args.output, "rbc_shear")
    fields = ["shear_rate", "stress_Pa", "Ca", "mode", "f_over_rate", "f_spread", "half_turns", "nodes_counted",
              "nodes_tracked", "tumble_f_over_rate", "angle_mean", "angle_min", "angle_max", "D_mean",
              "volume_rel_max_dev", "surface_rel", "exp_stress_Pa", "exp_rate", "exp_mean", "exp_sd", "exp_min",
              "exp_max", "exp_n", "ratio_to_exp_mean", "sd_from_exp_mean", "scale", "sim_rate", "Re", "a_over_H",
              "coupling", "gamma", "mesh", "box", "strain", "steps", "cpu_s"]
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    plot(rows, rates, ttf, groups, angles, stem + ".png")
    print(f"total {sum(r['cpu_s'] for r in rows):.1f} CPU s")
    print("wrote", stem + ".csv", stem + ".png")


if __name__ == "__main__":
    main()
