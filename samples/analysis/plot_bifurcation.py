#!/usr/bin/env pyoif
"""The PyOIF paper's Figs 2-5 from runs of samples/cell_flow_in_bifurcation.py.

    pyoif samples/analysis/plot_bifurcation.py DIR [DIR ...] [--output DIR]
          [--window MS] [--bins N]

DIR: output folders of the sample (its scene.json, cells.csv,
branches.csv, crossings.csv, haematocrit.csv). Several folders (e.g. one
per --seed) of the same case and size are combined, as the paper combines
ten seedings per case. Writes, into --output (default: the first DIR):

- bifurcation_fig2.png: histograms of the RBCs' centre y where they cross
  x = 75 um (the middle of the daughter branches) and x = 130 um (after the
  confluence), with the walls and the island marked;
- bifurcation_fig3.png: the share of branch entries per daughter branch
  (RBCs), with the count and the binomial standard error, per run and
  combined;
- bifurcation_fig4.png: surface, diameter and rotation angle of single RBCs
  against the x of their centre, a line per pass, coloured by the branch of
  that pass;
- bifurcation_fig5.png: the haematocrit (cell volume / fluid volume) of the
  parent channel and of each branch over time (uniform runs and runs with a
  stiff population, --stiff-fraction, side by side), averaged over windows of
  --window ms (default 10 ms, as the paper, or an eighth of the run when
  that is shorter), the runs' mean.

Needs only numpy and matplotlib (Debian's python3-matplotlib); runs with
the launcher or /usr/bin/python3.
"""
import argparse
import csv
import json
import math
import os
import sys

import numpy as np


def read_table(folder, name):
    """Columns of a CSV as numpy arrays (numbers) or lists (text)."""
    path = os.path.join(folder, name)
    try:
        with open(path, newline="") as f:
            lines = list(csv.reader(f))
    except OSError as e:
        raise SystemExit(f"plot_bifurcation: cannot read {path}: {e.strerror}")
    if not lines:
        raise SystemExit(f"plot_bifurcation: {path} is empty (no header line)")
    header, rows = lines[0], lines[1:]
    columns = {}
    for i, key in enumerate(header):
        values = [r[i] if i < len(r) else "" for r in rows]
        try:
            columns[key] = np.array([float(v) for v in values])
        except ValueError:
            columns[key] = values
    return columns


def read_run(folder):
    path = os.path.join(folder, "scene.json")
    try:
        with open(path) as f:
            scene = json.load(f)
    except OSError as e:
        raise SystemExit(f"plot_bifurcation: {folder} is not an output folder of cell_flow_in_bifurcation.py "
                         f"(cannot read {path}: {e.strerror})")
    except ValueError as e:
        raise SystemExit(f"plot_bifurcation: {path} is not valid JSON: {e}")
    return dict(folder=folder, scene=scene, cells=read_table(folder, "cells.csv"),
                branches=read_table(folder, "branches.csv"), crossings=read_table(folder, "crossings.csv"),
                haematocrit=read_table(folder, "haematocrit.csv"))


def check_same_scene(runs):
    keys = ("size", "case", "height_um", "speed_mm_s")
    first = runs[0]["scene"]
    for run in runs[1:]:
        for key in keys:
            if run["scene"][key] != first[key]:
                raise SystemExit(f"plot_bifurcation: {run['folder']} has {key} = {run['scene'][key]!r}, "
                                 f"{runs[0]['folder']} {first[key]!r}: combine runs of one scene only")


def branch_counts(run):
    """(lower, upper) branch entries of RBCs (particle type 0)."""
    b = run["branches"]
    rbc = np.asarray(b.get("type", []), dtype=float) == 0
    names = np.asarray(b.get("branch", []), dtype=object)
    return int(np.sum(rbc & (names == "lower"))), int(np.sum(rbc & (names == "upper")))


def share_with_error(lower, upper):
    n = lower + upper
    if n == 0:
        return float("nan"), float("nan")
    p = lower / n
    return p, math.sqrt(p * (1.0 - p) / n)


