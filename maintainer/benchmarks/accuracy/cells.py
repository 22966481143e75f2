"""The cell half of the speed-against-accuracy benchmark and of the stability
map: each study returns rows (one per setting) with an error against a
reference and a cost, and `charts` draws error against cost.

    pyoif maintainer/benchmarks/accuracy/cells.py [--quick] [--out DIR] [--only STUDY ...]

Units: the paper's lattice units (1 um, 1 us, 1e-15 kg; a force of 1 is
1 nN). The cell is the paper's red blood cell (radius 3.91 um, ks 0.005,
kb 0.02, kal 0.007, kag 0.7, kv 0.9) on every mesh: these moduli are
continuum moduli already (a triangulated spring network has the shear
modulus sqrt(3)/4 ks whatever its edge length, Dao, Li & Suresh, J. Mech.
Phys. Solids 54, 1147 (2006); dihedral bending the bending modulus
sqrt(3)/2 kb, Gompper & Kroll, J. Phys. I France 6, 1305 (1996); eqs. 5-7
scale with the triangle areas), so they stay the same on every mesh. Only
the fluid friction depends on the node density: gamma N is kept constant
(suggest_LBgamma; Busik, Slavik & Cimrak, Comput. Math. Methods Med. 2018,
7842857), which the `gamma` study measures.

Cost: CPU seconds of this process (time.process_time()) spent in the
integrator for one setting; the machine runs one rank.

Studies (each `run` row has `study` and the columns the chart needs):
- stretch: the optical-tweezers stretch of Mills et al. (Mech. Chem.
  Biosyst. 1, 169, 2004): opposite forces on two contact patches of 1 um
  radius at the rim, axial and transverse diameters at equilibrium, per mesh,
  against the finest mesh.
- flow: the cell in Poiseuille flow between two walls, after a fixed time:
  distance travelled, velocity, axial and transverse extent, per mesh,
  against the finest mesh.
- time: the same flow with rbc374 for time steps dt and lattice intervals
  tau = k dt at two stretching moduli, against dt = tau = 0.025.
- gamma: a cell driven by a body force through fluid at rest: its terminal
  velocity against the total friction gamma N, per mesh.
- stability: the largest stable dt of a free cell relaxing from a deformed
  shape, against ks, kb, kal (one varied at a time from the paper's values);
  and of the cell in Poiseuille flow (dt = tau) against gamma N.
- contacts: cells in shear flow, pushed onto each other, at rising
  haematocrit and membrane-collision strength: the deepest node of one
  cell inside another and how many nodes are inside other cells.
- hard_contacts: the same scene with the advised hard_contact, the cells
  packed by oif.pack_cells, per mesh (rbc374, rbc642, rbc1002).

Default run about 7 min, --quick about 20 s (26 Nov 2026, the 2-core
development VM). `--charts-from DIR` redraws the charts from the CSVs.
"""
import argparse
import os
import sys
import time

import numpy as np

import lbmd
import oif
from lbmd import lb, lbboundaries, shapes

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from benchmark_csv import write_rows  # noqa: E402

R_RBC = oif.stretching.RBC_RADIUS  # 3.91
R_RBC_SURFACE = 8.7709 * R_RBC ** 2  # Evans-Fung surface, 134 um^2 (oif.md)
PAPER = dict(oif.stretching.RBC_MODULI)  # ks 0.005, kb 0.02, kal 0.007, kag 0.7, kv 0.9
VISC, DENS = 1.5, 1.0
# the cell's mass, kept on every mesh (node mass CELL_MASS / N): node mass 1
# on rbc374 as in the paper's scenes
CELL_MASS = 374.0
MESHES = ("rbc162", "rbc374", "rbc642", "rbc1002", "rbc2562")


def cell_type(system, mesh, **moduli):
    k = dict(PAPER)
    k.update(moduli)
    return oif.OifCellType(*oif.mesh_files(mesh), system=system, resize=(R_RBC,) * 3, normal=True, **k)


def n_nodes(mesh):
    return int(mesh[3:]) if mesh.startswith("rbc") else None


def cpu():
    return time.process_time()


def extents(pos):
    return pos.max(axis=0) - pos.min(axis=0)


# ---------------------------------------------------------------------------
# stretch (Mills 2004)
# ---------------------------------------------------------------------------
def stretch_one(mesh, forces, **options):
    """oif.stretch_cell's rows (the equilibrium diameters at each force, nN
    on each patch; the driver's docstring has the method) with the
    benchmark's columns and the CPU time of the whole series."""
    t0 = cpu()
    rows = oif.stretch_cell(mesh, forces, radius=R_RBC, moduli=PAPER, progress=lambda r: print(
        f"stretch {mesh} F {r['force_nN']}: {r['axial_um']:.4f} {r['transverse_um']:.4f} ({r['converged']}) "
        f"after {r['steps']} steps", flush=True), **options)
    cost = cpu() - t0
    steps = rows[-1]["steps"]
    for r in rows:
        r.update(study="stretch", mesh=mesh, nodes=n_nodes(mesh), cpu_s=cost, steps=steps,
                 cpu_s_per_1000_steps=1000 * cost / steps)
    return rows


def study_stretch(quick):
    meshes = ("rbc162", "rbc374", "rbc642") if quick else MESHES
    forces = (0.05, 0.2) if quick else (0.025, 0.05, 0.1, 0.15, 0.2)
    rows = []
    for m in meshes:
        rows += stretch_one(m, forces)
    ref = {r["force_nN"]: r for r in rows if r["mesh"] == meshes[-1]}
    for r in rows:
        q = ref[r["force_nN"]]
        r["err_axial"] = abs(r["axial_um"] / q["axial_um"] - 1)
        r["err_transverse"] = abs(r["transverse_um"] / q["transverse_um"] - 1)
        r["reference"] = meshes[-1]
    return rows


