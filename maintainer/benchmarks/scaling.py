#!/usr/bin/env pyoif
"""Parallel scaling of the paper's bifurcation scene: the shape of the
PyOIF paper's Table 1 (seconds per 1000 steps at 1..10 cores with 0, 5, 10,
20, 40, 60 RBCs of 374 nodes; doc/model.md) measured at 1 and 2 MPI ranks,
and a model that projects it to 8, 10, 64 and 1024 ranks for three designs:
"replicated" (the fluid split over the ranks, every particle computed by
every rank: the engine up to 8113f59), "spread" (every rank stores every
particle, each cell's particles computed by the rank of its first node,
copies kept current point to point, all of them gathered at every re-sort:
378d77b) and "owned" (particles stored where they are and whole cells
evaluated by one rank: doc/architecture.md "Who owns a membrane", (b)).

    OMP_NUM_THREADS=1 pyoif maintainer/benchmarks/scaling.py [--cells 0 5 10 20 40 60]
        [--ranks 1 2] [--steps 500] [--cycles 1] [--repeats 2] [--tall-height 26] [--no-rare]
        [--project 0 40 60] [--project-ranks 2 8 10 64 1024] [--seeds 3]
        [--stencil-share 0.3] [--latency message|round] [--csv scaling.csv]
        [--model-csv scaling_model.csv] [--save-runs runs.pkl | --load-runs runs.pkl]

(as root, Open MPI needs OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
in the environment). At default settings it takes about 3 minutes on 2 cores.

Measurement. Each configuration runs samples/cell_flow_in_bifurcation.py
--full (box 160x40x22, agrid 1 um, time step = tau = 0.1 us, RBCs of 374
nodes and the stiff rare cell of 642 nodes; --no-rare: the RBCs alone, as
the paper's Table 1, and 0 RBCs is the fluid alone) with --cells N, --cycles
and --steps as given, under `mpirun --oversubscribe --bind-to core -np K
build/pyoif` (--bind-to none where K exceeds the cores; K = 1: the launcher
alone), OMP_NUM_THREADS=1, unchanged: the
sample runs inside this script's --child mode (runpy), which afterwards adds
what the sample does not print: every rank's halo bytes and exchange
seconds, the decomposition, the re-sorts, the fluid mask and the particles'
positions and cells. The figures are read from the sample's own timing
report (integrator.timing_report(): the time steps alone; set-up and
seeding are not in it; under MPI each phase the largest over the ranks, and
the last line the exchanges with other ranks and the load balance busy
max/mean); the least of --repeats runs counts (made in rounds over all
configurations, so that a burst of load does not hit every run of one).
Printed per configuration:
seconds per 1000 steps, the cost per cell (t(n) - t(0)) / n, the speed-up
(beside it, the memory-bandwidth limit of a K-rank speed-up on this
machine: the STREAM-like copy with K threads over 1 thread, the best of
the copies made at the start of each round, and the fluid alone's speed-up
as a share of it),
t1/tK and efficiency t1/(K tK), the load balance, the communication (halo +
coupling exchanges, waiting included) per step, the halo bytes a rank sends
per lattice update (lbf._core.halo_bytes, the largest over ranks; one
update per MD step here) and the coupling bytes a rank receives per MD
step: 24 N (K-1)/K for N particles where every rank computes every particle
(the MPI_Allgatherv of each particle's force, 3 doubles, from the rank of
its stencil's first node, about N/K from each rank), or 24 per particle
whose stencil reaches the rank while another rank owns its cell (point to
point to the owner; from the run's final positions) where the work is
spread (told by the membrane time per rank: the whole at every rank, or a
share). Also printed: the tree's commit and the engine's build time, before
and after (a rebuild during the measurement is flagged).
The sample's seeding region holds at most 48 RBCs + the rare cell at the
paper's height 20 (box 160x40x22); a count that does not fit is measured at
--height --tall-height (default 26: box 160x40x28, 27 % more lattice), with
its own 0-cell baseline, and marked "h26"; --tall-height 0 reports it as
not fitting instead.

Model. Per MD step, from the 1-rank run of a configuration (the phases of
integrator.timings()):
  L  the lattice update (lb_fluid), divided by fluid nodes: a rank's share
     is its fluid nodes / all fluid nodes (cuts balanced by fluid nodes per
     plane, the grid with the least halo surface, as DomainGrid chooses);
  C  the coupling (thermostat): c_div scales with the particles whose
     interpolation stencil touches the rank's subdomain, c_rep (finding the
     stencils, the loop over all particles) is replicated where every rank
     computes every particle; the split is fitted to the 2-rank run when
     that engine replicates (each rank's coupling less its exchange
     seconds), else c_rep = --stencil-share C (0.3: the fit with 40 RBCs
     on the replicating engine, 8113f59);
  M  the membranes (cells' moduli), O the rest of the particles' work
     (bonds, contacts, walls, velocity Verlet, neighbour lists);
  the re-sorts per step (cell_system.n_rebuilds during the timed run).
Communication, alpha-beta (as ownership_model.py: alpha = 1.5 us per
message, beta = 10 GB/s), per MD step on the busiest rank; a round of
neighbour messages costs n_peers alpha (n_peers: the distinct neighbour
ranks, up to 26; --latency round: alpha, as ownership_model.py counts a
round of concurrent messages), an allgather ceil(log2 P) alpha + bytes/beta, an
allreduce 2 ceil(log2 P) alpha:
  all designs: the halo (1 round, 8 bytes per crossing fluid population,
      counted link by link on the fluid mask, D3Q19; checked against
      lbf._core.halo_bytes) and the fluid velocities of the coupling's
      ghost layer (1 round, 24 bytes per ghost node on split axes);
  replicated: the allgather of the coupling forces, 24 N (P-1)/P bytes;
  spread: 3 rounds (copies' positions and velocities, normals, coupling
      forces to the owners; 96 bytes per copy, a copy being a particle
      within 1.3 um (largest cutoff + skin) of the subdomain whose cell
      another rank owns), 2 allreduces (the agreement on re-sorts and on
      errors), and per re-sort an allgather of the owner changes, an
      all-to-all of counts, one round of the particles within reach of
      other ranks (120 bytes each, about 6 times the copies: a cell's
      extent widens the reach) and a pass of 5 ns over every stored
      particle (storage replicated: N per rank, P N in weak scaling);
  owned: 2 rounds of particle ghosts (positions out, forces back: 48 bytes
      per particle within 1.3 um outside the subdomain) and the (b) cell
      exchange of ownership_model.py (72 bytes per node of a cell held by
      another rank than the cell's evaluator, 1 more round for normals).
Busy time of rank r (the step waits for the slowest: max over r, plus the
communication):
  replicated  L F_r/F + c_rep + c_div S_r/N + M + O
  spread      L F_r/F + C S_r/N + (M + O) V_r/V
  owned       L F_r/F + C S_r/N + M V_r/V + O N_r/N
with F_r fluid nodes, S_r particles whose stencil touches the subdomain,
N_r particles held (by position), V_r nodes of the cells whose first node
the rank holds (cells of 374 and 642 nodes). Strong scaling: the fixed
scene (--project cell counts; the 60-cell scene at its measured height),
efficiency t(1)/(P t(P)). Weak scaling: one copy of the scene per rank,
copies side by side along x (the grid with the least halo), so a rank's
subdomain is one copy with two x neighbours; efficiency t(1)/t(P). Where
storage is replicated every rank holds all P N particles: replicated
computes all of them (M, O, c_rep P-fold, the allgather 24 N (P-1) bytes),
spread passes over them all at every re-sort (before ca75f14 it also
gathered them all, 120 N (P-1) bytes). Cells are
placed as ownership_model.py places them (uniform centres in the channel,
random orientation, no overlap test; --seeds placements averaged): spread
over the channel as in a long run, not the seeding's cluster. The model
ignores cache effects (a smaller subdomain is faster per node), memory (P N
particles per rank where storage is replicated), second-neighbour messages
below one cell per subdomain, particle migration, and collectives other
than those named (e.g. the cells' volumes); it gives the order of
magnitude, and its 2-rank row is printed beside the measured one.
--save-runs keeps the measured runs (reports, masks, positions) and
--load-runs projects from them again without measuring, e.g. with another
--latency, --stencil-share or --project-ranks.
"""
import argparse
import json
import math
import os
import pickle
import re
import subprocess
import sys
import tempfile

