"""The fluid part of accuracy_vs_cost.py: error against a reference and cost,
one row per setting, for fixed physical questions, and a measured stability
map.

- Poiseuille flow (`poiseuille`): force-driven flow between two halfway
  bounce-back walls, the setup of testsuite/python/test_lb_poiseuille.py.
  The physical question is fixed: channel height H = 1, kinematic viscosity
  nu = 1, density 1, Reynolds number Re = u_max H / nu = RE_POISEUILLE, run
  for the same physical time 40 H^2 / (pi^2 nu) (the slowest transient mode
  has decayed by e^-40). A setting is (collision, precision, fluid nodes
  across N, lattice viscosity nu_lattice): agrid = H / N and
  tau = nu_lattice agrid^2 / nu, so the peak lattice speed is
  Re nu_lattice / N and the run takes 40 N^2 / (pi^2 nu_lattice) updates.
  Error: the largest deviation of the node velocities from the analytic
  parabola with the walls midway between the last fluid and the first solid
  node, u(x) = f / (2 rho nu) (x - x0)(x1 - x), relative to its peak.
- Stokes drag (`stokes`): a sphere of radius R (bounce-back nodes of
  lbmd.shapes.Sphere) in a periodic cube of side 5 R, i.e. a simple cubic
  array at volume fraction c = 4 pi / 375 = 0.0335, driven by a uniform
  force density (test_lb_stokes_sphere_slow.py). Reference: the drag per
  sphere F = 6 pi eta R U / K(c), U the superficial (box-averaged) velocity,
  K from Sangani & Acrivos, Int. J. Multiphase Flow 8, 343 (1982), eq. for
  the simple cubic array: K = 1 - 1.7601 c^(1/3) + c - 1.5593 c^2
  + 3.9799 c^(8/3) - 3.0734 c^(10/3) (Hasimoto's 1959 series carried to
  c^(10/3); the omitted terms are ~1e-5 at this c). Re = U 2R / nu =
  RE_STOKES (creeping flow). The run stops when the drag ratio changes by
  less than 1e-4 over one diffusion time of the box, L^2 / (4 pi^2 nu) (at
  least two sound crossings), and
  the drag balances the driving force within 1e-3 (the mean flow, which
  relaxes up to ~7 times slower, is set once to its steady value when the
  flow around the sphere has settled: Stokes flow is linear).
  Error: F / F_ref - 1, F from LBBoundary.get_force().
- Stability map (`stability`): the doubly periodic shear layer of Minion &
  Brown, J. Comput. Phys. 138, 734 (1997) (u_x = U tanh(kappa (y - 1/4)) for
  y <= 1/2, U tanh(kappa (3/4 - y)) above, u_y = delta U sin(2 pi (x + 1/4)),
  kappa = 80, delta = 0.05), on a 32 x 32 x 1 lattice: the layers are
  thinner than a node, the under-resolved case that collision models are
  compared on for robustness (Coreixas, Chopard & Latt, PRE 100, 033305
  (2019)). Settings: lattice viscosity (tau_lattice = 3 nu + 1/2) against
  Mach number Ma = U / c_s, c_s = 1/sqrt(3); every run covers the same four
  convective times 4 L / U. A point is stable when no
  lbmd.SimulationInstability is raised (a density <= 0 or a speed >= c_s),
  every velocity stays finite and the kinetic energy never exceeds
  ENERGY_GROWTH times its initial value (the flow is unforced: physically it
  only decays).

Cost: `cpu_s` is the CPU time (time.process_time) of the lattice updates
alone (one thread: n_threads=1), `wall_s` their wall time, `node_updates`
the fluid nodes times the updates; what is measured between runs (reading
the velocities) is not counted. CPU time is charted: on a shared machine it
is less disturbed than wall time.
"""
import math
import os
import time

import numpy as np

import lbmd
import lbmd.lb
import lbmd.lbboundaries
import lbmd.shapes
import lbmd.stokes

COLLISIONS = ("MRT", "MRT_ESPRESSO", "TRT", "BGK")
CS = 1.0 / math.sqrt(3.0)  # lattice sound speed

RE_POISEUILLE = 0.5
RE_STOKES = 0.05
BOX_PER_RADIUS = 5
ENERGY_GROWTH = 1.05  # kinetic energy above this times its initial value: unstable