# ---------------------------------------------------------------------------
# a cell in Poiseuille flow (slit between two walls, body-force driven)
# ---------------------------------------------------------------------------
FLOW_BOX = (32.0, 20.0, 20.0)
WALL = 1.0


def poiseuille_scene(mesh, dt, tau, u_max, moduli=None, gamma=None):
    lx, ly, lz = FLOW_BOX
    s = lbmd.System(box_l=list(FLOW_BOX))
    s.time_step = dt
    s.cell_system.skin = 0.4
    h = lz - 2 * WALL
    force = 8.0 * DENS * VISC * u_max / h ** 2  # u_max = f h^2 / (8 rho nu)
    lbf = lb.LBFluid(agrid=1.0, dens=DENS, visc=VISC, tau=tau, ext_force_density=[force, 0, 0])
    s.actors.add(lbf)
    walls = [shapes.Wall(normal=[0, 0, 1], dist=WALL), shapes.Wall(normal=[0, 0, -1], dist=-(lz - WALL))]
    for w in walls:
        s.lbboundaries.add(lbboundaries.LBBoundary(shape=w))
        s.constraints.add(shape=w, particle_type=10, penetrable=False)
    # start from the developed profile (node centres at k + 1/2)
    for k in range(int(lz)):
        z = k + 0.5
        if WALL < z < lz - WALL:
            u = 4 * u_max * (z - WALL) * (lz - WALL - z) / h ** 2
            lbf[:, :, k].velocity = np.tile([u, 0.0, 0.0], (int(lx), int(ly), 1))
    ct = cell_type(s, mesh, **(moduli or {}))
    # disc facing the flow, centred between the walls: it bends into a parachute
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[8.0, ly / 2, lz / 2], rotate=(0, np.pi / 2, 0),
                       particle_mass=CELL_MASS / ct.mesh.get_n_nodes())
    s.non_bonded_inter[0, 10].soft_sphere.set_params(a=1e-4, n=1.2, cutoff=0.5, offset=0.0)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=gamma if gamma is not None else ct.suggest_LBgamma(visc=VISC, dens=DENS))
    return s, lbf, ct, cell


def flow_measure(s, ct, cell, t_end, samples=10):
    """Run to t_end; return travelled distance, mean velocity over the last
    tenth, extents along the flow and across it, CPU seconds."""
    x0 = cell.get_origin()[0]
    steps = int(round(t_end / s.time_step))
    chunk = steps // samples
    t0 = cpu()
    xs = []
    for _ in range(samples):
        s.integrator.run(chunk)
        xs.append(cell.get_origin()[0])
    cost = cpu() - t0
    e = extents(cell.particles.pos)
    v = (xs[-1] - xs[-2]) / (chunk * s.time_step)
    return {"travel_um": xs[-1] - x0, "velocity": v, "axial_um": e[0], "transverse_um": max(e[1], e[2]),
            "volume_rel": cell.volume() / ct.volume0, "cpu_s": cost, "steps": steps,
            "cpu_s_per_1000_steps": 1000 * cost / steps}


def flow_errors(rows, ref):
    for r in rows:
        r["err_travel"] = abs(r["travel_um"] / ref["travel_um"] - 1)
        r["err_axial"] = abs(r["axial_um"] / ref["axial_um"] - 1)
        r["err_transverse"] = abs(r["transverse_um"] / ref["transverse_um"] - 1)
        r["err_max"] = max(r["err_travel"], r["err_axial"], r["err_transverse"])


U_FLOW = 0.15  # centre-line speed, um/us


def study_flow(quick):
    meshes = ("rbc162", "rbc374", "rbc642") if quick else MESHES
    t_end = 60.0 if quick else 200.0
    rows = []
    for m in meshes:
        s, lbf, ct, cell = poiseuille_scene(m, 0.1, 0.1, U_FLOW)
        r = {"study": "flow", "mesh": m, "nodes": n_nodes(m), "t_end": t_end,
             "gamma": ct.suggest_LBgamma(visc=VISC, dens=DENS)}
        r.update(flow_measure(s, ct, cell, t_end))
        rows.append(r)
        print(f"flow {m}: {r['travel_um']:.4f} um, v {r['velocity']:.5f}, extents {r['axial_um']:.3f} "
              f"{r['transverse_um']:.3f}, {r['cpu_s']:.1f} s", flush=True)
    flow_errors(rows, rows[-1])
    for r in rows:
        r["reference"] = meshes[-1]
    return rows


def study_time(quick):
    if quick:
        ks_values, settings, t_end = (0.005,), ((0.05, 0.05), (0.2, 0.2), (0.4, 0.4), (0.4, 0.1)), 40.0
    else:
        ks_values = (0.005, 0.05, 0.5)
        settings = [(0.025, 0.025)] + [(tau, tau / k) for tau in (0.05, 0.1, 0.2, 0.4) for k in (1, 2, 4)]
        t_end = 100.0
    rows = []
    for ks in ks_values:
        block = []
        for tau, dt in settings:
            s, lbf, ct, cell = poiseuille_scene("rbc374", dt, tau, U_FLOW, moduli={"ks": ks})
            r = {"study": "time", "mesh": "rbc374", "ks": ks, "tau": tau, "time_step": dt,
                 "steps_per_update": int(round(tau / dt)), "t_end": t_end}
            try:
                r.update(flow_measure(s, ct, cell, t_end))
                r["outcome"] = "stable"
            except lbmd.SimulationInstability as err:
                r["outcome"] = "SimulationInstability: " + str(err).split("\n")[0][:80]
            block.append(r)
            print(f"time ks {ks} tau {tau} dt {dt}: {r.get('travel_um', float('nan')):.5f} "
                  f"{r.get('axial_um', float('nan')):.4f} {r['outcome']}", flush=True)
        ref = block[0]
        flow_errors([b for b in block if b["outcome"] == "stable"], ref)
        for b in block:
            b["reference"] = f"tau {ref['tau']} dt {ref['time_step']}"
        rows += block
    return rows