def figure2(runs, plt, bins):
    scene = runs[0]["scene"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, plane in zip(axes, scene["planes_um"]):
        ys = [run["crossings"]["y_um"][(run["crossings"]["plane_x_um"] == plane) & (run["crossings"]["type"] == 0)]
              for run in runs if len(run["crossings"].get("y_um", []))]
        ys = np.concatenate(ys) if ys else np.zeros(0)
        lo, hi = (0.0, scene["box_width_um"])
        ax.hist(ys, bins=bins, range=(lo, hi), orientation="horizontal", color="tab:red", alpha=0.8)
        ax.set_title(f"x = {plane:g} um ({len(ys)} RBC crossings)")
        ax.set_xlabel("RBCs")
        walls = scene["parent_um"] if not (scene["split_um"] <= plane < scene["join_um"]) else None
        if walls:
            for w in walls:
                ax.axhline(w, color="k", lw=1)
        else:
            ax.axhline(1.0, color="k", lw=1)
            ax.axhline(scene["box_width_um"] - 1.0, color="k", lw=1)
            ax.axhspan(*scene["island_um"], color="0.8", label="island")
            ax.legend(loc="upper right")
    axes[0].set_ylabel("centre y (um)")
    fig.suptitle(f"Fig 2: RBC centres where they cross the planes (case {scene['case']}, {len(runs)} run(s))")
    fig.tight_layout()
    return fig


def figure3(runs, plt):
    scene = runs[0]["scene"]
    w_low, w_up = scene["branch_widths_um"]
    fig, ax = plt.subplots(figsize=(6, 4))
    total = np.zeros(2, dtype=int)
    for i, run in enumerate(runs):
        lower, upper = branch_counts(run)
        total += (lower, upper)
        if lower + upper:
            ax.plot([0, 1], [lower / (lower + upper), upper / (lower + upper)], "o", color="0.6",
                    label="single runs" if i == 0 else None)
    p, error = share_with_error(*total)
    n = int(total.sum())
    if n == 0:
        p, error = 0.0, 0.0
        ax.text(0.5, 0.5, "no RBC entered a branch yet", ha="center", transform=ax.transAxes)
    ax.bar([0, 1], [p, 1 - p], yerr=[error, error], capsize=6, color=["tab:blue", "tab:orange"], alpha=0.7,
           label=f"all runs: {n} entries")
    flow = [run["scene"].get("lower_flow_share") for run in runs]
    flow = [f for f in flow if f is not None and math.isfinite(f)]
    if flow:  # what cells following the fluid would do (before the cells came)
        ax.plot([-0.4, 0.4], [np.mean(flow)] * 2, "k--", label="share of the flow")
        ax.plot([0.6, 1.4], [1 - np.mean(flow)] * 2, "k--")
    ax.axhline(w_low / (w_low + w_up), color="k", ls=":", label="share of the width (lower)")
    ax.set_xticks([0, 1], [f"lower ({w_low:g} um)", f"upper ({w_up:g} um)"])
    ax.set_ylim(0, 1)
    ax.set_ylabel("share of RBC branch entries")
    ax.set_title(f"Fig 3: where the RBCs go (case {scene['case']})")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def figure4(runs, plt, max_cells=3):
    """Surface, diameter and rotation of single RBCs against x, a line per
    pass (a new line where the cell re-enters at x = 0)."""
    run = runs[0]
    c, b = run["cells"], run["branches"]
    branch_of = {(int(k), int(p)): name for k, p, name in zip(b.get("cell", []), b.get("pass", []),
                                                             b.get("branch", []))}
    # RBCs through each branch (the narrow one first), most passes first
    rbc_ids = sorted({int(k) for k, t in zip(c["cell"], c["type"]) if t == 0})
    passes = {k: sum(1 for (kk, _) in branch_of if kk == k) for k in rbc_ids}
    ranked = sorted(rbc_ids, key=lambda k: -passes[k])
    went = lambda k, name: any(kk == k and b == name for (kk, _), b in branch_of.items())  # noqa: E731
    chosen = [k for k in ranked if went(k, "lower")][:1]
    chosen += [k for k in ranked if went(k, "upper") and k not in chosen]
    chosen = (chosen + [k for k in ranked if k not in chosen])[:max_cells]
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    colours = {"lower": "tab:blue", "upper": "tab:orange", None: "0.6"}
    styles = ["-", "--", ":", "-."]
    branches_seen = []
    for j, k in enumerate(chosen):
        mine = c["cell"] == k
        for lap in np.unique(c["pass"][mine]):
            sel = mine & (c["pass"] == lap)
            name = branch_of.get((k, int(lap)))
            if name not in branches_seen:
                branches_seen.append(name)
            for ax, key in zip(axes, ("surface_um2", "diameter_um", "rotation_deg")):
                ax.plot(c["x_um"][sel], c[key][sel], styles[j % len(styles)], color=colours[name], lw=1.2)
    # the legend names both codes: the line style is the cell, the colour the
    # branch that pass went through
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color="k", ls=styles[j % len(styles)], lw=1.2, label=f"cell {k}")
               for j, k in enumerate(chosen)]
    handles += [Line2D([], [], color=colours[name], lw=2.5,
                       label=f"pass through the {name} branch" if name else "pass with no branch entered")
                for name in branches_seen]
    scene = run["scene"]
    for ax, name in zip(axes, ("surface (um^2)", "diameter (um)", "rotation angle (deg)")):
        ax.set_ylabel(name)
        for x in (scene["split_um"], scene["join_um"]):
            ax.axvline(x, color="k", lw=0.8, ls=":")
    axes[0].legend(handles=handles, fontsize=8, ncol=2, title="line style: cell; colour: branch", title_fontsize=8)
    axes[-1].set_xlabel("x of the cell centre (um); dotted: bifurcation and confluence")
    fig.suptitle(f"Fig 4: single RBCs through the bifurcation (case {scene['case']}, {run['folder']})")
    fig.tight_layout()
    return fig