# The advice drawn on the stability map (doc/accuracy.md derives it from the
# measured map): Mach number at most ADVICE_MACH, tau_lattice at least
# ADVICE_TAU_MIN and at most ADVICE_TAU_MAX.
ADVICE_MACH = 0.2
ADVICE_TAU_MIN = 0.55
ADVICE_TAU_MAX = 3.0


def precisions_available():
    """['double'] or ['double', 'single']: whether LBFluid takes
    single_precision=True (a parameter that a later branch adds)."""
    try:
        lbmd.lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=1.0, single_precision=True)
    except (TypeError, ValueError):
        return ["double"]
    return ["double", "single"]


def _fluid(precision, **params):
    if precision == "single":
        params["single_precision"] = True
    elif precision != "double":
        raise ValueError(f"precision: expected 'double' or 'single', got {precision!r}")
    return lbmd.lb.LBFluid(n_threads=1, **params)


def _timed_run(system, updates):
    """Runs `updates` lattice updates (time_step = tau); returns (cpu s, wall s)."""
    c0, w0 = time.process_time(), time.perf_counter()
    system.integrator.run(updates)
    return time.process_time() - c0, time.perf_counter() - w0


def _cost(fluid, updates, cpu, wall):
    node_updates = int(fluid._core.n_fluid_nodes) * int(updates)
    return dict(updates=int(updates), node_updates=node_updates, cpu_s=cpu, wall_s=wall,
                cpu_ns_per_node_update=1e9 * cpu / max(node_updates, 1))


# --- Poiseuille ---------------------------------------------------------------

def poiseuille(collision, nodes_across, nu_lattice, precision="double", reynolds=RE_POISEUILLE):
    """One setting of the Poiseuille question (module docstring); a row."""
    height, nu, dens = 1.0, 1.0, 1.0
    agrid = height / nodes_across
    tau = nu_lattice * agrid ** 2 / nu
    length = height + 2 * agrid
    u_max = reynolds * nu / height
    force = 8 * dens * nu * u_max / height ** 2
    system = lbmd.System(box_l=[length, agrid, agrid])
    system.time_step = tau
    fluid = _fluid(precision, agrid=agrid, dens=dens, visc=nu, tau=tau, collision=collision,
                   ext_force_density=[0, 0, force])
    system.actors.add(fluid)
    system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
        shape=lbmd.shapes.Wall(normal=[1, 0, 0], dist=agrid)))
    system.lbboundaries.add(lbmd.lbboundaries.LBBoundary(
        shape=lbmd.shapes.Wall(normal=[-1, 0, 0], dist=-(length - agrid))))
    updates = int(math.ceil(40 * nodes_across ** 2 / (math.pi ** 2 * nu_lattice)))
    cpu, wall = _timed_run(system, updates)
    x = (np.arange(nodes_across) + 1.5) * agrid
    u = fluid[1:nodes_across + 1, 0, 0].velocity[:, 2]
    expected = force / (2 * dens * nu) * (x - agrid) * (length - agrid - x)
    err = u - expected
    u_lattice = u_max * tau / agrid
    row = dict(collision=collision, precision=precision, nodes_across=nodes_across,
               nu_lattice=nu_lattice, tau_lattice=3 * nu_lattice + 0.5, reynolds=reynolds,
               u_max_lattice=u_lattice, mach=u_lattice / CS,
               err_max=float(np.max(np.abs(err)) / np.max(expected)),
               err_l2=float(np.sqrt(np.sum(err ** 2) / np.sum(expected ** 2))))
    row.update(_cost(fluid, updates, cpu, wall))
    system.actors.clear()
    return row


# --- Stokes drag ----------------------------------------------------------------

def sangani_acrivos_k(c):
    """Drag factor K(c) of a simple cubic array of spheres at volume fraction c
    (Sangani & Acrivos 1982; its first four terms are Hasimoto's): lbmd.stokes."""
    return lbmd.stokes.periodic_drag_factor(c)