# ---------------------------------------------------------------------------
# gamma against node density
# ---------------------------------------------------------------------------
def study_gamma(quick):
    """A cell pulled by a uniform body force (total 0.2 nN along the disc's
    axis) through a periodic box of fluid; the fluid carries the opposite
    force density, so that the total force is zero and a steady state
    exists. Terminal velocity against the total friction gamma N."""
    meshes = ("rbc162", "rbc642") if quick else ("rbc162", "rbc374", "rbc1002", "rbc2562")
    factors = (0.25, 1.0) if quick else (1 / 16, 0.25, 1.0, 2.0)
    t_end = 120.0 if quick else 300.0
    box, f_total = 20.0, 0.2
    rows = []
    for m in meshes:
        for fac in factors:
            s = lbmd.System(box_l=[box] * 3)
            s.time_step = 0.1
            s.cell_system.skin = 0.4
            lbf = lb.LBFluid(agrid=1.0, dens=DENS, visc=VISC, tau=0.1,
                             ext_force_density=[0, 0, -f_total / box ** 3])
            s.actors.add(lbf)
            ct = cell_type(s, m)
            n = ct.mesh.get_n_nodes()
            cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[box / 2] * 3, particle_mass=CELL_MASS / n)
            gamma = fac * ct.suggest_LBgamma(visc=VISC, dens=DENS)
            s.thermostat.set_lb(LB_fluid=lbf, gamma=gamma)
            cell.set_force([0, 0, f_total / n])
            steps = int(t_end / 0.1)
            t0 = cpu()
            s.integrator.run(steps - 200)
            z1 = cell.get_origin()[2]
            s.integrator.run(200)
            cost = cpu() - t0
            v = (cell.get_origin()[2] - z1) / 20.0
            rows.append({"study": "gamma", "mesh": m, "nodes": n, "gamma_factor": fac, "gamma": gamma,
                         "gamma_N": gamma * n, "velocity": v, "drag": f_total / v,
                         "cpu_s": cost, "steps": steps})
            print(f"gamma {m} x{fac}: gamma {gamma:.4f} gamma*N {gamma * n:.1f} v {v:.6f}", flush=True)
    return rows


# ---------------------------------------------------------------------------
# stability: largest stable dt against the moduli
# ---------------------------------------------------------------------------
def relax_trial(mesh, dt, moduli, steps=3000, mass=1.0):
    """A free cell (no fluid, Langevin friction 0.05 per node, kT 0) released
    at rest from a stretched (1.2 x), noisy (0.05 um) shape. Stable when the
    run ends without error, finite, and its elastic energy has not grown
    tenfold (a damped cell released at rest loses energy; the area forces
    are not conservative, so their energy may drift by a few per cent along
    the path, while a time-step instability grows by orders of magnitude).
    The growth goes per step, so a fixed number of steps tests each dt
    alike."""
    s = lbmd.System(box_l=[40.0] * 3)
    s.time_step = dt
    s.cell_system.skin = 0.4
    ct = cell_type(s, mesh, **moduli)
    cell = oif.OifCell(cell_type=ct, particle_type=0, origin=[20.0] * 3, particle_mass=mass)
    rng = np.random.default_rng(3)
    x = cell.particles.pos
    c = x.mean(axis=0)
    cell.particles.pos = c + (x - c) * [1.2, 1 / np.sqrt(1.2), 1 / np.sqrt(1.2)] + rng.normal(scale=0.05,
                                                                                          size=x.shape)
    s.thermostat.set_langevin(kT=0.0, gamma=0.05, seed=1)
    e0 = cell.get_energies()["total"]
    try:
        s.integrator.run(steps)
    except lbmd.SimulationInstability as err:
        return "raised", str(err).split("\n")[0][:120]
    pos = cell.particles.pos
    if not np.all(np.isfinite(pos)):
        return "nan_silent", "non-finite positions without SimulationInstability"
    e1 = cell.get_energies()["total"]
    if not np.isfinite(e1):
        return "nan_silent", "non-finite energy without SimulationInstability"
    if e1 > 10 * e0:
        return "grew_silent", (f"elastic energy grew {e0:.3g} -> {e1:.3g} in {steps} steps without "
                               f"SimulationInstability (surface {cell.surface() / ct.surface0:.3g}, volume "
                               f"{cell.volume() / ct.volume0:.3g} of relaxed)")
    return "stable", ""


def largest_stable_dt(mesh, moduli, lo=0.002, hi=20.0, iters=9, steps=3000):
    """Bisection in log dt between a stable lo and an unstable hi; returns
    (dt_stable, dt_unstable, how the first unstable trial failed)."""
    how = ""
    outcome, msg = relax_trial(mesh, hi, moduli, steps)
    if outcome == "stable":
        return hi, np.inf, "stable at the largest dt tried"
    how = f"{outcome}: {msg}"
    outcome, msg = relax_trial(mesh, lo, moduli, steps)
    if outcome != "stable":
        return 0.0, lo, f"unstable at the smallest dt tried: {outcome}: {msg}"
    for _ in range(iters):
        mid = np.sqrt(lo * hi)
        outcome, msg = relax_trial(mesh, mid, moduli, steps)
        if outcome == "stable":
            lo = mid
        else:
            hi, how = mid, f"{outcome}: {msg}"
    return lo, hi, how


def coupled_trial(mesh, dt, gamma_factor, steps=400):
    """The Poiseuille scene with dt = tau: stable when `steps` steps end
    without error, finite, with the cell's volume within 10 %."""
    s, lbf, ct, cell = poiseuille_scene(mesh, dt, dt, U_FLOW)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=gamma_factor * ct.suggest_LBgamma(visc=VISC, dens=DENS))
    try:
        s.integrator.run(steps)
    except lbmd.SimulationInstability as err:
        return "raised", str(err).split("\n")[0][:120]
    v = cell.volume() / ct.volume0
    if not np.all(np.isfinite(cell.particles.pos)) or not abs(v - 1) < 0.1:
        return "silent", f"volume {v:.3g} of relaxed, no SimulationInstability"
    return "stable", ""


