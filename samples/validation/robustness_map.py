#!/usr/bin/env pyoif
"""Robustness map: dense red-cell suspensions in straight tubes, run after
run, with the published moduli, and what became of each run.

    pyoif samples/validation/robustness_map.py [--diameters 10 20 40] [--hd 0.3 0.45]
        [--ca 1 10] [--seeds 1 2 3 4 5] [--strain 200] [--kvisc 1] [--output DIR]
    pyoif samples/validation/robustness_map.py --chart-only --output DIR

Each run is the Fahraeus-Lindqvist tube of fahraeus_lindqvist.py (rbc374
cells of radius 3.91 um, the PyOIF paper's ks 0.005, kb 0.02, kal 0.007,
kag 0.7, kv 0.9, plasma 1.5 mPa s, driven by a body force set by the
capillary number Ca = eta gamma_w r / Gs of the cell-free flow), with the
cells packed by oif.pack_cells to the tube haematocrit H_T that Pries'
fit (1990) gives for the discharge haematocrit H_D asked, and the advised
hard_contact between cells and with the wall (oif.set_contacts, scaled by
Ca/2 above Ca 2 like the membranes' load). Tube length 4 D (D <= 20 um) or
1.5 D (wider; 291 cells at D 40, H_D 0.45).

A run counts as passed when it reaches --strain wall strain units with no
SimulationInstability (a membrane crossing is one: `membrane_crossing`),
and every cell's volume and surface stay within 1 % of their start. A
failed run is recorded with its cause and the strain it reached; a
packing that cannot be done with its message.

Writes <output>/robustness_map.csv (one row per run, appended as each run
ends: an interrupted map goes on where it stopped when run again with the
same --output) and robustness_map.png (the map: one square per D, H_D and
Ca, coloured by the share of seeds passed, with the first failure's
cause). The full map (3 x 2 x 2 x 5 runs of 200 strain units) takes days
on one core; testsuite/python/test_robustness_map_slow.py runs the slice
D 10, H_D 0.45, Ca 10, 2 seeds, 30 strain units.
"""
import argparse
import csv
import math
import os
import sys
import time

import numpy as np

import lbmd
import oif

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fahraeus_lindqvist as fl  # noqa: E402  (the tube, its flow and its measurement)

FIELDS = ["diameter", "hd_target", "Ca", "seed", "strain_asked", "status", "cause", "strain_reached", "n_cells",
          "H_T", "H_D", "eta_rel", "eta_rel_error", "HT_over_HD_error", "worst_volume_dev", "worst_surface_dev",
          "cpu_s", "message"]
TOLERANCE = 0.01  # volume and surface, relative


def length_ratio(diameter):
    return 4.0 if diameter <= 20.0 else 1.5


def one_run(diameter, hd, ca, seed, strain, kvisc=fl.KVISC, progress=None):
    """One run of the map: a row of FIELDS."""
    row = {"diameter": diameter, "hd_target": hd, "Ca": ca, "seed": seed, "strain_asked": strain, "cause": "",
           "message": "", "strain_reached": 0.0}
    reached = {"strain": 0.0}

    def note(r):
        reached["strain"] = r["strain"]
        if progress:
            progress(r)

    t0 = time.process_time()
    try:
        summary, _ = fl.run_tube(diameter, ca=ca, hd_target=hd, length_ratio=length_ratio(diameter), strain=strain,
                                 transient=0.5 * strain, seed=seed, kvisc=kvisc, progress=note, packing="pack",
                                 contacts="hard")
    except oif.PackingError as e:
        row.update(status="packing", cause="packing", message=str(e)[:300])
    except lbmd.SimulationInstability as e:
        row.update(status="failed", cause=getattr(e, "cause", "instability"), message=str(e)[:300],
                   strain_reached=reached["strain"])
    else:
        stopped = summary["stopped"]
        drift = max(summary["worst_volume_dev"], summary["worst_surface_dev"])
        row.update({k: summary[k] for k in ("n_cells", "H_T", "H_D", "eta_rel", "eta_rel_error",
                                            "HT_over_HD_error", "worst_volume_dev", "worst_surface_dev")})
        row["strain_reached"] = summary["strain"]
        if stopped:
            row.update(status="failed", cause=stopped.split(": ")[1][:40], message=stopped[:300],
                       strain_reached=float(stopped.split(":")[0].split()[1]))
        elif drift > TOLERANCE:
            what = "surface" if summary["worst_surface_dev"] >= summary["worst_volume_dev"] else "volume"
            row.update(status="drift", cause=f"{what} off by {100 * drift:.2f} %")
        else:
            row.update(status="passed")
    row["cpu_s"] = time.process_time() - t0
    return row