def stokes(collision, radius_nodes, nu_lattice, precision="double", reynolds=RE_STOKES,
           tolerance=1e-4, max_diffusion_times=60):
    """One setting of the Stokes drag question (module docstring); a row."""
    radius, nu, dens = 1.0, 1.0, 1.0
    agrid = radius / radius_nodes
    tau = nu_lattice * agrid ** 2 / nu
    box_nodes = BOX_PER_RADIUS * radius_nodes
    length = box_nodes * agrid
    u_target = reynolds * nu / (2 * radius)
    c = 4 * math.pi * radius ** 3 / (3 * length ** 3)
    k = sangani_acrivos_k(c)
    force = 6 * math.pi * dens * nu * radius * u_target / k / length ** 3
    system = lbmd.System(box_l=[length] * 3)
    system.time_step = tau
    fluid = _fluid(precision, agrid=agrid, dens=dens, visc=nu, tau=tau, collision=collision,
                   ext_force_density=[force, 0, 0])
    system.actors.add(fluid)
    sphere = lbmd.lbboundaries.LBBoundary(
        shape=lbmd.shapes.Sphere(center=[length / 2] * 3, radius=radius))
    system.lbboundaries.add(sphere)
    fluid[:, :, :].velocity = [u_target, 0, 0]
    solid = fluid[:, :, :].boundary > 0
    n_fluid = int(np.sum(~solid))
    # one diffusion time of the box, but at least two sound crossings (the
    # start and the rescaling below send pressure waves through the box)
    chunk = int(math.ceil(max(box_nodes ** 2 / (4 * math.pi ** 2 * nu_lattice), 2 * box_nodes / CS)))
    cpu = wall = 0.0
    updates = 0
    ratio_prev = None
    converged = rescaled = False
    for _ in range(max_diffusion_times):
        dc, dw = _timed_run(system, chunk)
        cpu, wall, updates = cpu + dc, wall + dw, updates + chunk
        velocity = fluid[:, :, :].velocity
        u = velocity[..., 0].copy()
        u[solid] = 0.0
        mean_u = float(np.mean(u))
        drag = float(sphere.get_force()[0])
        ratio = drag / (6 * math.pi * dens * nu * radius * mean_u / k)
        balance = drag / (force * n_fluid * agrid ** 3)
        if ratio_prev is not None and abs(ratio - ratio_prev) < tolerance:
            if abs(balance - 1) < 10 * tolerance:
                converged = True
                break
            if rescaled:
                ratio_prev = ratio
                continue
            # the flow around the sphere has settled but the mean flow has
            # not (its relaxation time m K / (6 pi eta R) is ~7 times the
            # box's diffusion time): Stokes flow is linear, so the steady
            # state is this field scaled by 1 / balance
            fluid[:, :, :].velocity = velocity / balance
            rescaled = True
            ratio_prev = None
            continue
        ratio_prev = ratio
    n_fluid = int(np.sum(~solid))
    row = dict(collision=collision, precision=precision, radius_nodes=radius_nodes,
               box_nodes=box_nodes, nu_lattice=nu_lattice, tau_lattice=3 * nu_lattice + 0.5,
               volume_fraction=c, reynolds=reynolds, u_lattice=mean_u * tau / agrid,
               drag_ratio=ratio, err_rel=ratio - 1.0, err_abs=abs(ratio - 1.0),
               force_balance=balance, converged=int(converged))
    row.update(_cost(fluid, updates, cpu, wall))
    system.actors.clear()
    return row


# --- stability map --------------------------------------------------------------

def stability(collision, nu_lattice, mach, precision="double", nodes=32, kappa=80.0, delta=0.05,
              convective_times=4.0, checks=20):
    """One point of the stability map (module docstring): a row."""
    u0 = mach * CS
    system = lbmd.System(box_l=[nodes, nodes, 1])
    system.time_step = 1.0
    fluid = _fluid(precision, agrid=1.0, dens=1.0, visc=nu_lattice, tau=1.0, collision=collision)
    system.actors.add(fluid)
    s = (np.arange(nodes) + 0.5) / nodes
    ux = np.where(s <= 0.5, np.tanh(kappa * (s - 0.25)), np.tanh(kappa * (0.75 - s)))
    u = np.zeros((nodes, nodes, 1, 3))
    u[..., 0] = u0 * ux[None, :, None]
    u[..., 1] = u0 * delta * np.sin(2 * np.pi * (s + 0.25))[:, None, None]
    fluid[:, :, :].velocity = u

    def energy():
        v = fluid[:, :, :].velocity
        return 0.5 * float(np.sum(fluid[:, :, :].density * np.sum(v ** 2, axis=-1)))

    e0 = energy()
    planned = int(math.ceil(convective_times * nodes / u0))
    chunk = int(math.ceil(planned / checks))
    done, cpu, wall, growth, reason = 0, 0.0, 0.0, 1.0, ""
    while done < planned and not reason:
        n = min(chunk, planned - done)
        try:
            dc, dw = _timed_run(system, n)
        except lbmd.SimulationInstability:
            reason = "SimulationInstability"
            break
        cpu, wall, done = cpu + dc, wall + dw, done + n
        e = energy()
        if not math.isfinite(e):
            reason = "non-finite"
        else:
            growth = max(growth, e / e0)
            if growth > ENERGY_GROWTH:
                reason = "energy growth"
    row = dict(collision=collision, precision=precision, nu_lattice=nu_lattice,
               tau_lattice=3 * nu_lattice + 0.5, mach=mach, u0_lattice=u0, nodes=nodes,
               updates_planned=planned, updates_done=done, stable=int(not reason), reason=reason,
               energy_growth=growth, in_advice=int(in_advice(3 * nu_lattice + 0.5, mach)))
    row.update(_cost(fluid, done, cpu, wall))
    system.actors.clear()
    return row