def study_stability(quick):
    factors = (1, 100) if quick else (1, 10, 100, 1000)
    meshes = ("rbc374",) if quick else ("rbc374", "rbc1002")
    rows = []
    for mesh in meshes:
        paper_point = None
        for name in ("ks", "kb", "kal"):
            for fac in factors:
                moduli = {name: PAPER[name] * fac}
                t0 = cpu()
                if fac == 1 and paper_point is not None:
                    lo, hi, how = paper_point  # the paper's moduli: the same run for each name
                else:
                    lo, hi, how = largest_stable_dt(mesh, moduli, iters=5 if quick else 8,
                                                    steps=600 if quick else 3000)
                if fac == 1:
                    paper_point = lo, hi, how
                rows.append({"study": "stability", "scene": "free cell", "mesh": mesh, "modulus": name,
                             "value": PAPER[name] * fac, "factor": fac, "mass": 1.0, "dt_stable": lo,
                             "dt_unstable": hi, "failure": how, "cpu_s": cpu() - t0})
                print(f"stability {mesh} {name}={PAPER[name] * fac:g}: stable {lo:.4g} unstable {hi:.4g} "
                      f"({how[:90]})", flush=True)
    # in fluid: dt = tau against the total friction gamma N (node mass CELL_MASS / N)
    meshes = ("rbc374",) if quick else ("rbc162", "rbc642", "rbc2562")
    gfactors = (1.0,) if quick else (0.25, 1.0, 4.0)
    for mesh in meshes:
        for g in gfactors:
            t0 = cpu()
            lo, hi, how = 0.05, 2.0, ""
            for _ in range(4 if quick else 6):
                mid = np.sqrt(lo * hi)
                outcome, msg = coupled_trial(mesh, mid, g)
                if outcome == "stable":
                    lo = mid
                else:
                    hi, how = mid, f"{outcome}: {msg}"
            s = lbmd.System(box_l=[20.0] * 3)
            ct = cell_type(s, mesh)
            gamma = g * ct.suggest_LBgamma(visc=VISC, dens=DENS)
            n = ct.mesh.get_n_nodes()
            rows.append({"study": "stability", "scene": "in flow, dt = tau", "mesh": mesh, "modulus": "gamma_N",
                         "value": gamma * n, "factor": g, "mass": CELL_MASS / n, "dt_stable": lo,
                         "dt_unstable": hi, "failure": how, "cpu_s": cpu() - t0,
                         "gamma_dt_over_m_at_limit": gamma * hi / (CELL_MASS / n),
                         "gammaN_dt_over_rho_S_at_limit": gamma * n * hi / (DENS * ct.surface0)})
            print(f"stability in flow {mesh} gamma x{g} (gamma N {gamma * n:.0f}): stable {lo:.4g} unstable {hi:.4g} "
                  f"({how[:90]})", flush=True)
    return rows


# ---------------------------------------------------------------------------
# contacts: interpenetration in shear flow
# ---------------------------------------------------------------------------
def solid_angle_inside(points, tri_pos):
    """Winding number of each point with respect to a closed triangulated
    surface (Van Oosterom & Strackee, IEEE Trans. Biomed. Eng. 30, 125
    (1983), solid angle of a triangle): |w| about 1 inside, 0 outside."""
    a = tri_pos[None, :, 0, :] - points[:, None, :]
    b = tri_pos[None, :, 1, :] - points[:, None, :]
    c = tri_pos[None, :, 2, :] - points[:, None, :]
    la, lb_, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
    det = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
    den = la * lb_ * lc + np.einsum("ijk,ijk->ij", a, b) * lc + np.einsum("ijk,ijk->ij", a, c) * lb_ \
        + np.einsum("ijk,ijk->ij", b, c) * la
    return np.abs(np.sum(2 * np.arctan2(det, den), axis=1) / (4 * np.pi))


def interpenetration(cells, box_l, periodic, reach=2.0):
    """Deepest node of one cell inside another (distance to the other's
    nearest node, um), how many nodes are inside other cells, and how many
    cells have more than 10 % of their nodes inside one other cell.
    Only nodes within `reach` of the other cell's nodes are tested (a node
    inside an RBC is at most half its thickness, 1.3 um, plus an edge from
    its nearest node)."""
    from scipy.spatial import cKDTree
    pos = [c.particles.pos for c in cells]
    tris = cells[0].cell_type.mesh.triangle_ids
    cent = [p.mean(axis=0) for p in pos]
    trees = [cKDTree(p) for p in pos]
    box = np.asarray(box_l)
    deepest, inside_total, crossed = 0.0, 0, 0
    for i, pi in enumerate(pos):
        worst_share = 0.0
        for j, pj in enumerate(pos):
            if i == j:
                continue
            shift = cent[i] - cent[j]
            shift = np.where(periodic, box * np.round(shift / box), 0.0)
            q = pj + shift  # the image of cell j nearest to cell i
            lo, hi = q.min(axis=0), q.max(axis=0)
            cand = np.all((pi > lo) & (pi < hi), axis=1)
            if not cand.any():
                continue
            dist, _ = trees[j].query(pi[cand] - shift, distance_upper_bound=reach)
            near = np.isfinite(dist)
            if not near.any():
                continue
            pts, dist = pi[cand][near], dist[near]
            ins = solid_angle_inside(pts, q[tris]) > 0.5
            if not ins.any():
                continue
            deepest = max(deepest, float(dist[ins].max()))
            inside_total += int(ins.sum())
            worst_share = max(worst_share, ins.sum() / len(pi))
        crossed += worst_share > 0.1
    return deepest, inside_total, crossed