def read_rows(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def key(row):
    return (float(row["diameter"]), float(row["hd_target"]), float(row["Ca"]), int(row["seed"]),
            float(row["strain_asked"]))


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = sorted({(float(r["diameter"]), float(r["hd_target"])) for r in rows})
    cas = sorted({float(r["Ca"]) for r in rows})
    fig, ax = plt.subplots(figsize=(max(5.5, 2.4 * len(cas) + 2.5), 0.9 * len(cases) + 1.4))
    for i, (d, hd) in enumerate(cases):
        for j, ca in enumerate(cas):
            runs = [r for r in rows if (float(r["diameter"]), float(r["hd_target"]), float(r["Ca"])) == (d, hd, ca)]
            if not runs:
                continue
            passed = sum(r["status"] == "passed" for r in runs)
            share = passed / len(runs)
            colour = (1.0 - share, 0.35 + 0.5 * share, 0.35)
            ax.add_patch(plt.Rectangle((j, i), 0.96, 0.92, color=colour))
            strain = min(float(r["strain_asked"]) for r in runs)
            failed = [r for r in runs if r["status"] != "passed"]
            text = f"{passed}/{len(runs)} passed, {strain:g} strain"
            if failed:
                text += f"\n{failed[0]['cause'][:28]}"
            ax.text(j + 0.48, i + 0.46, text, ha="center", va="center", fontsize=7)
    ax.set_xlim(0, len(cas))
    ax.set_ylim(0, len(cases))
    ax.set_xticks([j + 0.48 for j in range(len(cas))], [f"Ca {c:g}" for c in cas])
    ax.set_yticks([i + 0.46 for i in range(len(cases))], [f"D {d:g} µm, H_D {hd:g}" for d, hd in cases])
    ax.set_title("robustness map: runs passed\n(no instability, every cell's volume and surface within 1 %)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--diameters", type=float, nargs="+", default=[10.0, 20.0, 40.0])
    parser.add_argument("--hd", type=float, nargs="+", default=[0.3, 0.45], help="discharge haematocrits aimed at")
    parser.add_argument("--ca", type=float, nargs="+", default=[1.0, 10.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    parser.add_argument("--strain", type=float, default=200.0, help="wall strain units per run")
    parser.add_argument("--kvisc", type=float, default=fl.KVISC, help="membrane viscosity kvisc (lattice units)")
    parser.add_argument("--chart-only", action="store_true", help="redraw the chart from the CSV")
    parser.add_argument("--output", default="output_robustness_map")
    args = parser.parse_args()
    for name in ("diameters", "hd", "ca"):
        for v in getattr(args, name):
            if not (math.isfinite(v) and v > 0):
                parser.error(f"--{name}: expected numbers > 0, got {v}")
    if any(not 0 < h < 0.6 for h in args.hd):
        parser.error(f"--hd: expected discharge haematocrits in (0, 0.6), got {args.hd}")
    if not args.strain > 0:
        parser.error(f"--strain: expected a number > 0, got {args.strain}")
    os.makedirs(args.output, exist_ok=True)
    path = os.path.join(args.output, "robustness_map.csv")
    rows = read_rows(path)
    if not args.chart_only:
        done = {key(r) for r in rows}
        for d in args.diameters:
            for hd in args.hd:
                for ca in args.ca:
                    for seed in args.seeds:
                        if (d, hd, ca, seed, args.strain) in done:
                            continue

                        def progress(r, tag=f"D {d:g} H_D {hd:g} Ca {ca:g} seed {seed}"):
                            if int(round(r["strain"] / fl.SAMPLE_STRAIN)) % 4 == 0:
                                print(f"  {tag} strain {r['strain']:6.1f}: volume dev {r['worst_volume_dev']:.4f}, "
                                      f"surface dev {r['worst_surface_dev']:.4f}", flush=True)
                        row = one_run(d, hd, ca, seed, args.strain, args.kvisc, progress)
                        print(f"D {d:g} H_D {hd:g} Ca {ca:g} seed {seed}: {row['status']}"
                              + (f" ({row['cause']} at strain {float(row['strain_reached']):.1f})"
                                 if row["status"] != "passed" else "")
                              + f"; worst volume {row.get('worst_volume_dev', '')}, surface "
                                f"{row.get('worst_surface_dev', '')}; {row['cpu_s']:.0f} CPU s", flush=True)
                        new = not os.path.exists(path)
                        with open(path, "a", newline="") as f:
                            w = csv.DictWriter(f, fieldnames=FIELDS, restval="")
                            if new:
                                w.writeheader()
                            w.writerow(row)
                        rows.append({k: str(v) for k, v in row.items()})
    if rows:
        chart(rows, os.path.join(args.output, "robustness_map.png"))
        passed = sum(r["status"] == "passed" for r in rows)
        print(f"{passed} of {len(rows)} runs passed; wrote {path} and robustness_map.png")


if __name__ == "__main__":
    main()