def in_advice(tau_lattice, mach):
    return mach <= ADVICE_MACH + 1e-12 and ADVICE_TAU_MIN - 1e-12 <= tau_lattice <= ADVICE_TAU_MAX + 1e-12


# --- the settings -----------------------------------------------------------------

def _nu_from_tau(tau):
    return (tau - 0.5) / 3.0


def settings(quick=False):
    """The cases of each question: lists of keyword dicts (without precision)."""
    if quick:
        nodes, nus_res, nus_visc = (5, 10, 20), (1.0 / 6,), (1.0 / 6, 1.0, 3.0)
        stokes_radii = {1.0 / 6: (3, 4, 5), 1.0: (3, 4, 5)}
        taus = 0.5 + 3 * np.geomspace(_nu_from_tau(0.5005), _nu_from_tau(3.0), 7)
        machs = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7)
    else:
        nodes, nus_res, nus_visc = (5, 10, 20, 40), (1.0 / 6, 1.0), (0.05, 1.0 / 6, 0.5, 1.0, 3.0)
        stokes_radii = {1.0 / 6: (3, 4, 5, 6, 8, 10), 1.0: (3, 4, 5, 6, 8)}
        taus = 0.5 + 3 * np.geomspace(_nu_from_tau(0.5005), _nu_from_tau(3.0), 14)
        machs = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
    pois = []
    for col in COLLISIONS:
        for nu in nus_res:
            pois += [dict(study="resolution", collision=col, nodes_across=n, nu_lattice=nu) for n in nodes]
        pois += [dict(study="viscosity", collision=col, nodes_across=20, nu_lattice=nu)
                 for nu in nus_visc if nu not in nus_res]
    stokes_cases = [dict(collision=col, radius_nodes=r, nu_lattice=nu) for nu, radii in stokes_radii.items()
                    for col in COLLISIONS for r in radii]
    stab = [dict(collision=col, nu_lattice=_nu_from_tau(t), mach=m) for col in COLLISIONS for t in taus
            for m in machs]
    return dict(poiseuille=pois, stokes=stokes_cases, stability=stab)


# The smallest meaningful run (the test): the wall at nu_lattice = 1 with
# MRT and MRT_ESPRESSO, one small sphere, one stable and one unstable point.
TINY = dict(poiseuille=[dict(study="viscosity", collision="MRT", nodes_across=20, nu_lattice=1.0),
                        dict(study="viscosity", collision="MRT_ESPRESSO", nodes_across=20, nu_lattice=1.0)],
            stokes=[dict(collision="MRT", radius_nodes=3, nu_lattice=1.0 / 6)],
            stability=[dict(collision="MRT", nu_lattice=1.0 / 6, mach=0.1),
                       dict(collision="BGK", nu_lattice=_nu_from_tau(0.5005), mach=0.7)])