def figure5(runs, plt, window_ms=None):
    """Haematocrit per region in windows; runs with a stiff population
    (--stiff-fraction, the paper's "mixed" suspension) in a panel of their
    own beside the uniform ones, their stiff cells' share dashed."""
    scene = runs[0]["scene"]
    t_end = min(run["haematocrit"]["time_ms"][-1] for run in runs)
    if window_ms is None:
        window_ms = 10.0 if t_end >= 80.0 else max(t_end / 8.0, 1e-9)
    edges = np.arange(0.0, t_end + 1e-9, window_ms)
    if len(edges) < 2:
        edges = np.array([0.0, t_end])
    groups = [(name, [r for r in runs if bool(r["scene"].get("stiff_rbcs")) == mixed])
              for name, mixed in (("uniform", False), ("mixed", True))]
    groups = [(name, members) for name, members in groups if members]
    fig, axes = plt.subplots(1, len(groups), figsize=(7 * len(groups), 4), sharey=True, squeeze=False)

    def windowed(members, column):
        means = []
        for run in members:
            h = run["haematocrit"]
            idx = np.clip(np.digitize(h["time_ms"], edges) - 1, 0, len(edges) - 2)
            means.append([h[column][idx == w].mean() if np.any(idx == w) else np.nan
                          for w in range(len(edges) - 1)])
        return np.nanmean(np.array(means), axis=0)

    for ax, (name, members) in zip(axes[0], groups):
        for region, colour in (("parent", "k"), ("lower", "tab:blue"), ("upper", "tab:orange")):
            label = region if region == "parent" else f"{region} branch"
            mean = windowed(members, region)
            ax.step(edges, np.append(mean, mean[-1]), where="post", color=colour, label=label)
            if name == "mixed" and region + "_stiff" in members[0]["haematocrit"]:
                mean = windowed(members, region + "_stiff")
                ax.step(edges, np.append(mean, mean[-1]), where="post", color=colour, linestyle="--",
                        label=f"{label}, stiff cells")
        ax.set_xlabel("time (ms)")
        stiff = members[0]["scene"].get("stiff_rbcs") or 0
        ax.set_title(f"{name}: {members[0]['scene']['rbcs']} RBCs" + (f", {stiff} stiff" if stiff else "")
                     + f" ({len(members)} run(s))")
        ax.legend(fontsize=8)
    axes[0][0].set_ylabel("haematocrit (cell volume / fluid volume)")
    fig.suptitle(f"Fig 5: haematocrit in {window_ms:.3g} ms windows (case {scene['case']})")
    fig.tight_layout()
    return fig


#: the damage threshold of the figure: oif.DAMAGE_AREA_STRAIN (this script
#: reads CSV files and runs without the engine)
DAMAGE_STRAIN = 0.3