CONTACT_BOX = (24.0, 24.0, 20.0)


def place_lattice(s, ct, layers, rng, tilt=0.04):
    """Cells on a lattice: 3 along x (8 apart: 0.2 um between rims), 2 rows
    along z (rims 1.3 um apart, 0.5 um from the walls; the upper row
    shifted by half a cell), `layers` along y (24/layers apart; the cells
    2.6 um thick: at 8 layers 0.4 um apart), each disc in the x-z plane
    (the shear plane) at a random angle in it and tilted out of it by up to
    `tilt` rad (0.16 um at the rim: never enough to close a gap)."""
    lx, ly, lz = CONTACT_BOX
    cells = []
    for j in range(layers):
        for k, zc in enumerate((WALL + 0.5 + R_RBC, lz - WALL - 0.5 - R_RBC)):
            for i in range(3):
                origin = [4.0 + 8.0 * i + 4.0 * k, (j + 0.5) * ly / layers, zc]
                rot = (np.pi / 2 + rng.uniform(-tilt, tilt), rng.uniform(0, 2 * np.pi), rng.uniform(-tilt, tilt))
                cells.append(oif.OifCell(cell_type=ct, particle_type=0, origin=origin, rotate=rot))
    return cells


def contact_walls():
    """The contacts scene's walls: normal to z, WALL from each face."""
    lz = CONTACT_BOX[2]
    return [shapes.Wall(normal=[0, 0, 1], dist=WALL), shapes.Wall(normal=[0, 0, -1], dist=-(lz - WALL))]


def couette_fluid(s, walls, u_wall):
    """The contacts scene's fluid: the walls moving at -+u_wall along x (as
    lattice boundaries and as constraints of particle type 10), the fluid
    started in the linear Couette profile; returns the LBFluid."""
    lx, ly, lz = CONTACT_BOX
    lbf = lb.LBFluid(agrid=1.0, dens=DENS, visc=VISC, tau=0.1)
    s.actors.add(lbf)
    s.lbboundaries.add(lbboundaries.LBBoundary(shape=walls[0], velocity=[-u_wall, 0, 0]))
    s.lbboundaries.add(lbboundaries.LBBoundary(shape=walls[1], velocity=[u_wall, 0, 0]))
    for w in walls:
        s.constraints.add(shape=w, particle_type=10, penetrable=False)
    for k in range(int(lz)):
        z = k + 0.5
        if WALL < z < lz - WALL:
            u = u_wall * (2 * (z - WALL) / (lz - 2 * WALL) - 1)
            lbf[:, :, k].velocity = np.tile([u, 0.0, 0.0], (int(lx), int(ly), 1))
    return lbf