def run(quick=False, precisions=None, cases=None, log=print):
    """Runs every case (settings(quick), or `cases` in its form) in each
    precision (default: those LBFluid offers); returns
    {'fluid_poiseuille': rows, 'fluid_stokes': rows, 'fluid_stability': rows}."""
    available = precisions_available()
    precisions = available if precisions is None else list(precisions)
    for prec in precisions:
        if prec not in available:
            raise ValueError(f"precisions: {prec!r} is not offered by this build's LBFluid "
                             f"(available: {', '.join(available)})")
    cases = settings(quick) if cases is None else cases
    out = {}
    for name, func in (("poiseuille", poiseuille), ("stokes", stokes), ("stability", stability)):
        rows = []
        t0 = time.perf_counter()
        for prec in precisions:
            for case in cases.get(name, []):
                args = {k: v for k, v in case.items() if k != "study"}
                try:
                    row = func(precision=prec, **args)
                except lbmd.SimulationInstability as e:  # Poiseuille or drag setting out of range
                    row = dict(args, precision=prec, failed=str(e).split("\n")[0])
                if "study" in case:
                    row = dict(study=case["study"], **row)
                rows.append(row)
                if name != "stability" and log:
                    log(_describe(name, row))
        if rows:
            keys = []
            for r in rows:
                keys += [k for k in r if k not in keys]
            rows = [{k: r.get(k, "") for k in keys} for r in rows]
            out[f"fluid_{name}"] = rows
        if log and name == "stability" and rows:
            n_stable = sum(r["stable"] for r in rows)
            advised = [r for r in rows if r["in_advice"]]
            broken = [f"{r['collision']} {r['precision']} tau {r['tau_lattice']:.4g} Ma {r['mach']:g}"
                      for r in advised if not r["stable"]]
            log(f"stability: {n_stable} of {len(rows)} points stable; inside the advice "
                f"({ADVICE_TAU_MIN:g} <= tau_lattice <= {ADVICE_TAU_MAX:g}, Ma <= {ADVICE_MACH:g}): "
                f"{len(advised) - len(broken)} of {len(advised)} stable" +
                (f", unstable: {'; '.join(broken)}" if broken else ""))
            for col, prec in sorted({(r["collision"], r["precision"]) for r in rows}):
                edges = []
                for mach in sorted({r["mach"] for r in rows}):
                    sel = sorted([r for r in rows if r["collision"] == col and r["precision"] == prec
                                  and r["mach"] == mach], key=lambda r: -r["tau_lattice"])
                    if not sel:
                        continue
                    edge = None  # smallest tau from which every larger one is stable
                    for r in sel:
                        if not r["stable"]:
                            break
                        edge = r["tau_lattice"]
                    edges.append(f"Ma {mach:g}: {edge:.4g}" if edge else f"Ma {mach:g}: none")
                log(f"  {col} {prec}, stable from tau_lattice " + ", ".join(edges))
        if log:
            log(f"[{name}: {time.perf_counter() - t0:.1f} s wall]")
    return out


def _describe(name, row):
    if "failed" in row and row["failed"]:
        return f"{name} {row}: FAILED {row['failed']}"
    if name == "poiseuille":
        return (f"poiseuille {row['collision']:<12} {row['precision']:<6} N={row['nodes_across']:<3} "
                f"nu_lat={row['nu_lattice']:.4g} Ma={row['mach']:.3g}: err_max={row['err_max']:.3e} "
                f"cpu={row['cpu_s']:.3f} s ({row['node_updates']:.3g} node updates)")
    return (f"stokes {row['collision']:<12} {row['precision']:<6} R={row['radius_nodes']:<3} "
            f"F/F_ref-1={row['err_rel']:+.3e} cpu={row['cpu_s']:.2f} s "
            f"({row['node_updates']:.3g} node updates, converged={row['converged']})")


# --- charts ---------------------------------------------------------------------

_COLORS = dict(MRT="tab:blue", MRT_ESPRESSO="tab:orange", TRT="tab:green", BGK="tab:red")
_MARKERS = dict(double="o", single="s")
_LINES = ("-", "--", ":", "-.")


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _num(rows, key):
    return np.array([float(r[key]) for r in rows])


def _ok(rows):
    return [r for r in rows if not r.get("failed")]


def _save(fig, outdir, name):
    path = os.path.join(outdir, name + ".png")
    fig.savefig(path, dpi=90)
    _pyplot().close(fig)
    return path


def _curves(rows, by, order):
    """Groups rows by the keys `by` (sorted), each group sorted by `order`."""
    groups = {}
    for r in rows:
        groups.setdefault(tuple(r[k] if k in ("collision", "precision") else float(r[k]) for k in by),
                          []).append(r)
    return [(key, sorted(groups[key], key=lambda r: float(r[order]))) for key in sorted(groups)]


