"""``system.integrator.run(steps, progress=True)``: the run in chunks under a
tqdm bar (Debian's python3-tqdm: simulated time, steps/s, time left) and a
one-line summary at the end (wall time, steps/s, MLUPS with a fluid, the
cells' share with oif cells). The chunks are ordinary ``run()`` calls, whose
results equal one long run bit for bit (System::integrate keeps the forces
of the last step across calls). Under MPI rank 0 alone prints; it chooses
the chunk lengths and tells the other ranks, so that every rank makes the
same calls."""
import sys
import time as wallclock

#: wall seconds one chunk aims at (the bar's refresh interval)
CHUNK_SECONDS = 0.5


def _cells(system):
    """The number of live oif cells of system (0 when oif is not in use).
    Collective under MPI (every rank calls at the end of the run)."""
    oif_classes = sys.modules.get("oif.oif_classes")
    if oif_classes is None:
        return 0
    try:
        return len(oif_classes.live_cells(system))
    except Exception:  # a count for a summary line must never stop a run
        return 0


def summary(system, steps, wall, before, after, t0):
    """The line printed after a run: steps, wall time, rate, the fluid's MLUPS
    (lattice nodes times lattice updates per second), the cells' membrane
    and contact time per cell per 1000 steps (from integrator.timings())."""
    t1 = system.time
    rate = steps / wall if wall > 0 else float("inf")
    parts = [f"integrator.run: {steps} steps (time {t0:.6g} -> {t1:.6g}) in {wall:.3f} s, {rate:.1f} steps/s"]
    fluid = system._lb_fluid()
    if fluid is not None and steps:
        shape = fluid.shape
        nodes = shape[0] * shape[1] * shape[2]
        updates = steps / max(1, int(round(fluid.tau / system.time_step)))
        parts.append(f"fluid {nodes * updates / wall / 1e6:.2f} MLUPS ({shape[0]}x{shape[1]}x{shape[2]} nodes)"
                     if wall > 0 else "fluid")
    n_cells = _cells(system)
    if n_cells and steps:
        cells_s = sum(after[k] - before[k] for k in ("membrane", "non_bonded"))
        parts.append(f"{n_cells} cell{'s' if n_cells > 1 else ''}: {1000.0 * cells_s / n_cells / steps:.4f} s per cell per 1000 steps "
                     f"(membrane and contacts)")
    return "; ".join(parts)


def run(integrator, steps, recalc_forces, reuse_forces, out=None):
    """integrator.run(steps) in chunks of about CHUNK_SECONDS under a bar
    (rank 0), then the summary line on rank 0's stdout (or out)."""
    from . import comm, rank, size
    system = integrator._system
    before = integrator.timings()
    t0 = system.time
    bar = None
    if rank == 0:
        try:
            from tqdm import tqdm
        except ImportError:  # pragma: no cover - python3-tqdm is a dependency
            tqdm = None
        if tqdm is not None:
            end = system.time + steps * system.time_step
            tty = sys.stderr.isatty()
            bar = tqdm(total=steps, unit="step", dynamic_ncols=True, mininterval=0.5 if tty else 30.0,
                       bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} steps [{elapsed}<{remaining}, "
                                  "{rate_fmt}{postfix}]")
            bar.set_postfix_str(f"time {system.time:.6g} of {end:.6g}", refresh=False)
    started = wallclock.perf_counter()
    done, chunk, first = 0, 1, True
    try:
        while done < steps or first:  # 0 steps: one run(0), as without progress
            n = min(chunk, steps - done)
            t = wallclock.perf_counter()
            # the first chunk alone carries the caller's choice about the forces
            integrator.run(n, recalc_forces=recalc_forces and first, reuse_forces=reuse_forces and first)
            first = False
            done += n
            if rank == 0 and n:
                spent = wallclock.perf_counter() - t
                per_step = spent / n if spent > 0 else 0.0
                chunk = max(1, min(2 * chunk + 1, int(CHUNK_SECONDS / per_step) if per_step > 0 else 2 * chunk))
                if bar is not None:
                    bar.update(n)
                    bar.set_postfix_str(f"time {system.time:.6g} of {end:.6g}", refresh=False)
            if size > 1:
                chunk = comm.bcast(chunk, root=0)
    finally:
        if bar is not None:
            bar.close()
    wall = wallclock.perf_counter() - started
    after = integrator.timings()
    line = summary(system, steps, wall, before, after, t0)
    if rank == 0:
        print(line, file=out or sys.stdout, flush=True)
    return line