def study_contacts(quick, layers_list=None, strengths=None, series=None, t_end=None):
    """Cells pressed together in shear flow: Couette flow (walls moving at
    +-u_wall, shear rate 0.011/us), rbc374 cells on a lattice of 1, 2, 4, 6
    or 8 layers (haematocrit 0.05 to 0.42), each node pushed towards the
    bottom wall (total `push` nN per cell, a centrifuge-like load that
    piles the upper row on the lower one); membrane collision
    V = a/(1+e^(n d)), cutoff 0.5: the paper's n 1.2 with a varied, 0
    included (no contact force: shows what the measure sees when nothing
    keeps the membranes apart), and at the larger load a steeper n 10 (the
    barrier a (1/2 - 1/(1+e^(n cutoff))) and the largest pair force a n/4
    both grow with n) and a longer cutoff 1.0 (longer than rbc374's edges,
    0.64 um on average, 0.85 um at most).
    Shear rate 0.011/us. Samples the deepest interpenetration every tenth of
    the run."""
    layers_list = layers_list or ((8,) if quick else (1, 4, 8))
    strengths = strengths or ((0.0, 1e-1) if quick else (0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0))
    # (push nN per cell, steepness n, cutoff, strengths a or None for `strengths`)
    series = series or (((2.0, 1.2, 0.5, None),) if quick else
                        ((0.5, 1.2, 0.5, None), (2.0, 1.2, 0.5, None), (2.0, 10.0, 0.5, (0.01, 0.1, 1.0)),
                         (2.0, 1.2, 1.0, (0.1, 1.0))))
    t_end = t_end or (100.0 if quick else 200.0)
    lx, ly, lz = CONTACT_BOX
    u_wall = 0.1
    rows = []
    for push, steep, cutoff, own in series:
        for layers in layers_list:
            for a in own or strengths:
                s = lbmd.System(box_l=[lx, ly, lz])
                s.time_step = 0.1
                s.cell_system.skin = 0.4
                walls = contact_walls()
                lbf = couette_fluid(s, walls, u_wall)
                ct = cell_type(s, "rbc374")
                cells = place_lattice(s, ct, layers, np.random.default_rng(layers))
                n = ct.mesh.get_n_nodes()
                for c in cells:
                    c.set_force([0.0, 0.0, -push / n])
                h_real = len(cells) * ct.volume0 / (lx * ly * (lz - 2 * WALL))
                s.non_bonded_inter[0, 10].soft_sphere.set_params(a=1e-4, n=1.2, cutoff=0.5, offset=0.0)
                s.non_bonded_inter[0, 0].membrane_collision.set_params(a=a, n=steep, cutoff=cutoff, offset=0.0)
                # the interpenetration is what is measured here: the engine's
                # crossing check (membrane_crossing) would stop the run at the
                # first crossed pair
                s.cell_checks = False
                s.thermostat.set_lb(LB_fluid=lbf, gamma=ct.suggest_LBgamma(visc=VISC, dens=DENS))
                steps = int(t_end / 0.1)
                deepest, inside_max, crossed_max, outcome = 0.0, 0, 0, "ran"
                vol_drift, cost, first_inside = 0.0, 0.0, None
                for sample in range(10):
                    t0 = cpu()
                    try:
                        s.integrator.run(steps // 10)
                    except lbmd.SimulationInstability as err:
                        outcome = "SimulationInstability: " + str(err).split("\n")[0][:100]
                        cost += cpu() - t0
                        break
                    cost += cpu() - t0
                    d, ins, cr = interpenetration(cells, s.box_l, np.array([True, True, False]))
                    if ins and first_inside is None:
                        first_inside = (sample + 1) * (steps // 10)
                    deepest, inside_max, crossed_max = max(deepest, d), max(inside_max, ins), max(crossed_max, cr)
                    vol_drift = max(vol_drift, max(abs(c.volume() / ct.volume0 - 1) for c in cells))
                rows.append({"study": "contacts", "haematocrit": h_real, "layers": layers, "cells": len(cells),
                             "push_nN_per_cell": push, "a": a, "n": steep, "cutoff": cutoff,
                             "max_pair_force": a * steep / 4,
                             "barrier": a * (0.5 - 1 / (1 + np.exp(steep * cutoff))), "shear_rate": 2 * u_wall / (lz - 2 * WALL),
                             "t_end": t_end, "deepest_um": deepest, "nodes_inside_max": inside_max,
                             "cells_crossed_max": crossed_max, "first_inside_step": first_inside or -1,
                             "volume_drift_max": vol_drift, "outcome": outcome, "cpu_s": cost})
                print(f"contacts push {push} n {steep} cutoff {cutoff} H {h_real:.3f} ({len(cells)} cells) a {a:g}: deepest {deepest:.3f} um, "
                      f"nodes inside {inside_max}, crossed {crossed_max}, {outcome[:60]}, {cost:.1f} s", flush=True)
    return rows


def study_hard_contacts(quick, meshes=None, targets=None, push=2.0, t_end=None, seed=1):
    """The same Couette scene with the advised hard_contact
    (oif.contact_settings: a 0.01, n 1, cutoff 0.5, offset the mesh's
    covering radius; walls offset 0) instead of membrane_collision, the
    cells placed by oif.pack_cells (flat discs, rotation_axis z) at each
    target haematocrit, every node pushed towards the bottom wall (`push` nN
    per cell), per mesh. The engine's crossing check stays on: a crossing or
    a contact_overrun is the outcome."""
    meshes = meshes or (("rbc374",) if quick else ("rbc374", "rbc642", "rbc1002"))
    targets = targets or ((0.3,) if quick else (0.05, 0.15, 0.3, 0.45))
    t_end = t_end or (50.0 if quick else 200.0)
    lx, ly, lz = CONTACT_BOX
    u_wall = 0.1
    rows = []
    for mesh in meshes:
        for target in targets:
            s = lbmd.System(box_l=[lx, ly, lz])
            s.periodicity = [True, True, False]
            s.time_step = 0.1
            s.cell_system.skin = 0.4
            walls = contact_walls()
            ct = cell_type(s, mesh)
            t0 = cpu()
            try:
                cells = oif.pack_cells(s, ct, haematocrit=target, boundaries=walls, rotation_axis=(0, 0, 1),
                                       seed=seed, max_iterations=6000)
            except oif.PackingError as err:
                rows.append({"study": "hard_contacts", "mesh": mesh, "nodes": n_nodes(mesh), "target": target,
                             "haematocrit": float("nan"), "outcome": "not packed: " + str(err)[:80]})
                print(f"hard contacts {mesh} H {target}: not packed", flush=True)
                continue
            pack_s = cpu() - t0
            lbf = couette_fluid(s, walls, u_wall)
            settings = oif.set_contacts(s, ct, particle_types=0, wall_types=10)
            n = ct.mesh.get_n_nodes()
            for c in cells:
                c.set_force([0.0, 0.0, -push / n])
            s.thermostat.set_lb(LB_fluid=lbf, gamma=ct.suggest_LBgamma(visc=VISC, dens=DENS))
            h_real = cells.report["haematocrit"]
            steps = int(t_end / 0.1)
            deepest, inside_max, crossed_max, outcome, cost = 0.0, 0, 0, "ran", 0.0
            vol_drift = surf_drift = 0.0
            for sample in range(10):
                t0 = cpu()
                try:
                    s.integrator.run(steps // 10)
                except lbmd.SimulationInstability as err:
                    outcome = f"{err.cause}: " + str(err).split("\n")[0][:100]
                    cost += cpu() - t0
                    break
                cost += cpu() - t0
                d, ins, cr = interpenetration(cells, s.box_l, np.array([True, True, False]))
                deepest, inside_max, crossed_max = max(deepest, d), max(inside_max, ins), max(crossed_max, cr)
                vol_drift = max(vol_drift, max(abs(c.volume() / ct.volume0 - 1) for c in cells))
                surf_drift = max(surf_drift, max(abs(c.surface() / ct.surface0 - 1) for c in cells))
            timings = s.integrator.timings() if hasattr(s.integrator, "timings") else {}
            rows.append({"study": "hard_contacts", "mesh": mesh, "nodes": n_nodes(mesh), "target": target,
                         "haematocrit": h_real, "cells": len(cells), "push_nN_per_cell": push,
                         "a": settings["cell"]["a"], "n": settings["cell"]["n"], "cutoff": settings["cell"]["cutoff"],
                         "offset": settings["cell"]["offset"], "t_end": t_end, "deepest_um": deepest,
                         "nodes_inside_max": inside_max, "cells_crossed_max": crossed_max,
                         "volume_drift_max": vol_drift, "surface_drift_max": surf_drift, "outcome": outcome,
                         "pack_cpu_s": pack_s, "cpu_s": cost,
                         "nonbonded_s": timings.get("non_bonded", float("nan")),
                         "membrane_s": timings.get("membrane", float("nan"))})
            print(f"hard contacts {mesh} H {h_real:.3f} ({len(cells)} cells): deepest {deepest:.3f} um, nodes inside "
                  f"{inside_max}, volume drift {vol_drift:.4f}, surface {surf_drift:.4f}, {outcome[:70]}, "
                  f"{cost:.1f} s (packing {pack_s:.1f} s)", flush=True)
    return rows


STUDIES = {"stretch": study_stretch, "flow": study_flow, "time": study_time, "gamma": study_gamma,
           "stability": study_stability, "contacts": study_contacts, "hard_contacts": study_hard_contacts}


def same_columns(rows):
    """Every row with every column (CSV writers take the first row's keys):
    a column a row lacks (e.g. the errors of a run that blew up) is NaN."""
    keys = list(dict.fromkeys(k for r in rows for k in r))
    return [{k: r.get(k, float("nan")) for k in keys} for r in rows]


def run(quick=False, only=None):
    """{study name: rows}."""
    out = {}
    for name, fn in STUDIES.items():
        if only and name not in only:
            continue
        t0 = time.time()
        out["cells_" + name] = same_columns(fn(quick))
        print(f"[cells] {name}: {time.time() - t0:.1f} s wall", flush=True)
    return out


# ---------------------------------------------------------------------------
# charts
# ---------------------------------------------------------------------------
def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


#: the contact advice of lbmd/settings_check.py, and rbc374's longest edge
#: at the paper's size (0.85 um)
CONTACT_A_MIN = 0.1
RBC374_LONGEST_EDGE = 0.85


def charts(results, outdir, dpi=90):
    """One PNG per study present in results; returns the paths written."""
    plt = _plt()
    os.makedirs(outdir, exist_ok=True)
    written = []

    def save(fig, name):
        path = os.path.join(outdir, name + ".png")
        fig.tight_layout()
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        written.append(path)

    def floor(x):
        return np.maximum(np.asarray(x, float), 1e-6)

    rows = results.get("cells_stretch")
    if rows:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8))
        meshes = list(dict.fromkeys(r["mesh"] for r in rows))
        for m in meshes:
            rr = [r for r in rows if r["mesh"] == m]
            ax1.plot([r["force_nN"] * 1e3 for r in rr], [r["axial_um"] for r in rr], "o-", ms=3, label=m)
            ax1.plot([r["force_nN"] * 1e3 for r in rr], [r["transverse_um"] for r in rr], "s--", ms=3,
                     color=ax1.lines[-1].get_color())
        ax1.set_xlabel("stretching force (pN)")
        ax1.set_ylabel("diameter (um): axial o-, transverse s--")
        ax1.legend(fontsize=7)
        for key, mk in (("err_axial", "o-"), ("err_transverse", "s--")):
            pts = [(r0["cpu_s"], max(r[key] for r in rows if r["mesh"] == m), int(r0["nodes"]))
                   for m in meshes[:-1] for r0 in [next(r for r in rows if r["mesh"] == m)]]
            ax2.loglog([p[0] for p in pts], floor([p[1] for p in pts]), mk, ms=4, label=key[4:])
            for p in pts:
                ax2.annotate(str(p[2]), (p[0], max(p[1], 1e-6)), fontsize=7)
        ax2.set_xlabel("CPU s to equilibrium, all forces (no fluid)")
        ax2.set_ylabel(f"max rel. error over forces vs {meshes[-1]}")
        ax2.set_title("stretched RBC: error vs cost (labels: nodes)", fontsize=9)
        ax2.legend(fontsize=7)
        save(fig, "cells_stretch")

    rows = results.get("cells_flow")
    if rows:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        for key, mk in (("err_travel", "o-"), ("err_axial", "s-"), ("err_transverse", "^-")):
            rr = rows[:-1]
            ax.loglog([r["cpu_s"] for r in rr], floor([r[key] for r in rr]), mk, ms=4, label=key[4:])
        for r in rows[:-1]:
            ax.annotate(str(int(r["nodes"])), (r["cpu_s"], max(r["err_max"], 1e-6)), fontsize=8)
        ax.set_xlabel(f"CPU s for {rows[0]['t_end']:g} us of flow")
        ax.set_ylabel(f"rel. error vs {rows[-1]['mesh']}")
        ax.set_title("RBC in Poiseuille flow: mesh resolution", fontsize=9)
        ax.legend(fontsize=7)
        save(fig, "cells_flow")

    rows = results.get("cells_time")
    if rows:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        for ks in sorted(set(r["ks"] for r in rows)):
            rr = [r for r in rows if r["ks"] == ks and r["outcome"] == "stable" and "err_max" in r][1:]
            ax.loglog([r["cpu_s"] for r in rr], floor([r["err_max"] for r in rr]), "o", label=f"ks {ks:g}")
            for r in rr:
                ax.annotate(f"{r['tau']:g}/{r['time_step']:g}", (r["cpu_s"], max(r["err_max"], 1e-6)), fontsize=6)
        ax.set_xlabel("CPU s")
        ax.set_ylabel("max rel. error (travel, extents)")
        ax.set_title("time step: labels tau/dt, vs tau = dt = 0.025", fontsize=9)
        ax.legend(fontsize=7)
        save(fig, "cells_time")

    rows = results.get("cells_gamma")
    if rows:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.8))
        for m in dict.fromkeys(r["mesh"] for r in rows):
            rr = [r for r in rows if r["mesh"] == m]
            ax1.semilogx([r["gamma_N"] for r in rr], [r["velocity"] for r in rr], "o-", ms=4, label=m)
            ax2.semilogx([r["gamma"] for r in rr], [r["velocity"] for r in rr], "o-", ms=4, label=m)
        ax1.set_xlabel("total friction gamma N")
        ax2.set_xlabel("friction per node gamma")
        ax1.set_ylabel("terminal velocity (um/us)")
        ax1.legend(fontsize=7)
        ax1.set_title("one curve: gamma N is what counts", fontsize=9)
        save(fig, "cells_gamma")

    rows = results.get("cells_stability")
    if rows:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10, 3.9))
        free = [r for r in rows if r.get("scene", "free cell") == "free cell"]
        for mesh, ls in zip(dict.fromkeys(r["mesh"] for r in free), ("-", ":")):
            for name, mk in (("ks", "o"), ("kb", "s"), ("kal", "^")):
                rr = [r for r in free if r["mesh"] == mesh and r["modulus"] == name and r["dt_stable"] > 0]
                if rr:
                    ax.loglog([r["factor"] for r in rr], [r["dt_stable"] for r in rr], mk + ls, ms=4,
                              label=f"{name} ({mesh})")
        f = np.logspace(0, 3, 20)
        ax.fill_between(f, 1e-3, 0.05 / f, color="g", alpha=0.12, label="advice (kb, kal): dt < 0.05 k_paper/k")
        ax.set_xlabel("modulus / paper's value (others at the paper's values)")
        ax.set_ylabel("largest stable time step")
        ax.set_title("free cell, node mass 1, no fluid", fontsize=9)
        ax.legend(fontsize=6)
        flow = [r for r in rows if r.get("scene") == "in flow, dt = tau"]
        for mesh in dict.fromkeys(r["mesh"] for r in flow):
            rr = [r for r in flow if r["mesh"] == mesh]
            ax2.loglog([r["value"] for r in rr], [r["dt_stable"] for r in rr], "o-", ms=4, label=mesh)
        if flow:
            g = np.logspace(np.log10(100), np.log10(3000), 20)
            ax2.fill_between(g, 0.02, np.minimum(R_RBC_SURFACE / g, 1.0), color="g", alpha=0.12,
                             label="advice dt < rho agrid S / (gamma N)")
        ax2.set_xlabel("total friction gamma N")
        ax2.set_ylabel("largest stable dt = tau")
        ax2.set_title("cell in Poiseuille flow, node mass 374/N", fontsize=9)
        ax2.legend(fontsize=6)
        save(fig, "cells_stability")

    rows = results.get("cells_contacts")
    if rows:
        combos = list(dict.fromkeys((r["push_nN_per_cell"], r["n"], r["cutoff"]) for r in rows))
        fig, axes = plt.subplots(1, len(combos), figsize=(3.9 * len(combos) + 1, 3.8), squeeze=False,
                                 constrained_layout=True)
        vmax = max(0.5, max(r["deepest_um"] for r in rows))
        for ax, (push, steep, cut) in zip(axes[0], combos):
            rr = [r for r in rows if (r["push_nN_per_cell"], r["n"], r["cutoff"]) == (push, steep, cut)]
            h = [r["haematocrit"] for r in rr]
            a = [max(r["a"], 1e-5) for r in rr]
            sc = ax.scatter(h, a, c=[r["deepest_um"] for r in rr], s=90, cmap="viridis_r", vmin=0, vmax=vmax)
            for r in rr:
                ax.annotate(str(int(r["nodes_inside_max"])), (r["haematocrit"], max(r["a"], 1e-5)), fontsize=6,
                            xytext=(6, 4), textcoords="offset points")
                if r["cells_crossed_max"] > 0 or r["outcome"] != "ran":
                    ax.scatter([r["haematocrit"]], [max(r["a"], 1e-5)], s=200, facecolors="none", edgecolors="r")
            # the region system.check_settings() advises (lbmd/settings_check.py):
            # reach longer than rbc374's longest edge and a >= CONTACT_A_MIN
            if cut > RBC374_LONGEST_EDGE:
                ax.axhspan(CONTACT_A_MIN, 3, color="tab:green", alpha=0.12, zorder=0,
                           label=f"advised: a >= {CONTACT_A_MIN:g}, cutoff > edge")
                ax.legend(fontsize=6, loc="lower right")
            else:
                ax.text(0.25, 2e-5, f"outside the advice:\ncutoff {cut:g} < longest edge "
                        f"{RBC374_LONGEST_EDGE:g}", fontsize=7, ha="center", color="0.3")
            ax.set_yscale("log")
            ax.set_xlabel("haematocrit")
            ax.set_xlim(0, 0.5)
            ax.set_ylim(5e-6, 3)
            ax.set_ylabel("collision a (1e-5: a = 0)")
            ax.set_title(f"push {push:g} nN/cell, n {steep:g}, cutoff {cut:g}\nlabels: most nodes inside others",
                         fontsize=8)
        fig.colorbar(sc, ax=axes[0].tolist(), label="deepest interpenetration (um)")
        path = os.path.join(outdir, "cells_contacts.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        written.append(path)
    return written


def read_results(folder):
    """{name: rows} from the cells_*.csv files that `main` writes."""
    import csv
    out = {}
    for name in STUDIES:
        path = os.path.join(folder, f"cells_{name}.csv")
        if not os.path.exists(path):
            continue
        rows = []
        with open(path) as f:
            for row in csv.DictReader(f):
                for k, v in row.items():
                    try:
                        row[k] = float(v) if v not in ("True", "False") else v == "True"
                    except ValueError:
                        pass
                rows.append(row)
        out[f"cells_{name}"] = rows
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default="accuracy_out")
    ap.add_argument("--only", nargs="*", choices=list(STUDIES))
    ap.add_argument("--charts-from", metavar="DIR", help="draw the charts from the CSV files in DIR, run nothing")
    args = ap.parse_args()
    if args.charts_from:
        for p in charts(read_results(args.charts_from), args.out):
            print("chart", p)
        return
    os.makedirs(args.out, exist_ok=True)
    t0 = time.time()
    results = run(args.quick, args.only)
    for name, rows in results.items():
        write_rows(os.path.join(args.out, name + ".csv"), rows)
    for p in charts(results, args.out):
        print("chart", p)
    print(f"[cells] total {time.time() - t0:.1f} s wall")


if __name__ == "__main__":
    main()