import numpy as np

from benchmark_csv import write_rows

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SAMPLE = os.path.join(ROOT, "samples", "cell_flow_in_bifurcation.py")

ALPHA = 1.5e-6      # s per message (as ownership_model.py)
BETA = 10e9         # bytes per s
GHOST_RANGE = 1.3   # largest cutoff (1.0, node-wall) + skin 0.3
FULL_HEIGHT = 20.0  # the sample's --full channel height

# the paper's Table 1: CPU s per 1000 steps, cores -> {cells: s}
PAPER = {1: {0: 48.14, 5: 55.90, 10: 62.68, 20: 84.37, 40: 145.00, 60: 242.47},
         3: {0: 17.40, 5: 21.27, 10: 22.70, 20: 32.14, 40: 53.56, 60: 93.56},
         5: {0: 12.79, 5: 16.88, 10: 19.13, 20: 23.78, 40: 37.35, 60: 58.97},
         6: {0: 11.02, 5: 14.82, 10: 15.98, 20: 22.90, 40: 36.04, 60: 53.31},
         10: {0: 8.31, 5: 11.61, 10: 13.96, 20: 18.31, 40: 26.67, 60: 40.22}}

# the designs the model projects (module docstring)
DESIGNS = ("replicated", "spread", "owned")
RESORT_PASS_S = 5e-9  # seconds per stored particle and re-sort (folding, masks, lists)

# D3Q19 velocities less the rest one
D3Q19 = [c for c in ((x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1))
         if 0 < sum(map(abs, c)) <= 2]


# ---------------------------------------------------------------- child mode
def child(json_path, argv):
    """Run the sample (argv: its path and arguments) on every rank, then
    write what rank 0 needs besides its report (collective calls on all)."""
    import runpy
    from mpi4py import MPI
    import lbmd.system
    # the re-sorts of the timed run only: counted from the sample's
    # reset_timings() (the calibration runs before it re-sort at every step,
    # with no particles)
    reset = lbmd.system.Integrator.reset_timings
    at_reset = {}

    def counting_reset(self):
        at_reset["rebuilds"] = int(self._system.cell_system.n_rebuilds)
        return reset(self)

    lbmd.system.Integrator.reset_timings = counting_reset
    sys.argv = list(argv)
    g = runpy.run_path(argv[0], run_name="__main__")
    system, lbf = g["system"], g["lbf"]
    t = system.integrator.timings()  # collective under MPI
    core = lbf._core
    comm = MPI.COMM_WORLD
    ranks = comm.allgather(dict(halo_bytes=int(core.halo_bytes), halo_seconds=float(core.halo_seconds),
                                coupling_exchange_seconds=float(core.coupling_exchange_seconds),
                                decomposition=str(core.decomposition)))
    mask = np.asarray(lbf[:, :, :].boundary) != 0  # collective
    everyone = system.part.all()
    pos, mol = np.asarray(everyone.pos, dtype=float), np.asarray(everyone.mol_id, dtype=int)
    if comm.Get_rank() == 0:
        np.savez(json_path + ".npz", solid=mask, pos=pos, mol=mol)
        with open(json_path, "w") as f:
            json.dump(dict(timings=t, ranks=ranks, n_particles=len(pos),
                           rebuilds=int(system.cell_system.n_rebuilds) - at_reset.get("rebuilds", 0),
                           particles_spread=getattr(system._core, "particles_spread", None)), f)


# ----------------------------------------------------------- measurement
class NoRoom(Exception):
    """The sample could not seed that many cells."""


def parse_report(out):
    """The sample's timing report: total seconds and steps, and under MPI the
    exchanges' seconds and the load balance (its last line)."""
    rep = {}
    for line in out.splitlines():
        m = re.match(r"total \((\d+) steps\)\s+([\d.]+)\s", line)
        if m:
            rep["steps"], rep["total"] = int(m.group(1)), float(m.group(2))
            continue
        m = re.search(r"(\d+) ranks\b.*exchanges with other ranks ([\d.]+) s.*load balance[^)]*\)\s*([\d.]+)", line)
        if m:
            rep["ranks"], rep["communication"], rep["balance"] = int(m.group(1)), float(m.group(2)), float(m.group(3))
    if "total" not in rep:
        raise RuntimeError("no timing report in the sample's output:\n" + out[-2000:])
    return rep