def _integer_ticks(ax, values):
    """Plain tick labels at the measured abscissae of a log axis."""
    from matplotlib.ticker import NullFormatter, NullLocator
    ax.set_xticks(sorted({int(round(v)) for v in values}))
    ax.set_xticklabels([str(v) for v in sorted({int(round(v)) for v in values})])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


def _legend_below(fig, axes, ncol=4):
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=ncol, fontsize=7, frameon=False)


def chart_poiseuille(rows, outdir):
    plt = _pyplot()
    rows = _ok(rows)
    paths = []
    res = [r for r in rows if r["study"] == "resolution"]
    if res:
        nus = sorted({float(r["nu_lattice"]) for r in res})
        fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
        for (col, prec, nu), sel in _curves(res, ("collision", "precision", "nu_lattice"), "nodes_across"):
            kw = dict(color=_COLORS.get(col), marker=_MARKERS.get(prec, "x"), ls=_LINES[nus.index(nu) % 4],
                      label=f"{col} {prec}, nu_lattice {nu:.3g}")
            err = np.maximum(_num(sel, "err_max"), 1e-16)
            axes[0].loglog(_num(sel, "nodes_across"), err, **kw)
            axes[1].loglog(_num(sel, "cpu_s"), err, **kw)
        _integer_ticks(axes[0], _num(res, "nodes_across"))
        axes[0].set_xlabel("fluid nodes across the channel")
        axes[1].set_xlabel("CPU seconds (process_time) of the updates")
        for ax in axes:
            ax.set_ylabel("max error / peak speed")
            ax.grid(True, which="major", alpha=0.3)
        axes[0].set_title(f"Poiseuille, Re = {RE_POISEUILLE:g}, same physical time: error against resolution",
                          fontsize=8)
        axes[1].set_title("error against cost", fontsize=8)
        _legend_below(fig, axes)
        fig.tight_layout(rect=(0, 0.13, 1, 1))
        paths.append(_save(fig, outdir, "fluid_poiseuille_resolution"))
    at20 = [r for r in rows if int(float(r["nodes_across"])) == 20]
    if at20:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
        for (col, prec), sel in _curves(at20, ("collision", "precision"), "nu_lattice"):
            kw = dict(color=_COLORS.get(col), marker=_MARKERS.get(prec, "x"), label=f"{col} {prec}")
            err = np.maximum(_num(sel, "err_max"), 1e-16)
            axes[0].loglog(_num(sel, "nu_lattice"), err, **kw)
            axes[1].loglog(_num(sel, "cpu_s"), err, **kw)
            if col in ("MRT", "TRT"):
                for r, e in zip(sel, err):
                    axes[1].annotate(f"{float(r['nu_lattice']):.2g}", (float(r["cpu_s"]), e), fontsize=6,
                                     xytext=(2, 2), textcoords="offset points")
        axes[0].set_xlabel("lattice viscosity nu_lattice = (tau_lattice - 1/2) / 3")
        axes[1].set_xlabel("CPU seconds of the updates (labels: nu_lattice)")
        for ax in axes:
            ax.set_ylabel("max error / peak speed")
            ax.grid(True, which="major", alpha=0.3)
        axes[0].set_title(f"Poiseuille, 20 nodes across, Re = {RE_POISEUILLE:g}: error against lattice "
                          "viscosity", fontsize=8)
        axes[1].set_title("error against cost (larger nu_lattice: larger tau, fewer updates)", fontsize=8)
        _legend_below(fig, axes)
        fig.tight_layout(rect=(0, 0.08, 1, 1))
        paths.append(_save(fig, outdir, "fluid_poiseuille_viscosity"))
    return paths


