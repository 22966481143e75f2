#!/usr/bin/env pyoif
"""Communication per time step of the two ownership models of membrane
nodes under MPI domain decomposition, for the PyOIF paper's bifurcation
scene (box 160 x 40 x 22 um, 60 RBCs of radius 3.91 um with 374 nodes, the
rare cell of radius 7.5 um with 642 nodes), at 2, 8 and 64 ranks. The
numbers behind the decision in doc/architecture.md ("Parallel model").

    pyoif maintainer/benchmarks/ownership_model.py [--seeds 10] [--csv ownership_model.csv]

(a) node ownership (ESPResSo): every node belongs to the rank whose
    subdomain holds it; a bond is evaluated by the rank of its first node,
    which needs the bond's other nodes as ghosts (positions in, forces back,
    every step), and the cells' surfaces and volumes are summed over ranks
    (one allreduce per step for all cells).
(b) whole-cell evaluation: every node is stored, integrated, coupled to the
    fluid and in contact where it is (as in (a)), but each cell's membrane is
    evaluated whole by one rank, the owner of the cell's first node: the
    cell's nodes held by other ranks send their positions to it and get
    their forces and normals back (neighbour messages, no collective).

Both need the ordinary ghost exchange of the contacts (positions out,
forces back) anyway; what is counted here is what each model adds to it.
(a) sends its bond ghosts with the ghost exchange (no extra message) and
adds one allreduce; (b) sends the remote nodes' positions with the ghost
exchange and their forces with the reverse force exchange, and adds one
round of neighbour messages for the normals (membrane collision needs them
before the pair forces).

Cells are seeded at random (uniform centres in the channel, random
orientation, no overlap test) and the figures averaged over --seeds
placements; the subdomain grid is the one with the least cut area (as the
automatic choice will be). Bytes: 8 per double; positions and forces 3
doubles, normals 3 more. The time model (latency alpha per round of
concurrent neighbour messages, bandwidth beta per rank, allreduce 2 log2(P)
alpha) gives the order of magnitude, not a measurement. Per rank: the
busiest rank (most bytes).
"""
import argparse
import csv

import numpy as np

import oif
from oif import mesh_io

BOX = np.array([160.0, 40.0, 22.0])
ALPHA = 1.5e-6  # s per message (InfiniBand-class network)
BETA = 10e9     # bytes per s
DOUBLES = 8


def best_grid(ranks):
    """The grid (nx, ny, nz) with nx ny nz = ranks and the least total cut area."""
    best = None
    for nx in range(1, ranks + 1):
        for ny in range(1, ranks // nx + 1):
            if ranks % (nx * ny):
                continue
            nz = ranks // (nx * ny)
            grid = np.array([nx, ny, nz])
            area = sum(grid[d] * np.prod(np.delete(BOX, d)) for d in range(3) if grid[d] > 1)
            if best is None or area < best[0]:
                best = (area, grid)
    return best[1]


def mesh(name, radius):
    data = mesh_io.read_mesh(*oif.mesh_files(name), resize=(radius, radius, radius))
    nodes, tris = data.nodes, np.asarray(data.triangles)
    edges = set()
    for a, b, c in tris:
        edges.update({tuple(sorted(e)) for e in ((a, b), (b, c), (c, a))})
    # the local bonds (B, A, C, D): one per edge with its two wings
    wing = {}
    for a, b, c in tris:
        for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):
            wing.setdefault(tuple(sorted((u, v))), []).append(w)
    bonds = [(u, wing[(u, v)][0], v, wing[(u, v)][1]) for u, v in sorted(edges)]
    return nodes, np.asarray(tris), np.asarray(bonds)


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def scene(rng):
    """(cell node positions, its mesh) per cell: 60 RBCs and the rare cell."""
    rbc, rare = mesh("rbc374", 3.91), mesh("sphere642", 7.5)
    cells = []
    for k, m in enumerate([rbc] * 60 + [rare]):
        lo = np.array([0.0, 5.0 + 4.0, 1.0 + (1.5 if k < 60 else 7.6)])
        hi = np.array([BOX[0], 35.0 - 4.0, BOX[2] - lo[2]])
        centre = rng.uniform(lo, np.maximum(hi, lo + 1e-9))
        cells.append(((m[0] @ random_rotation(rng).T + centre) % BOX, m))
    return cells


def rank_of(x, grid):
    cell = np.minimum((x / (BOX / grid)).astype(int), grid - 1)
    return (cell[:, 0] * grid[1] + cell[:, 1]) * grid[2] + cell[:, 2]


def measure(ranks, rng):
    grid = best_grid(ranks)
    straddling = ghost_nodes = remote_nodes = 0
    bytes_a = np.zeros(ranks)  # per rank: received and sent
    bytes_b = np.zeros(ranks)
    cells_of = np.zeros(ranks)
    for x, (nodes, tris, bonds) in scene(rng):
        owner = rank_of(x, grid)
        straddling += len(np.unique(owner)) > 1
        # (a) ghosts: (evaluating rank, node) pairs of bonds whose nodes lie
        #     elsewhere: positions in, forces back
        need = set()
        for group in (bonds, tris):
            for row in group:
                r = owner[row[0]]
                need.update((r, v) for v in row[1:] if owner[v] != r)
        ghost_nodes += len(need)
        for r, v in need:
            bytes_a[r] += 2 * 3 * DOUBLES
            bytes_a[owner[v]] += 2 * 3 * DOUBLES
        # (b) the cell's nodes held by other ranks than its evaluating one:
        #     positions in, forces and normals back
        evaluator = owner[0]
        cells_of[evaluator] += 1
        remote = owner[owner != evaluator]
        remote_nodes += len(remote)
        bytes_b[evaluator] += len(remote) * 9 * DOUBLES
        np.add.at(bytes_b, remote, 9 * DOUBLES)
    allreduce = 2 * np.log2(ranks) * ALPHA
    return dict(ranks=ranks, grid="x".join(map(str, grid)), straddling=straddling,
                a_ghost_nodes=ghost_nodes, a_kB_per_rank=bytes_a.max() / 1e3,
                a_time_us=1e6 * (bytes_a.max() / BETA + allreduce),
                b_remote_nodes=remote_nodes, b_kB_per_rank=bytes_b.max() / 1e3,
                b_time_us=1e6 * (bytes_b.max() / BETA + ALPHA),
                b_most_cells_on_a_rank=cells_of.max())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--csv", default=None)
    args = ap.parse_args()
    rows = []
    for ranks in (2, 8, 64, 1024):
        samples = [measure(ranks, np.random.default_rng(seed)) for seed in range(args.seeds)]
        row = {k: samples[0][k] for k in ("ranks", "grid")}
        row.update({k: float(np.mean([s[k] for s in samples])) for k in samples[0] if k not in row})
        rows.append(row)
        print(f"{ranks:3d} ranks (grid {row['grid']}): {row['straddling']:.1f} of 61 cells straddle a border")
        print(f"    (a) node ownership: {row['a_ghost_nodes']:.0f} bond ghosts, {row['a_kB_per_rank']:.1f} kB on "
              f"the busiest rank + 1 allreduce: ~{row['a_time_us']:.0f} us per step")
        print(f"    (b) whole cells:    {row['b_remote_nodes']:.0f} remote nodes, {row['b_kB_per_rank']:.1f} kB on "
              f"the busiest rank + 1 neighbour round: ~{row['b_time_us']:.0f} us per step; "
              f"up to {row['b_most_cells_on_a_rank']:.1f} cells evaluated by one rank")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