def run_once(args, cells, ranks, height, tmp):
    """One run of the sample at `ranks` ranks: its report and the child's data."""
    js = os.path.join(tmp, f"run_{cells}_{ranks}_{height}.json")
    sample_args = [SAMPLE, "--full", "--cells", str(cells), "--cycles", str(args.cycles), "--steps",
                   str(args.steps), "--output", os.path.join(tmp, "out"), "--no-plots", "--progress", "off"]
    if height != FULL_HEIGHT:
        sample_args += ["--height", f"{height:g}"]
    if args.no_rare:
        sample_args += ["--no-rare"]
    cmd = [args.pyoif, os.path.abspath(__file__), "--child", js, "--"] + sample_args
    if ranks > 1:
        # each rank on its own core where there are enough (Open MPI's own
        # default for 2 ranks), else unbound (oversubscribed)
        bind = args.bind_to if args.bind_to != "auto" else ("core" if ranks <= (os.cpu_count() or 1) else "none")
        cmd = [args.mpirun, "--oversubscribe", "--bind-to", bind, "-np", str(ranks)] + cmd
    env = dict(os.environ, OMP_NUM_THREADS=str(args.threads))
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    if p.returncode != 0:
        if "SeedingError" in p.stderr:
            raise NoRoom(p.stderr.strip().splitlines()[-1])
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-3000:]}")
    rep = parse_report(p.stdout)
    if ranks > 1 and "balance" not in rep:
        raise RuntimeError("no load-balance line in the sample's timing report under MPI:\n" + p.stdout[-2000:])
    with open(js) as f:
        data = json.load(f)
    with np.load(js + ".npz") as z:
        data["solid"], data["pos"], data["mol"] = z["solid"], z["pos"], z["mol"]
    data["report"] = rep
    return data


def per_step(run):
    """Wall seconds per MD step of a run, from the sample's report."""
    return run["report"]["total"] / run["report"]["steps"]