def chart_stokes(rows, outdir):
    plt = _pyplot()
    rows = _ok(rows)
    if not rows:
        return []
    nus = sorted({float(r["nu_lattice"]) for r in rows})
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
    for (col, prec, nu), sel in _curves(rows, ("collision", "precision", "nu_lattice"), "radius_nodes"):
        kw = dict(color=_COLORS.get(col), marker=_MARKERS.get(prec, "x"), ls=_LINES[nus.index(nu) % 4],
                  label=f"{col} {prec}, nu_lattice {nu:.3g}")
        err = 100 * _num(sel, "err_rel")
        axes[0].semilogx(_num(sel, "radius_nodes"), err, **kw)
        axes[1].semilogx(_num(sel, "cpu_s"), err, **kw)
    _integer_ticks(axes[0], _num(rows, "radius_nodes"))
    axes[0].set_xlabel("sphere radius R in lattice nodes (box 5 R)")
    axes[1].set_xlabel("CPU seconds (process_time) of the updates to the steady drag")
    for ax in axes:
        ax.set_ylabel("F / F_reference - 1  (%, symlog: linear within 1 %)")
        ax.set_yscale("symlog", linthresh=1.0)
        ax.axhline(0, color="k", lw=0.6)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_title(f"Stokes drag, simple cubic array c = {float(rows[0]['volume_fraction']):.3g}, "
                      f"Re = {RE_STOKES:g} (Sangani & Acrivos)", fontsize=8)
    axes[1].set_title("error against cost", fontsize=8)
    _legend_below(fig, axes)
    fig.tight_layout(rect=(0, 0.13, 1, 1))
    return [_save(fig, outdir, "fluid_stokes")]


def chart_stability(rows, outdir):
    plt = _pyplot()
    if not rows:
        return []
    panels = sorted({(r["collision"], r["precision"]) for r in rows},
                    key=lambda p: (p[1], COLLISIONS.index(p[0]) if p[0] in COLLISIONS else 9))
    ncol = min(4, len(panels))
    nrow = int(math.ceil(len(panels) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(2.6 * ncol + 0.6, 2.7 * nrow + 0.9), squeeze=False,
                             sharex=True, sharey=True)
    taus = np.array(sorted({float(r["tau_lattice"]) for r in rows}))
    machs = np.array(sorted({float(r["mach"]) for r in rows}))
    for ax, (col, prec) in zip(axes.flat, panels):
        sel = [r for r in rows if r["collision"] == col and r["precision"] == prec]
        x = _num(sel, "tau_lattice") - 0.5
        y = _num(sel, "mach")
        st = np.array([int(float(r["stable"])) == 1 for r in sel])
        blow = np.array([r["reason"] == "SimulationInstability" for r in sel])
        other = ~st & ~blow
        ax.scatter(x[st], y[st], marker="o", color="tab:green", s=14, label="stable")
        ax.scatter(x[blow], y[blow], marker="x", color="tab:red", s=18,
                   label="SimulationInstability raised")
        ax.scatter(x[other], y[other], marker="^", color="tab:orange", s=14,
                   label=f"kinetic energy grew > {ENERGY_GROWTH:g} x (or not finite)")
        # the advised region: tau_lattice in [ADVICE_TAU_MIN, ADVICE_TAU_MAX], Ma <= ADVICE_MACH
        x0, x1 = ADVICE_TAU_MIN - 0.5, ADVICE_TAU_MAX - 0.5
        ax.plot([x0, x0, x1, x1], [0, ADVICE_MACH, ADVICE_MACH, 0], "b--", lw=1.2,
                label=f"advice: {ADVICE_TAU_MIN:g} <= tau_lattice <= {ADVICE_TAU_MAX:g}, Ma <= {ADVICE_MACH:g}")
        ax.set_xscale("log")
        ax.set_title(f"{col} ({prec})", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.set_xlim(0.6 * (taus[0] - 0.5), 1.6 * (taus[-1] - 0.5))
        ax.set_ylim(0, 1.08 * machs[-1])
    for ax in axes[-1, :]:
        ax.set_xlabel("tau_lattice - 1/2 = 3 nu_lattice")
    for ax in axes[:, 0]:
        ax.set_ylabel("Mach number U / c_s")
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    _legend_below(fig, list(axes.flat))
    fig.suptitle("Measured stability: doubly periodic shear layer (Minion & Brown, kappa 80), "
                 "32 x 32 nodes, 4 convective times", fontsize=9)
    fig.tight_layout(rect=(0, 0.07 if nrow > 1 else 0.1, 1, 1))
    return [_save(fig, outdir, "fluid_stability")]


def charts(results, outdir):
    """Writes the PNG charts of run()'s results into outdir; returns their paths."""
    os.makedirs(outdir, exist_ok=True)
    paths = []
    paths += chart_poiseuille(results.get("fluid_poiseuille", []), outdir)
    paths += chart_stokes(results.get("fluid_stokes", []), outdir)
    paths += chart_stability(results.get("fluid_stability", []), outdir)
    return paths