def figure_damage(runs, plt):
    """Per-cell observables over time (doc/oif.md): the deformation index
    and the largest local area strain, mean over the cells of each type with
    the largest as a thin line, and each cell's damage time (above 30 % local
    area strain) at the end; None for runs written before these columns."""
    if not all("max_area_strain" in run["cells"] for run in runs):
        return None
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    names = {0: "RBCs", 1: "rare cell", 2: "stiff RBCs"}
    colours = {0: "tab:red", 1: "k", 2: "tab:purple"}
    for run in runs:
        c = run["cells"]
        for kind in sorted({int(t) for t in c["type"]}):
            sel = c["type"] == kind
            times = np.unique(c["time_ms"][sel])
            for ax, key in zip(axes[:2], ("deformation_index", "max_area_strain")):
                per_time = [c[key][sel & (c["time_ms"] == t)] for t in times]
                label = names.get(kind, f"type {kind}") if run is runs[0] else None
                ax.plot(times, [v.mean() for v in per_time], color=colours.get(kind, "0.5"), label=label)
                ax.plot(times, [v.max() for v in per_time], color=colours.get(kind, "0.5"), lw=0.6, alpha=0.6)
            # each cell's time above the threshold, from its strain at the outputs
            # (each interval counted by its start, as oif.CellDamage does)
            damage = []
            for k in sorted({int(i) for i in c["cell"][sel]}):
                mine = sel & (c["cell"] == k)
                t, strain = c["time_ms"][mine], c["max_area_strain"][mine]
                damage.append(float(np.sum(np.diff(t)[strain[:-1] > DAMAGE_STRAIN])))
            axes[2].hist(damage, bins=10, color=colours.get(kind, "0.5"), alpha=0.6,
                         label=names.get(kind, f"type {kind}") if run is runs[0] else None)
    axes[0].set_ylabel("deformation index (a - c) / (a + c)")
    axes[1].set_ylabel("largest local area strain |A / A0 - 1|")
    axes[1].axhline(DAMAGE_STRAIN, color="k", ls=":", lw=0.8)
    for ax in axes[:2]:
        ax.set_xlabel("time (ms); thick: mean over the cells, thin: the largest")
        ax.legend(fontsize=8)
    axes[2].set_xlabel("time above 30 % local area strain (ms), at the end")
    axes[2].set_ylabel("cells")
    axes[2].legend(fontsize=8)
    fig.suptitle(f"cell deformation and damage (after Gusenbauer et al. 2018), case {runs[0]['scene']['case']}")
    fig.tight_layout()
    return fig


def make_figures(folders, output=None, window_ms=None, bins=20, runs=None):
    """Read the runs in `folders` (or take them as read, `runs`), write the
    four PNGs into `output` (default: the first folder); returns their
    paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs = runs or [read_run(f) for f in folders]
    check_same_scene(runs)
    output = output or folders[0]
    os.makedirs(output, exist_ok=True)
    paths = []
    for number, fig in ((2, figure2(runs, plt, bins)), (3, figure3(runs, plt)), (4, figure4(runs, plt)),
                        (5, figure5(runs, plt, window_ms))):
        path = os.path.join(output, f"bifurcation_fig{number}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    fig = figure_damage(runs, plt)
    if fig is not None:
        path = os.path.join(output, "bifurcation_damage.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folders", nargs="+", help="output folders of cell_flow_in_bifurcation.py")
    ap.add_argument("--output", default=None, help="folder for the PNGs (default: the first folder)")
    ap.add_argument("--window", type=float, default=None, help="haematocrit averaging window in ms")
    ap.add_argument("--bins", type=int, default=20, help="histogram bins over the box width")
    args = ap.parse_args(argv)
    if args.window is not None and not (math.isfinite(args.window) and args.window > 0):
        ap.error(f"--window must be a positive number of ms, got {args.window}")
    if args.bins < 1:
        ap.error(f"--bins must be at least 1, got {args.bins}")
    runs = [read_run(f) for f in args.folders]
    for path in make_figures(args.folders, args.output, args.window, args.bins, runs=runs):
        print(path)
    lower, upper = np.sum([branch_counts(r) for r in runs], axis=0)
    p, error = share_with_error(int(lower), int(upper))
    print(f"RBC branch entries over {len(runs)} run(s): lower {lower}, upper {upper}; share lower "
          f"{p:.2f} +- {error:.2f}")


if __name__ == "__main__":
    sys.exit(main())