def engine(pyoif):
    """The commit of the tree, whether src/ differs from it, and the time of
    the engine's build (to tell whether it changed during the measurement)."""
    import glob
    import time
    so = sorted(glob.glob(os.path.join(os.path.dirname(os.path.abspath(pyoif)), "python", "lbmd", "_lbmd*.so")))
    built = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(os.path.getmtime(so[0]))) if so else "?"
    try:
        head = subprocess.run(["git", "-C", ROOT, "log", "-1", "--format=%h"], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--", "src"], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True).stdout.strip()
    except OSError:
        head, dirty = "?", ""
    return f"tree at {head or '?'}{' (src/ changed since)' if dirty else ''}, engine built {built}"


# ------------------------------------------------------------------ model
def choose_dims(ranks, nodes):
    """DomainGrid::choose_dims: least halo surface of a subdomain, ties to more
    ranks along x, then y."""
    best, best_surface = (ranks, 1, 1), math.inf
    for dx in range(ranks, 0, -1):
        if ranks % dx:
            continue
        for dy in range(ranks // dx, 0, -1):
            if (ranks // dx) % dy:
                continue
            d = (dx, dy, ranks // dx // dy)
            if any(d[a] > nodes[a] for a in range(3)):
                continue
            s = sum(nodes[(a + 1) % 3] / d[(a + 1) % 3] * nodes[(a + 2) % 3] / d[(a + 2) % 3]
                    for a in range(3) if d[a] > 1)
            if s < best_surface * (1 - 1e-12):
                best, best_surface = d, s
    return best


def balanced_cuts(dims, fluid):
    """DomainGrid::balance with the fluid nodes per plane as weights."""
    cuts = []
    for d in range(3):
        n, k_max = fluid.shape[d], dims[d]
        even = [n * k // k_max for k in range(k_max + 1)]
        w = fluid.sum(axis=tuple(a for a in range(3) if a != d)).astype(float)
        if k_max == 1 or w.sum() <= 0:
            cuts.append(even)
            continue
        prefix = np.concatenate([[0.0], np.cumsum(w)])
        c = [0] * (k_max + 1)
        c[k_max] = n
        for j in range(1, k_max):
            target = prefix[-1] * j / k_max
            k = int(np.searchsorted(prefix, target, side="left"))
            if k > 0 and target - prefix[k - 1] < prefix[k] - target:
                k -= 1
            c[j] = min(max(k, c[j - 1] + 1), n - (k_max - j))
        cuts.append(c)
    return cuts


def parse_decomposition(text, nodes):
    """'2x1x1, cuts x: 0 80 160' -> dims, cuts."""
    dims = tuple(int(v) for v in text.split(",")[0].split("x"))
    cuts = [[n * k // dims[d] for k in range(dims[d] + 1)] for d, n in enumerate(nodes)]
    for axis, values in re.findall(r"cuts ([xyz]):([\d ]+)", text):
        cuts["xyz".index(axis)] = [int(v) for v in values.split()]
    return dims, cuts


class Grid:
    """A Cartesian grid of subdomains over a lattice of shape `nodes`."""

    def __init__(self, dims, cuts, nodes):
        self.dims, self.cuts, self.nodes = tuple(dims), [np.asarray(c) for c in cuts], tuple(nodes)
        self.size = int(np.prod(dims))

    def rank(self, cx, cy, cz):
        dx, dy, dz = self.dims
        return ((np.asarray(cz) % dz) * dy + np.asarray(cy) % dy) * dx + np.asarray(cx) % dx

    def coords_of_node(self, g, d):
        g = np.asarray(g) % self.nodes[d]
        return np.searchsorted(self.cuts[d], g, side="right") - 1

    def owner_of_nodes(self, gx, gy, gz):
        return self.rank(self.coords_of_node(gx, 0), self.coords_of_node(gy, 1), self.coords_of_node(gz, 2))

    def owner_field(self):
        ix, iy, iz = np.meshgrid(*(np.arange(n) for n in self.nodes), indexing="ij")
        return self.owner_of_nodes(ix, iy, iz)

    def coords(self, r):
        dx, dy, _ = self.dims
        return r % dx, (r // dx) % dy, r // (dx * dy)

    def extent(self, r):
        c = self.coords(r)
        return np.array([self.cuts[d][c[d] + 1] - self.cuts[d][c[d]] for d in range(3)])

    def lower(self, r):
        c = self.coords(r)
        return np.array([self.cuts[d][c[d]] for d in range(3)])

    def peers(self, r):
        c = self.coords(r)
        out = {int(self.rank(c[0] + ox, c[1] + oy, c[2] + oz))
               for ox in (-1, 0, 1) for oy in (-1, 0, 1) for oz in (-1, 0, 1)}
        out.discard(int(r))
        return len(out)


def rank_loads(grid, solid, scene):
    """Per-rank arrays: fluid nodes, halo bytes sent per update, ghost-velocity
    bytes, neighbour ranks, particles touching (stencil), held, ghosts, cell
    nodes evaluated, (b) bytes; scene: (positions, cell index per node,
    nodes per cell)."""
    P = grid.size
    fluid = ~solid
    owner = grid.owner_field()
    F_r = np.bincount(owner[fluid], minlength=P)
    halo = np.zeros(P)
    for c in D3Q19:
        dst_owner = np.roll(owner, shift=[-c[0], -c[1], -c[2]], axis=(0, 1, 2))
        dst_fluid = np.roll(fluid, shift=[-c[0], -c[1], -c[2]], axis=(0, 1, 2))
        cross = fluid & dst_fluid & (owner != dst_owner)
        halo += np.bincount(owner[cross], minlength=P)
    halo *= 8.0
    split = np.array([d > 1 for d in grid.dims], dtype=int)
    vel = np.array([24.0 * (np.prod(grid.extent(r) + 2 * split) - np.prod(grid.extent(r))) for r in range(P)])
    peers = np.array([grid.peers(r) for r in range(P)])
    pos, cell_of, cell_nodes = scene
    N = len(pos)
    if N == 0:  # no stencil reads ghost velocities: the engine skips their exchange
        vel = np.zeros(P)
    L = np.array(grid.nodes, dtype=float)
    node = np.floor(pos).astype(int)
    held = grid.owner_of_nodes(node[:, 0], node[:, 1], node[:, 2])
    N_r = np.bincount(held, minlength=P)
    S_r = np.bincount(stencil_ranks(grid, pos) % P, minlength=P)
    first = np.searchsorted(cell_of, np.arange(len(cell_nodes)))  # each cell's first node
    evaluator = held[first]
    cell_owner = evaluator[cell_of]  # the spread engine's owner of each particle
    V_r = np.bincount(evaluator, weights=cell_nodes, minlength=P)
    ghosts, copies_in, copies_out = np.zeros(P), np.zeros(P), np.zeros(P)
    for r in range(P):
        near = np.ones(N, dtype=bool)  # in the subdomain or within GHOST_RANGE of it
        for d in range(3):
            if grid.dims[d] == 1:
                continue
            x = (pos[:, d] - grid.lower(r)[d]) % L[d]
            near &= (x < grid.extent(r)[d] + GHOST_RANGE) | (x > L[d] - GHOST_RANGE)
        ghosts[r] = np.count_nonzero(near & (held != r))
        wanted = near & (cell_owner != r)
        copies_in[r] = np.count_nonzero(wanted)
        copies_out += np.bincount(cell_owner[wanted], minlength=P)
    b_bytes = np.zeros(P)
    remote = held != evaluator[cell_of]
    np.add.at(b_bytes, evaluator[cell_of[remote]], 72.0)
    np.add.at(b_bytes, held[remote], 72.0)
    return dict(F_r=F_r, halo=halo, vel=vel, peers=peers, S_r=S_r, N_r=N_r, ghosts=ghosts, V_r=V_r,
                b_bytes=b_bytes, copies=np.maximum(copies_in, copies_out), F=fluid.sum(), N=N,
                V=float(np.sum(cell_nodes)))


def random_scene(box, n_rbc, rng, meshes, with_rare=True):
    """ownership_model.scene for n_rbc RBCs (+ the rare cell) in a box: node
    positions (folded), cell index per node, nodes per cell."""
    import ownership_model as om
    rbc, rare = meshes
    pos, cell_of, sizes = [], [], []
    for k, m in enumerate([rbc] * n_rbc + ([rare] if with_rare else [])):
        lo = np.array([0.0, 5.0 + 4.0, 1.0 + (1.5 if k < n_rbc else 7.6)])
        hi = np.array([box[0], 35.0 - 4.0, box[2] - lo[2]])
        centre = rng.uniform(lo, np.maximum(hi, lo + 1e-9))
        pos.append((m @ om.random_rotation(rng).T + centre) % box)
        cell_of.append(np.full(len(m), k))
        sizes.append(len(m))
    if not pos:  # the fluid alone
        return np.zeros((0, 3)), np.zeros(0, dtype=int), np.zeros(0)
    return np.concatenate(pos), np.concatenate(cell_of), np.array(sizes, dtype=float)


def meshes():
    import ownership_model as om
    return om.mesh("rbc374", 3.91)[0], om.mesh("sphere642", 7.5)[0]


def step_time(cal, loads, design, P, weak=False, per_message=True):
    """(busy, comm) seconds per step on the busiest rank, model of the module
    docstring. cal: per-step seconds L, c_rep, c_div, M, O, rebuilds per step."""
    L, c_rep, c_div, M, O = (cal[k] for k in ("L", "c_rep", "c_div", "M", "O"))
    F, N, V = loads["F"], loads["N"], loads["V"]
    N, V = max(N, 1e-300), max(V, 1e-300)  # the fluid alone: the particles' shares 0 / tiny = 0
    if weak:  # one copy per rank: the 2-copy model's rank 0, copies P-fold
        F, N, V = F / 2, N / 2, V / 2
        pick = slice(0, 1)
        peers = min(P - 1, 2)
    else:
        pick = slice(None)
        peers = loads["peers"][pick].max() if P > 1 else 0
    Fr, Sr, Nr, Vr = (loads[k][pick] for k in ("F_r", "S_r", "N_r", "V_r"))
    copies = P if weak else 1  # scene copies: particles on every rank where storage is replicated
    n_all = N * copies
    log_p = math.ceil(math.log2(P)) if P > 1 else 0
    halo = loads["halo"][pick].max() if P > 1 else 0.0
    vel = loads["vel"][pick].max() if P > 1 else 0.0
    rounds = lambda k: k * (peers if per_message else min(peers, 1)) * ALPHA  # k rounds of neighbour messages
    lattice = (rounds(2) + (halo + vel) / BETA) if P > 1 else 0.0
    if design == "replicated":
        busy = (L * Fr / F + c_rep * copies + c_div * np.minimum(Sr / N, 1.0) + (M + O) * copies).max()
        gather = (log_p * ALPHA + 24.0 * n_all * (P - 1) / P / BETA) if P > 1 else 0.0
        return busy, lattice + gather
    if design == "spread":
        busy = (L * Fr / F + (c_rep + c_div) * np.minimum(Sr / N, 1.0) + (M + O) * Vr / V).max()
        if P == 1:
            return busy, 0.0
        p2p = rounds(3) + 96.0 * loads["copies"][pick].max() / BETA
        collectives = 2 * 2 * log_p * ALPHA
        # per re-sort (since ca75f14 no gather of all particles): the
        # owner changes (an allgather of a few ints), the counts (an
        # all-to-all), one round of the particles within reach of other
        # ranks (120 bytes each: the copies within 1.3 um, times the wider
        # reach of a cell's extent, about 6), and a pass over every stored
        # particle (about 5 ns each: storage is replicated)
        reach = 6.0 * loads["copies"][pick].max()
        resort = cal["rebuilds"] * (2 * log_p * ALPHA + rounds(1) + 120.0 * reach / BETA
                                    + RESORT_PASS_S * n_all)
        return busy, lattice + p2p + collectives + resort
    busy = (L * Fr / F + (c_rep + c_div) * np.minimum(Sr / N, 1.0) + M * Vr / V + O * Nr / N).max()
    if P == 1:
        return busy, 0.0
    ghosts = rounds(2) + 48.0 * loads["ghosts"][pick].max() / BETA
    cells = rounds(1) + loads["b_bytes"][pick].max() / BETA
    return busy, lattice + ghosts + cells


def spreads(run, one):
    """Whether the engine of a run at K > 1 ranks spreads the particles' work
    (each cell's particles computed by one rank) rather than replicating it:
    system._core.particles_spread where the engine has it, else told by the
    membrane time summed over the ranks against the lattice's (whose work is
    split either way), about 1 (spread) or K (replicated) times the 1-rank
    ratio."""
    per = run["timings"].get("per_rank")
    if not per:
        return False
    if run.get("particles_spread") is not None:
        return bool(run["particles_spread"])
    t1 = one["timings"]
    ratio1 = t1["membrane"] / max(t1["lb_fluid"], 1e-30)
    ratio = sum(r["membrane"] for r in per) / max(sum(r["lb_fluid"] - x["halo_seconds"]
                                                      for r, x in zip(per, run["ranks"])), 1e-30)
    return ratio / max(ratio1, 1e-30) < 0.5 * (1 + len(per))


def stencil_ranks(grid, pos):
    """(particle, rank) pairs, as particle * P + rank: the ranks whose
    subdomain a particle's interpolation stencil touches."""
    lo = np.floor(pos - 0.5).astype(int)
    owners8 = np.stack([grid.owner_of_nodes(lo[:, 0] + a, lo[:, 1] + b, lo[:, 2] + c)
                        for a in (0, 1) for b in (0, 1) for c in (0, 1)], axis=1)
    return np.unique(np.arange(len(pos))[:, None] * grid.size + owners8)


def coupling_bytes(run, spread):
    """Bytes of the coupling's force exchange a rank receives per MD step: the
    allgather of every particle's force (replicated work), or the forces of
    the particles whose stencil reaches another rank than their owner, the
    rank of their cell's first node (spread work; the busiest rank)."""
    K, N = len(run["ranks"]), run["n_particles"]
    if K == 1:
        return 0.0
    if not spread:
        return 24.0 * N * (K - 1) / K
    nodes = np.array(run["solid"].shape)
    grid = Grid(*parse_decomposition(run["ranks"][0]["decomposition"], nodes), nodes)
    pos, mol = run["pos"], run["mol"]
    node = np.floor(pos).astype(int)
    held = grid.owner_of_nodes(node[:, 0], node[:, 1], node[:, 2])
    mols, first = np.unique(mol, return_index=True)
    owner = held[first][np.searchsorted(mols, mol)]
    pairs = stencil_ranks(grid, pos)
    elsewhere = pairs[(pairs % K) != owner[pairs // K]]
    return 24.0 * np.bincount(elsewhere % K, minlength=K).max()


def calibrate(one, two, stencil_share):
    """Per-step seconds of the 1-rank run's phases; the coupling's replicated
    part fitted to the 2-rank run where that engine replicates the particle
    work, else stencil_share of it; re-sorts per step."""
    t = one["timings"]
    steps = t["steps"]
    cal = dict(L=t["lb_fluid"] / steps, C=t["coupling"] / steps, M=t["membrane"] / steps,
               O=(t["bonded"] + t["non_bonded"] + t["constraints"] + t["other"]) / steps,
               rebuilds=one.get("rebuilds", 0) / steps)  # (of the timed run)
    cal["c_rep"] = stencil_share * cal["C"]
    cal["c_div"] = cal["C"] - cal["c_rep"]
    cal["fit"] = f"no 2-rank run: {100 * stencil_share:.0f} % of C replicated (--stencil-share)"
    cal["engine"] = "?"
    if two is not None:
        # does the measured engine replicate the particles' work? (every rank
        # computes every membrane, or each cell's owner only)
        per = two["timings"]["per_rank"]
        m_share = np.mean([r["membrane"] / r["steps"] for r in per]) / max(cal["M"], 1e-30)
        cal["engine"] = "spread" if spreads(two, one) else "replicated"
        nodes = np.array(two["solid"].shape)
        dims, cuts = parse_decomposition(two["ranks"][0]["decomposition"], nodes)
        grid = Grid(dims, cuts, nodes)
        pairs = stencil_ranks(grid, two["pos"])
        share = np.bincount(pairs % grid.size, minlength=grid.size) / max(len(two["pos"]), 1)
        y = np.mean([(r["coupling"] - x["coupling_exchange_seconds"]) / r["steps"]
                     for r, x in zip(per, two["ranks"])])
        s = share.mean()
        cal["fit"] = (f"the measured engine spreads the particles' work (membrane per rank at 2 ranks "
                      f"{100 * m_share:.0f} % of 1 rank): {100 * stencil_share:.0f} % of C replicated "
                      f"(--stencil-share)")
        if cal["engine"] == "replicated" and s < 1.0 - 1e-9:
            cal["c_div"] = float(min(max((cal["C"] - y) / (1.0 - s), 0.0), cal["C"]))
            cal["c_rep"] = cal["C"] - cal["c_div"]
            cal["fit"] = (f"the measured engine replicates the particles' work; 2 ranks: coupling less its "
                          f"exchanges {1e3 * y:.3f} ms/step per rank, {100 * s:.0f} % of the particles touch "
                          f"a rank's subdomain")
        # the lattice: busy per fluid node at 2 ranks against 1
        fluid = ~two["solid"]
        F_r = np.bincount(grid.owner_field()[fluid], minlength=grid.size)
        lat = [(r["lb_fluid"] - x["halo_seconds"]) / r["steps"] for r, x in zip(per, two["ranks"])]
        cal["lattice_check"] = float(np.mean([l / (cal["L"] * f / fluid.sum()) for l, f in zip(lat, F_r)]))
    return cal


def measure_all(args, ranks_list):
    """Run every configuration --repeats times; the quietest run of each, the
    height each count was measured at, the counts that did not fit, and the
    header of the measured table (settings, load, engine)."""
    load_before = os.getloadavg()
    engine_before = engine(args.pyoif)
    results = {}  # (cells, height) -> {ranks: data}
    heights = {}  # cells -> height measured at
    no_room = {}
    bandwidth = {}

    def copy_bandwidths():
        """The best copy bandwidth so far with 1 thread and with each rank
        count's threads (two cores' threads share the memory as two ranks
        do): what bounds a memory-bound speed-up on this machine."""
        from lbmd import _lbmd
        for k in [1] + [k for k in ranks_list if k > 1]:
            threads = min(k, os.cpu_count() or 1)
            bw = _lbmd.copy_bandwidth(1 << 25, 5, threads)
            bandwidth[k] = max(bandwidth.get(k, 0.0), bw)

    def keep(n, h, k, d):
        """Keep the quieter of the runs of a configuration."""
        old = results.setdefault((n, h), {}).get(k)
        if old is None or per_step(d) < per_step(old):
            results[(n, h)][k] = d
        print(f"  {n:3d} RBCs, height {h:g}, {k} rank(s): {1e3 * per_step(d):.2f} s / 1000 steps", flush=True)

    # the repeats are rounds over all configurations, so that a burst of
    # load on a shared machine does not hit all runs of one configuration
    with tempfile.TemporaryDirectory() as tmp:
        todo = [(n, FULL_HEIGHT) for n in sorted(set(args.cells))]
        configs = []
        print(f"round 1 of {args.repeats}", flush=True)
        copy_bandwidths()
        while todo:
            n, h = todo.pop(0)
            try:
                for k in ranks_list:
                    keep(n, h, k, run_once(args, n, k, h, tmp))
                configs.append((n, h))
                if n not in heights or h == FULL_HEIGHT:
                    heights[n] = h
            except NoRoom as e:
                results.pop((n, h), None)
                if h == FULL_HEIGHT and args.tall_height > 0:
                    print(f"  {n} RBCs do not fit the sample's seeding region at height {h:g}; "
                          f"measuring at --height {args.tall_height:g}", flush=True)
                    todo.append((n, args.tall_height))
                    if (0, args.tall_height) not in results and all(m != (0, args.tall_height) for m in todo):
                        todo.insert(0, (0, args.tall_height))
                else:
                    no_room[n] = str(e)
        for r in range(1, args.repeats):
            print(f"round {r + 1} of {args.repeats}", flush=True)
            copy_bandwidths()
            for n, h in configs:
                for k in ranks_list:
                    keep(n, h, k, run_once(args, n, k, h, tmp))
    engine_after = engine(args.pyoif)
    header = ("Measured: samples/cell_flow_in_bifurcation.py --full"
              f"{' --no-rare (no rare cell)' if args.no_rare else ' (with the rare cell)'}, "
              f"{args.cycles} x {args.steps} steps, least of {args.repeats}, OMP_NUM_THREADS={args.threads}; "
              f"load average (1 min) {load_before[0]:.2f} before, {os.getloadavg()[0]:.2f} after\n  "
              + engine_before + ("" if engine_after == engine_before else
                                 f"; CHANGED during the measurement, now {engine_after}"))
    return results, heights, no_room, header, bandwidth


# ------------------------------------------------------------------- main
def main():
    if len(sys.argv) > 3 and sys.argv[1] == "--child" and sys.argv[3] == "--":
        child(sys.argv[2], sys.argv[4:])
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=int, nargs="+", default=[0, 5, 10, 20, 40, 60], help="numbers of RBCs")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2], help="MPI ranks to measure at")
    ap.add_argument("--steps", type=int, default=500, help="MD steps per cycle")
    ap.add_argument("--cycles", type=int, default=1, help="cycles of --steps (all are timed)")
    ap.add_argument("--repeats", type=int, default=2, help="runs per configuration (the least counts)")
    ap.add_argument("--threads", type=int, default=1, help="OMP_NUM_THREADS of the runs")
    ap.add_argument("--tall-height", type=float, default=26.0,
                    help="channel height for counts that do not fit at the paper's 20 (0: report them)")
    ap.add_argument("--project", type=int, nargs="*", default=[0, 40, 60],
                    help="cell counts to project (measured ones only)")
    ap.add_argument("--project-ranks", type=int, nargs="+", default=[2, 8, 10, 64, 1024])
    ap.add_argument("--seeds", type=int, default=3, help="random placements averaged in the model")
    ap.add_argument("--stencil-share", type=float, default=0.3,
                    help="replicated share of the coupling where the measured engine spreads the particles "
                         "(fitted where it replicates them: 0.3 with 40 RBCs, 8113f59)")
    ap.add_argument("--no-rare", action="store_true",
                    help="the RBCs alone, without the sample's rare cell (the paper's Table 1; 0 RBCs: the fluid alone)")
    ap.add_argument("--bind-to", choices=("auto", "core", "none"), default="auto",
                    help="mpirun --bind-to (auto: core where the ranks fit on the cores, else none)")
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--pyoif", default=os.path.join(ROOT, "build", "pyoif"))
    ap.add_argument("--csv", default="scaling.csv")
    ap.add_argument("--model-csv", default="scaling_model.csv")
    ap.add_argument("--latency", choices=("message", "round"), default="message",
                    help="alpha per message (a round of neighbour messages costs n_peers alpha) or per round "
                         "(alpha, as ownership_model.py counts)")
    ap.add_argument("--save-runs", default=None, help="keep the measured runs in this file (pickle)")
    ap.add_argument("--load-runs", default=None,
                    help="take the runs from a --save-runs file instead of measuring (to vary the model)")
    args = ap.parse_args()
    if args.steps < 1 or args.repeats < 1 or args.cycles < 1 or min(args.ranks) < 1:
        ap.error("--steps, --cycles, --repeats and --ranks must be at least 1")
    ranks_list = sorted(set(args.ranks))
    if 1 not in ranks_list:
        ap.error("--ranks must include 1 (the reference of speed-up and model)")

    # --- measure (or take the runs of an earlier invocation)
    if args.load_runs:
        with open(args.load_runs, "rb") as f:
            saved = pickle.load(f)
        results, heights, no_room, header = (saved[k] for k in ("results", "heights", "no_room", "header"))
        bandwidth = saved.get("bandwidth", {})
        header = f"{header} (runs read from {args.load_runs})"
        ranks_list = sorted({k for by_k in results.values() for k in by_k})
    else:
        results, heights, no_room, header, bandwidth = measure_all(args, ranks_list)
        if args.save_runs:
            with open(args.save_runs, "wb") as f:
                pickle.dump(dict(results=results, heights=heights, no_room=no_room, header=header,
                                 bandwidth=bandwidth), f)

    # --- measured table
    print()
    print(header)
    hdr = (f"{'RBCs':>6s} {'N':>6s} {'ranks':>5s} {'s/1000':>8s} {'s/cell':>7s} {'speedup':>7s} {'eff':>5s} "
           f"{'balance':>7s} {'comm ms':>8s} {'halo kB':>8s} {'coupl kB':>8s}  decomposition")
    print(hdr)
    rows = []
    for (n, h), by_k in sorted(results.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        base = results.get((0, h))
        tag = f"{n}" + ("" if h == FULL_HEIGHT else f" h{h:g}")
        for k in ranks_list:
            d = by_k[k]
            t = per_step(d)
            t1 = per_step(by_k[1])
            N = d["n_particles"]
            per_cell = (t - per_step(base[k])) / n if (n and base and k in base) else None
            rep = d["report"]
            comm = rep.get("communication", 0.0) / rep["steps"] if k > 1 else 0.0
            bal = rep.get("balance", 1.0) if k > 1 else 1.0
            halo = max(r["halo_bytes"] for r in d["ranks"]) if k > 1 else 0
            spread = spreads(d, by_k[1])
            coupl = coupling_bytes(d, spread)
            dec = d["ranks"][0]["decomposition"]
            print(f"{tag:>6s} {N:6d} {k:5d} {1e3 * t:8.2f} "
                  + (f"{1e3 * per_cell:7.3f} " if per_cell is not None else f"{'-':>7s} ")
                  + f"{t1 / t:7.2f} {100 * t1 / (k * t):4.0f}% {bal:7.3f} {1e3 * comm:8.3f} "
                  f"{halo / 1e3:8.1f} {coupl / 1e3:8.1f}  {dec}" + ("; work spread" if spread else ""))
            rows.append({"rbcs": n, "height": h, "particles": N, "ranks": k, "s_per_1000_steps": 1e3 * t,
                         "s_per_cell_per_1000_steps": "" if per_cell is None else 1e3 * per_cell,
                         "speedup": t1 / t, "efficiency": t1 / (k * t), "load_balance": bal,
                         "communication_ms_per_step": 1e3 * comm,
                         "halo_ms_per_step": 1e3 * max(r["halo_seconds"] for r in d["ranks"]) / rep["steps"],
                         "coupling_exchange_ms_per_step": 1e3 * max(r["coupling_exchange_seconds"]
                                                                    for r in d["ranks"]) / rep["steps"],
                         "halo_bytes_per_update": halo,
                         "coupling_bytes_per_step": coupl, "particle_work_spread": spread,
                         "resorts_per_step": d.get("rebuilds", 0) / rep["steps"],
                         "lattice_share": d["timings"]["lb_fluid"] / d["timings"]["total"], "decomposition": dec,
                         "paper_one_core_s": PAPER[1].get(n, ""),
                         "paper_ten_cores_s": PAPER[10].get(n, ""), "bandwidth_limit": ""})
    for n, why in no_room.items():
        print(f"{n:6d} RBCs: does not fit the sample's seeding region ({why})")
    print("  s/cell: (t(n) - t(0)) / n per 1000 steps (same height); comm: halo + coupling exchanges "
          "per step, waiting included (largest rank); halo kB: sent per lattice update by the busiest rank; "
          "coupl kB: the coupling's forces received per MD step by a rank: 24 N (K-1)/K (the allgather where "
          "every rank computes every particle) or 24 per particle whose stencil reaches the rank but whose cell "
          "another rank owns (\"work spread\": each cell's particles computed by the rank of its first node; "
          "busiest rank)")
    for k in ranks_list:
        if k > 1 and k in bandwidth and 1 in bandwidth:
            # the fluid alone is memory-bound: its speed-up cannot pass what
            # the memory gives k threads over one
            limit = bandwidth[k] / bandwidth[1]
            fluid = results.get((0, FULL_HEIGHT), {})
            seen = (f"; the fluid alone (0 RBCs) sped up {per_step(fluid[1]) / per_step(fluid[k]):.2f}x = "
                    f"{100 * per_step(fluid[1]) / per_step(fluid[k]) / limit:.0f} % of it"
                    if 1 in fluid and k in fluid else "")
            print(f"  memory-bandwidth limit of a {k}-rank speed-up: copy with {min(k, os.cpu_count() or 1)} "
                  f"threads / 1 thread = {bandwidth[k] / 1e9:.1f} / {bandwidth[1] / 1e9:.1f} GB/s = "
                  f"{limit:.2f}{seen} (best copies of the rounds, measured beside the runs)")
            for row in rows:
                if row["ranks"] == k:
                    row["bandwidth_limit"] = limit
    print("  paper (Table 1, CPU s / 1000 steps, 1 core / 10 cores): "
          + ", ".join(f"{n}: {PAPER[1][n]:.2f} / {PAPER[10][n]:.2f}" for n in sorted(PAPER[1])))
    write_rows(args.csv, rows)

    # --- model
    projected = [n for n in args.project if n in heights]
    for n in args.project:
        if n not in heights:
            print(f"(no projection for {n} RBCs: not measured)")
    if not projected:
        return
    cell_meshes = meshes()
    print()
    print(f"Model (alpha {ALPHA * 1e6:.1f} us per {args.latency}, beta {BETA / 1e9:.0f} GB/s; calibrated on the "
          "1-rank run of each count, the coupling's split on the 2-rank run)")
    model_rows = []
    for n in projected:
        h = heights[n]
        by_k = results[(n, h)]
        cal = calibrate(by_k[1], by_k.get(2), args.stencil_share)
        print(f"  {n} RBCs{'' if h == FULL_HEIGHT else f' (height {h:g})'}: per step L {1e3 * cal['L']:.3f} "
              f"ms, C {1e3 * cal['C']:.3f} (c_rep {1e3 * cal['c_rep']:.3f}, c_div {1e3 * cal['c_div']:.3f}), "
              f"M {1e3 * cal['M']:.3f}, O {1e3 * cal['O']:.3f}; measured total {1e3 * per_step(by_k[1]):.3f} ms; "
              f"a re-sort every {1 / cal['rebuilds'] if cal['rebuilds'] > 0 else math.inf:.0f} steps; {cal['fit']}"
              + (f"; lattice busy per fluid node at 2 ranks / 1 rank: {cal['lattice_check']:.2f}"
                 if "lattice_check" in cal else ""))
        solid = by_k[1]["solid"]
        nodes = solid.shape
        box = np.array(nodes, dtype=float)
        fluid = ~solid
        # placements: the fixed scene, and two copies side by side for weak scaling
        scenes, weak_loads = [], []
        solid2 = np.concatenate([solid, solid], axis=0)
        grid2 = Grid((2, 1, 1), [[0, nodes[0], 2 * nodes[0]], [0, nodes[1]], [0, nodes[2]]], solid2.shape)
        for seed in range(args.seeds):
            rng = np.random.default_rng(seed)
            scene = random_scene(box, n, rng, cell_meshes, not args.no_rare)
            other = random_scene(box, n, rng, cell_meshes, not args.no_rare)
            scenes.append(scene)
            weak_loads.append(rank_loads(grid2, solid2, (np.concatenate([scene[0], other[0] + [box[0], 0, 0]]),
                                                         np.concatenate([scene[1], other[1] + len(scene[2])]),
                                                         np.concatenate([scene[2], other[2]]))))
        rows_n = []
        for P in sorted({1} | set(args.project_ranks)):
            dims = choose_dims(P, nodes)
            grid = Grid(dims, balanced_cuts(dims, fluid), nodes)
            acc = {k: [] for d in DESIGNS for k in (d, "weak_" + d)}
            for scene, loads2 in zip(scenes, weak_loads):
                loads = rank_loads(grid, solid, scene)
                for d in DESIGNS:
                    acc[d].append(step_time(cal, loads, d, P, per_message=args.latency == "message"))
                    acc["weak_" + d].append(step_time(cal, loads2, d, P, weak=True,
                                                      per_message=args.latency == "message"))
            row = {"rbcs": n, "height": h, "ranks": P, "grid": "x".join(map(str, dims))}
            for k, v in acc.items():
                busy, comm = np.mean(v, axis=0)
                row[f"{k}_s_per_1000"] = 1e3 * (busy + comm)
                row[f"{k}_comm_share"] = comm / (busy + comm)
            if P in by_k:
                row["measured_s_per_1000"] = 1e3 * per_step(by_k[P])
            rows_n.append(row)
        ref = rows_n[0]  # one rank: the same scene for strong and weak scaling
        for row in rows_n:
            P = row["ranks"]
            for k in DESIGNS:
                row[f"{k}_strong_efficiency"] = ref[f"{k}_s_per_1000"] / (P * row[f"{k}_s_per_1000"])
                row[f"{k}_weak_efficiency"] = ref[f"{k}_s_per_1000"] / row[f"weak_{k}_s_per_1000"]
        model_rows += rows_n

    print()
    print("Projected, per design: s/1000 = seconds per 1000 steps of the fixed scene, comm = its communication "
          "share, strong = t1/(P tP) (the fixed scene), weak = t1/tP (one copy of the scene per rank)")
    print(f"{'':6s} {'':5s} {'':8s} | {'':8s} | " + " | ".join(f"{d:^27s}" for d in DESIGNS) + " |")
    print(f"{'RBCs':>6s} {'ranks':>5s} {'grid':>8s} | {'measured':>8s} | "
          + " | ".join(f"{'s/1000':>8s} {'comm':>5s} {'strong':>6s} {'weak':>5s}" for _ in DESIGNS)
          + " | paper (Table 1)")
    for row in model_rows:
        n, P = row["rbcs"], row["ranks"]
        paper = ""
        if P > 1 and P in PAPER and n in PAPER[P]:
            paper = f"{PAPER[1][n]:.2f} / ({P} x {PAPER[P][n]:.2f}) = {100 * PAPER[1][n] / (P * PAPER[P][n]):.0f} %"
        tag = f"{n}" + ("" if row["height"] == FULL_HEIGHT else f" h{row['height']:g}")
        meas = f"{row['measured_s_per_1000']:8.3f}" if "measured_s_per_1000" in row else f"{'':8s}"
        print(f"{tag:>6s} {P:5d} {row['grid']:>8s} | {meas} | "
              + " | ".join(f"{row[d + '_s_per_1000']:8.3f} {100 * row[d + '_comm_share']:4.0f}% "
                           f"{100 * row[d + '_strong_efficiency']:5.0f}% {100 * row[d + '_weak_efficiency']:4.0f}%"
                           for d in DESIGNS) + f" | {paper}")
    print("  paper's Table 1 efficiency t1/(P tP) at 3 / 5 / 6 / 10 cores: "
          + "; ".join(f"{n} cells " + " / ".join(f"{100 * PAPER[1][n] / (P * PAPER[P][n]):.0f}"
                                                 for P in (3, 5, 6, 10)) + " %" for n in sorted(PAPER[1])))
    write_rows(args.model_csv, model_rows)


if __name__ == "__main__":
    main()
