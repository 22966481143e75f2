"""``system.integrator.run(steps, progress=True)``: the run in chunks under a
tqdm bar (Debian's python3-tqdm: simulated time, steps/s, time left) and a
one-line summary at the end (wall time, steps/s, MLUPS with a fluid, the
cells' share with oif cells). The chunks are ordinary ``run()`` calls, whose
results equal one long run bit for bit (System::integrate keeps the forces
of the last step across calls). Under MPI rank 0 alone prints; it chooses
the chunk lengths and tells the other ranks, so that every rank makes the
same calls.

``Bar(total, initial=0, mode="auto")`` is the bar itself, for a script
that runs in its own loop (output between runs): ``bar.update(n,
postfix="...")`` after each run, ``bar.close()`` at the end."""
import sys
import time as wallclock

#: wall seconds one chunk aims at (the bar's refresh interval)
CHUNK_SECONDS = 0.5


def _cells(system):
    """The number of live cells of system (lbmd.cell_registry; 0 when no
    cell model made any). Collective under MPI (every rank calls at the end
    of the run)."""
    try:
        return len(system.cells)
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
        parts.append(f"{n_cells} cell{'s' if n_cells > 1 else ''}: {1000.0 * cells_s / n_cells / steps:.4f} s "
                     f"per cell per 1000 steps (membrane and contacts)")
    return "; ".join(parts)


class Bar:
    """Progress of a run of ``total`` steps, on rank 0 only (other ranks: no
    output). mode: "bar" (a tqdm bar on stderr: steps, steps/s, time left and
    a postfix), "lines" (a line on stdout every ``every`` seconds and at the
    end: steps, steps/s, time left, postfix; for logs), "off", or "auto"
    (a bar on a terminal, lines otherwise). Without tqdm, "bar" becomes
    "lines" with a note."""

    MODES = ("auto", "bar", "lines", "off")

    def __init__(self, total, initial=0, mode="auto", every=10.0):
        from . import rank
        if mode not in self.MODES:
            raise ValueError(f"progress: mode must be one of {', '.join(self.MODES)}, got {mode!r}")
        if mode == "auto":
            mode = "bar" if sys.stderr.isatty() else "lines"
        self.mode = mode if rank == 0 else "off"
        self.total, self.done, self.start, self.every = int(total), int(initial), int(initial), float(every)
        self.started = self.said = wallclock.monotonic()
        self._tqdm = None
        if self.mode == "bar":
            try:
                from tqdm import tqdm
            except ImportError:  # pragma: no cover - python3-tqdm is a dependency
                print("(no progress bar: Debian's python3-tqdm is not installed; a line every "
                      f"{self.every:g} s instead)")
                self.mode = "lines"
            else:
                self._tqdm = tqdm(total=self.total, initial=self.done, unit="step", dynamic_ncols=True,
                                  mininterval=0.5 if sys.stderr.isatty() else 30.0,
                                  bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} steps [{elapsed}<{remaining}, "
                                             "{rate_fmt}{postfix}]")

    def update(self, n, postfix=""):
        """n more steps done; postfix: what to show beside them."""
        self.done += int(n)
        if self._tqdm is not None:
            self._tqdm.update(int(n))
            if postfix:
                self._tqdm.set_postfix_str(postfix, refresh=False)
        elif self.mode == "lines" and (wallclock.monotonic() - self.said >= self.every or self.done >= self.total):
            self.said = wallclock.monotonic()
            elapsed = self.said - self.started
            rate = (self.done - self.start) / elapsed if elapsed > 0 else 0.0
            left = (self.total - self.done) / rate if rate > 0 else 0.0
            print(f"{self.done}/{self.total} steps  {rate:7.0f} steps/s  {left:6.0f} s left"
                  + (f"  {postfix}" if postfix else ""), flush=True)

    def close(self):
        if self._tqdm is not None:
            self._tqdm.close()
            self._tqdm = None


def run(integrator, steps, recalc_forces, reuse_forces, out=None):
    """integrator.run(steps) in chunks of about CHUNK_SECONDS under a Bar
    (rank 0; "bar" mode), then the summary line on rank 0's stdout (or out)."""
    from . import comm, rank, size
    system = integrator._system
    before = integrator.timings()
    t0 = system.time
    end = t0 + steps * system.time_step
    bar = Bar(steps, mode="bar")
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
                bar.update(n, postfix=f"time {system.time:.6g} of {end:.6g}")
            if size > 1:
                chunk = comm.bcast(chunk, root=0)
    finally:
        bar.close()
    wall = wallclock.perf_counter() - started
    after = integrator.timings()
    line = summary(system, steps, wall, before, after, t0)
    if rank == 0:
        print(line, file=out or sys.stdout, flush=True)
    return line
