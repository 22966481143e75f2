"""lbmd.System and its parts: cell_system, integrator, thermostat, actors,
analysis (ESPResSo 4.2 names)."""

import numpy as np

from . import _lbmd
from .constraints import Constraints
from .interactions import BondedInteractions, NonBondedInteractions
from .particle_data import ParticleList
from .validation import Param, check_not_metres, parse, positive, non_negative


#: runs shorter than this do not trigger the settings check of the first run
SETTINGS_CHECK_MIN_STEPS = 10


class CellSystem:
    """``system.cell_system``: neighbour search (linked cells + Verlet lists)."""

    def __init__(self, system):
        self._system = system
        self._node_grid = None
        self._balance = "fluid"

    @property
    def node_grid(self):
        """MPI ranks per axis of the fluid's subdomain grid, ``[nx, ny, nz]``.
        Unset (None) before a fluid is added, the grid is chosen then for the
        least halo per rank; set it before adding the fluid to choose it
        (the product must equal the number of ranks)."""
        fluid = self._system._core_fluid()
        if fluid is not None:
            return [int(n) for n in fluid.node_grid]
        return None if self._node_grid is None else list(self._node_grid)

    @node_grid.setter
    def node_grid(self, value):
        from mpi4py import MPI
        size = MPI.COMM_WORLD.Get_size()
        try:
            grid = [int(n) for n in value]
            ok = len(grid) == 3 and all(int(n) == n for n in value)
        except (TypeError, ValueError):
            ok = False
        if not ok or any(n < 1 for n in grid) or grid[0] * grid[1] * grid[2] != size:
            raise ValueError(f"cell_system.node_grid: expected 3 positive integers whose product is the "
                             f"number of MPI ranks ({size}), got {value!r}")
        if self._system._core_fluid() is not None:
            raise ValueError("cell_system.node_grid: set it before adding the lattice-Boltzmann fluid "
                             "(the fluid is split when it is added)")
        self._node_grid = grid

    @property
    def balance(self):
        """How the fluid's subdomain cuts are placed: "fluid" (default: the
        cuts move, when the boundaries are first set, so that every rank
        holds about as many fluid nodes) or "even" (equal slabs)."""
        return self._balance

    @balance.setter
    def balance(self, value):
        if value not in ("fluid", "even"):
            raise ValueError(f"cell_system.balance: expected 'fluid' or 'even', got {value!r}")
        self._balance = value

    @property
    def skin(self):
        return self._system._core.skin

    @skin.setter
    def skin(self, value):
        parse("cell_system", [Param("skin", "float", check=non_negative)], {"skin": value})
        self._system._core.skin = float(value)

    def set_regular_decomposition(self, use_verlet_lists=True, fully_connected_boundary=None):
        """Accepted for ESPResSo compatibility: this engine always uses linked
        cells with Verlet lists."""

    set_domain_decomposition = set_regular_decomposition

    def set_n_square(self, use_verlet_lists=True):
        """Accepted for ESPResSo compatibility (linked cells are used)."""

    def get_pairs(self, distance):
        """Sorted list of (id1, id2) with id1 < id2 of particles closer than
        distance (minimum image); distance may not exceed largest cutoff + skin."""
        d = parse("cell_system.get_pairs", [Param("distance", "float", check=positive)],
                  {"distance": distance})["distance"]
        return sorted(set(self._system._core.get_pairs(d)))

    @property
    def n_rebuilds(self):
        """Number of Verlet-list rebuilds so far."""
        return self._system._core.n_rebuilds

    def __repr__(self):
        return f"CellSystem(skin={self.skin}, node_grid={self.node_grid}, balance={self.balance!r})"


_TIMED_PHASES = (("membrane", "membrane: the cells' elastic moduli"),
                 ("bonded", "bonded: other bonds"),
                 ("non_bonded", "non-bonded: pair contacts"),
                 ("constraints", "constraints: walls"),
                 ("coupling", "thermostat: fluid coupling or Langevin"),
                 ("lb_fluid", "lattice-Boltzmann update"))


class Integrator:
    """``system.integrator``: velocity Verlet."""

    def __init__(self, system):
        self._system = system

    def run(self, steps=1, recalc_forces=False, reuse_forces=False, progress=False):
        """Integrate `steps` time steps (all in C++). progress=True: in chunks
        under a progress bar (simulated time, steps/s, time left) with a
        summary line at the end, rank 0 only (lbmd.progress); the same
        result bit for bit. Returns the summary line (progress=True) or None."""
        v = parse("integrator.run", [Param("steps", "int", check=non_negative),
                                     Param("recalc_forces", "bool"), Param("reuse_forces", "bool"),
                                     Param("progress", "bool")],
                  {"steps": steps, "recalc_forces": recalc_forces, "reuse_forces": reuse_forces,
                   "progress": progress})
        if v["progress"]:
            self._system._check_ready()
            from . import progress as _progress
            return _progress.run(self, v["steps"], v["recalc_forces"], v["reuse_forces"])
        self._system._check_ready()
        self._system.prepare()  # the run's collective set-up step, before anything reads the flags
        fluid = self._system._lb_fluid()
        if fluid is not None and len(fluid.open_boundaries):
            fluid.open_boundaries._before_run()
        if not self._system.__dict__.get("_settings_checked") and v["steps"] >= SETTINGS_CHECK_MIN_STEPS:
            # once, at the first run of SETTINGS_CHECK_MIN_STEPS steps or
            # more: the scene's choices against their measured limits,
            # warnings only (system.check_settings()). A shorter run (one
            # step to compute the forces, as ESPResSo's tests do before they
            # set the thermostat) cannot show an instability, and the scene
            # may not be complete yet.
            self._system.__dict__["_settings_checked"] = True
            from .settings_check import check_settings
            try:
                check_settings(self._system, warn=True)
            except Exception as e:  # a check must never stop a run
                import warnings
                warnings.warn(f"check_settings could not check the scene: {e}", RuntimeWarning)
        try:
            stopped = self._system._core.integrate(v["steps"], v["recalc_forces"], v["reuse_forces"],
                                                   _interruptible())
        finally:
            self._system._warn_drifted_cells()
        if fluid is not None:
            from .settings_check import watch_fluid_speed
            watch_fluid_speed(self._system, fluid)
        if stopped:  # a walltime signal (lbmd.checkpoint.stop_on_signal): save and exit
            from . import checkpoint
            checkpoint._after_stop()

    def set_vv(self):
        """Velocity Verlet (the only integrator; accepted for ESPResSo compatibility)."""

    def __repr__(self):
        s = self._system
        return (f"Integrator(velocity Verlet, time_step={s.time_step if s._time_step_set else None}, "
                f"step_count={s.step_count}, time={s.time:.6g})")

    #: the keys of ``timings()`` that divide its 'total' among the phases of
    #: a step (they add up to it)
    PHASES = tuple(key for key, _ in _TIMED_PHASES) + ("other",)

    def timings(self):
        """Where the time of the runs went, summed over all ``run()`` calls
        since the System was made or since ``reset_timings()``: a dict of
        wall-clock seconds, 'total' (all of ``run()``) and its parts
        'membrane' (the cells' elastic moduli), 'bonded' (other bonds),
        'non_bonded' (pair contacts),
        'constraints' (walls), 'coupling' (thermostat: particle-fluid
        coupling or Langevin forces), 'lb_fluid' (the lattice update) and
        'other' (velocity Verlet, neighbour lists, checks); 'steps': the
        steps run; 'communication': of 'total', the time in exchanges with
        other ranks, waiting included (the fluid's halo, the coupling's
        ghost velocities and forces).

        Under mpirun this is collective (call it on every rank): every rank
        gets the same dict, each value the largest over the ranks, with
        'per_rank' (each rank's own dict), 'busy_max' and 'busy_mean' (the
        largest and mean time a rank computed, 'total' less its
        'communication': their ratio is the load balance)."""
        from mpi4py import MPI
        t = self._system._core.run_timings()
        t["other"] = max(0.0, t["total"] - sum(t[k] for k, _ in _TIMED_PHASES))
        t["communication"] = max(0.0, self._communication_seconds() - self.__dict__.get("_comm_offset", 0.0))
        comm = MPI.COMM_WORLD
        if comm.Get_size() == 1:
            return t
        per_rank = comm.allgather(t)
        out = {k: max(r[k] for r in per_rank) for k in t}
        busy = [r["total"] - r["communication"] for r in per_rank]
        out.update(per_rank=per_rank, busy_max=max(busy), busy_mean=sum(busy) / len(busy))
        return out

    def _communication_seconds(self):
        fluid = self._system._core_fluid()
        return fluid.halo_seconds + fluid.coupling_exchange_seconds if fluid is not None else 0.0

    def reset_timings(self):
        """Start the sums of ``timings()`` again from zero."""
        self._system._core.reset_run_timings()
        self.__dict__["_comm_offset"] = self._communication_seconds()

    def timing_report(self):
        """``timings()`` as a table (seconds, milliseconds per step, share of
        the total), for printing after a run."""
        t = self.timings()
        steps, total = t["steps"], t["total"]
        lines = [f"{'phase':<44s} {'seconds':>10s} {'ms/step':>9s} {'share':>7s}"]
        for key, label in _TIMED_PHASES + (("other", "other: velocity Verlet, neighbour lists"),):
            per_step = 1e3 * t[key] / steps if steps else 0.0
            share = 100.0 * t[key] / total if total > 0 else 0.0
            lines.append(f"{label:<44s} {t[key]:10.3f} {per_step:9.3f} {share:6.1f}%")
        lines.append(f"{'total (' + str(steps) + ' steps)':<44s} {total:10.3f} "
                     f"{(1e3 * total / steps if steps else 0.0):9.3f} {100.0 if total > 0 else 0.0:6.1f}%")
        if "per_rank" in t:
            lines.append(f"MPI, {len(t['per_rank'])} ranks (each line: the largest over them); exchanges with other "
                         f"ranks {t['communication']:.3f} s; load balance (busy max/mean) "
                         f"{t['busy_max'] / t['busy_mean'] if t['busy_mean'] > 0 else 1.0:.3f}")
        return "\n".join(lines)


def _interruptible():
    """Whether a run may stop for Ctrl-C between steps: Python handles
    signals in the main thread only; under MPI one rank leaving alone would
    hang the others (mpirun ends the job instead); a script that ignores
    SIGINT, or left it to the default action, keeps that."""
    import signal
    import threading
    from mpi4py import MPI
    return (threading.current_thread() is threading.main_thread() and MPI.COMM_WORLD.Get_size() == 1
            and callable(signal.getsignal(signal.SIGINT)))


class Thermostat:
    """``system.thermostat``: Langevin (relaxation runs, tests) and the
    lattice-Boltzmann coupling (model eq. 1)."""

    def __init__(self, system):
        self._system = system
        self._lb = None

    def set_langevin(self, kT=None, gamma=None, seed=None):
        v = parse("thermostat.set_langevin",
                  [Param("kT", "float", check=non_negative), Param("gamma", "float", check=non_negative),
                   Param("seed", "seed", None, check=non_negative)],
                  {k: x for k, x in (("kT", kT), ("gamma", gamma), ("seed", seed)) if x is not None})
        if v["kT"] > 0 and v["seed"] is None:
            raise ValueError("thermostat.set_langevin: parameter 'seed' is required when kT > 0")
        self._system._core.set_langevin(v["kT"], v["gamma"], v["seed"] or 0)

    def set_lb(self, LB_fluid=None, gamma=None, seed=None, act_on_virtual=True, kT=None):
        """Couple all particles to the fluid LB_fluid with friction gamma.
        (ESPResSo <= 4.0: ``set_lb(kT=...)`` with the friction given to the
        fluid as LBFluid(fric=...): the active fluid and its fric.)"""
        from .lb import LBFluid
        if LB_fluid is not None and not isinstance(LB_fluid, LBFluid):
            raise TypeError("thermostat.set_lb: parameter 'LB_fluid' must be an lbmd.lb.LBFluid, "
                            f"got {type(LB_fluid).__name__}")
        if LB_fluid is None:
            old = [a for a in self._system.actors if getattr(a, "_old_fric", None) is not None]
            if old:
                from .old_names import warn_old_name
                warn_old_name("thermostat.set_lb(kT=...) with LBFluid(fric=...)",
                              "system.thermostat.set_lb(LB_fluid=lbf, gamma=...)")
                LB_fluid = old[0]
                gamma = old[0]._old_fric if gamma is None else gamma
        if kT is not None and (isinstance(kT, bool) or not isinstance(kT, (int, float, np.floating, np.integer))):
            raise TypeError(f"thermostat.set_lb: parameter 'kT' must be a number, got {kT!r}")
        if kT is not None and LB_fluid is not None and float(kT) != float(LB_fluid.kT):
            raise ValueError(f"thermostat.set_lb: parameter 'kT' ({kT}) differs from the fluid's kT "
                             f"({LB_fluid.kT}): the temperature is the fluid's, LBFluid(kT=..., seed=...)")
        if not isinstance(LB_fluid, LBFluid):
            raise TypeError("thermostat.set_lb: parameter 'LB_fluid' must be an lbmd.lb.LBFluid, "
                            f"got {type(LB_fluid).__name__}")
        v = parse("thermostat.set_lb", [Param("gamma", "float", check=non_negative),
                                        Param("seed", "seed", 0, check=non_negative)],
                  {k: x for k, x in (("gamma", gamma), ("seed", seed)) if x is not None})
        if LB_fluid.kT > 0 and seed is None:
            raise ValueError("thermostat.set_lb: parameter 'seed' is required when the fluid has kT > 0")
        if LB_fluid not in self._system.actors:
            raise ValueError("thermostat.set_lb: add the fluid first with system.actors.add(lbf)")
        self._system._core.set_lb_coupling(v["gamma"], v["seed"])
        self._lb = (LB_fluid, v["gamma"], v["seed"])

    def turn_off(self):
        self._system._core.langevin_off()
        if self._lb is not None:
            self._system._core.set_lb_coupling_off()
            self._lb = None

    def __repr__(self):
        state = self.get_state()
        if not state:
            return "Thermostat(off)"
        return "Thermostat(" + ", ".join(
            d["type"] + "(" + ", ".join(f"{k}={v}" for k, v in d.items() if k != "type") + ")"
            for d in state) + ")"

    def get_state(self):
        out = []
        lang = self._system._core.langevin
        if lang.active:
            out.append({"type": "LANGEVIN", "kT": lang.kT, "gamma": lang.gamma, "seed": lang.seed})
        if self._lb is not None:
            out.append({"type": "LB", "gamma": self._lb[1], "seed": self._lb[2]})
        return out


class Actors:
    """``system.actors``: the lattice-Boltzmann fluid (one at a time)."""

    def __init__(self, system):
        self._system = system
        self._list = []

    def add(self, actor):
        if not hasattr(actor, "_activate"):
            raise TypeError(f"actors.add: {type(actor).__name__} is not an actor")
        if actor in self._list:
            raise ValueError("actors.add: this actor is already active")
        actor._activate(self._system)
        self._list.append(actor)
        fric = getattr(actor, "_old_fric", None)
        if fric is not None and self._system.thermostat._lb is None:
            # LBFluid(fric=...) of ESPResSo <= 4.0: the particles coupled with
            # that friction as soon as the fluid was there; a coupling that
            # cannot be made takes the fluid out again
            try:
                self._system.thermostat.set_lb(LB_fluid=actor, gamma=fric, seed=actor.seed)
            except (TypeError, ValueError) as e:
                actor._deactivate(self._system)
                self._list.remove(actor)
                raise type(e)(f"actors.add: the coupling LBFluid(fric={fric:g}) asks for could not be made: "
                              f"{e}") from None
        return actor

    def remove(self, actor):
        if actor not in self._list:
            raise ValueError("actors.remove: this actor is not active")
        actor._deactivate(self._system)
        self._list.remove(actor)
        thermostat = self._system.thermostat
        if thermostat._lb is not None and thermostat._lb[0] is actor:
            # the coupling goes with its fluid; said aloud, since the cells
            # then stay where they are while the script runs on
            import warnings
            from .settings_check import SettingsWarning
            gamma = thermostat._lb[1]
            self._system._core.set_lb_coupling_off()
            thermostat._lb = None
            n = len(self._system.part.all())
            warnings.warn(f"actors.remove: the thermostat coupled the particles to this fluid (set_lb, gamma "
                          f"{gamma:g}); the coupling is switched off with it, so the {n} particles are no longer "
                          f"carried by any fluid. Add a fluid and call thermostat.set_lb again (or "
                          f"thermostat.set_langevin for particles without fluid)", SettingsWarning, stacklevel=2)

    def clear(self):
        for a in list(self._list):
            self.remove(a)

    def __contains__(self, actor):
        return any(a is actor for a in self._list)

    def __iter__(self):
        return iter(self._list)

    def __len__(self):
        return len(self._list)

    def __getitem__(self, i):
        return self._list[i]

    def __repr__(self):
        return f"Actors({self._list!r})"


class Analysis:
    """``system.analysis``: energies, momentum, distances."""

    def __init__(self, system):
        self._system = system

    def __repr__(self):
        return ("Analysis(energy(), linear_momentum(), min_dist(), center_of_mass(), oif_cell_sums(), "
                "oif_energies(), oif_forces())")

    # The membrane analysis calls (doc/interactions.md) take the bonded
    # interaction itself; the cell model (oif) reads its cells through them.
    def oif_cell_sums(self, interaction):
        """(mol_ids, areas, volumes) of the cells whose triangles carry this
        OifGlobalForces or OifOutDirection interaction, at the current
        positions; volumes are absolute."""
        s = self._system
        return s._core.oif_cell_sums(s.bonded_inter._id_of(interaction))

    def oif_energies(self, interaction, mol_id=-1):
        """dict term -> (mol_ids, energies) of an OifLocalForces or
        OifGlobalForces interaction; mol_id >= 0: of that cell's bonds only."""
        s = self._system
        return s._core.oif_energies(s.bonded_inter._id_of(interaction), mol_id)

    def oif_forces(self, interaction, term, mol_id=-1):
        """(ids, N x 3 forces) of one modulus of an OIF interaction
        ('stretching', 'bending', 'local_area', 'visc', 'global_area',
        'volume'), the particles' own forces untouched; mol_id >= 0: of that
        cell's bonds only."""
        s = self._system
        return s._core.oif_forces(s.bonded_inter._id_of(interaction), term, mol_id)

    def energy(self):
        """dict with 'total', 'kinetic', 'bonded', 'non_bonded' and
        ('bonded', id) per bonded interaction. Collective (begins with
        system.prepare())."""
        self._system.prepare()
        return self._system._core.energies()

    def linear_momentum(self, include_particles=True, include_lbfluid=True):
        p = np.zeros(3)
        if include_particles:
            p += self._system._core.particle_momentum()
        if include_lbfluid:
            self._system.prepare()  # collective: the fluid's total over its flagged nodes
            p += self._system._core.fluid_momentum()
        return p

    def min_dist(self, p1="default", p2="default"):
        """Smallest minimum-image distance between particles (of types p1, p2)."""
        part = self._system.part.all()
        pos, types = part.pos, part.type
        sel1 = np.ones(len(pos), bool) if p1 == "default" else np.isin(types, p1)
        sel2 = np.ones(len(pos), bool) if p2 == "default" else np.isin(types, p2)
        best = np.inf
        box = np.asarray(self._system.box_l)
        per = np.asarray(self._system.periodicity)
        for i in np.nonzero(sel1)[0]:
            d = pos[sel2] - pos[i]
            d[:, per] -= box[per] * np.round(d[:, per] / box[per])
            r = np.linalg.norm(d, axis=1)
            r = r[np.nonzero(sel2)[0] != i]
            if r.size:
                best = min(best, r.min())
        return float(best)

    def center_of_mass(self, p_type):
        sel = self._system.part.select(type=p_type)
        if len(sel) == 0:
            raise ValueError(f"analysis.center_of_mass: no particle of type {p_type!r}")
        m = sel.mass
        return (sel.pos * m[:, None]).sum(axis=0) / m.sum()


class CellDriftWarning(RuntimeWarning):
    """A cell's volume or surface drifted beyond system.cell_drift_tolerance."""


class System:
    """A simulation: box, particles, interactions, fluid, integrator.

    ``System(box_l=[Lx, Ly, Lz], periodicity=[True, True, True], time_step=None)``
    """

    _attributes = {"box_l", "periodicity", "time_step", "time", "min_global_cut", "max_oif_objects",
                   "cell_checks", "cell_drift_tolerance"}

    def prepare(self):
        """The explicit collective set-up step (every rank calls it under
        mpirun): flags the lattice for the boundaries added or removed since
        the last one, which may move the ranks' cuts (load balance) and the
        fluid with them. Every run begins with it, and so do the fluid's
        collective data calls (node reads and writes, totals, boundary
        forces, the interpolated velocity, VTK output, check_settings,
        checkpoints); the fluid's plain attributes (n_fluid_nodes,
        decomposition, ...) never communicate and raise while boundaries
        are pending. Nothing happens when nothing changed (doc/engine.md)."""
        self._core.prepare()

    @property
    def cells(self):
        """The cells a cell model (oif) made in this System and that are still
        in it, by cell_id (a tuple; lbmd.cell_registry)."""
        from .cell_registry import cells_of
        return cells_of(self)

    @property
    def lb_fluid(self):
        """The active lattice-Boltzmann fluid (lbmd.lb.LBFluid), or None."""
        return self._lb_fluid()

    def _lb_fluid(self):
        """The active LBFluid (Python object), or None."""
        from .lb import LBFluid
        for actor in self.__dict__.get("actors", ()):
            if isinstance(actor, LBFluid):
                return actor
        return None

    def _core_fluid(self):
        """The active fluid's C++ object, or None."""
        fluid = self._lb_fluid()
        return fluid._core if fluid is not None else None

    def __init__(self, **kwargs):
        v = parse("System", [Param("box_l", "vec3"), Param("periodicity", "bool3", [True, True, True]),
                             Param("time_step", "float", None, check=positive),
                             Param("min_global_cut", "float", 0.0, check=non_negative)], kwargs)
        if not np.all(v["box_l"] > 0):
            raise ValueError(f"System: parameter 'box_l' must be positive in every component, got {kwargs['box_l']!r}")
        check_not_metres("System: parameter 'box_l'", float(np.max(v["box_l"])))
        d = self.__dict__
        d["_core"] = _lbmd.System(v["box_l"], v["periodicity"])
        d["_time_step_set"] = False
        d["part"] = ParticleList(self)
        d["non_bonded_inter"] = NonBondedInteractions(self)
        d["bonded_inter"] = BondedInteractions(self)
        d["constraints"] = Constraints(self)
        d["cell_system"] = CellSystem(self)
        d["integrator"] = Integrator(self)
        d["thermostat"] = Thermostat(self)
        d["actors"] = Actors(self)
        d["analysis"] = Analysis(self)
        from .lbboundaries import LBBoundaries
        d["lbboundaries"] = LBBoundaries(self)
        d["min_global_cut"] = v["min_global_cut"]
        d["max_oif_objects"] = 0
        if v["time_step"] is not None:
            self.time_step = v["time_step"]

    def _check_box_change(self, box):
        """Refuse a box the fluid or the cells already made cannot follow."""
        from .lb import LBFluid
        if not np.array_equal(box, self.box_l) and any(isinstance(a, LBFluid) for a in self.actors):
            raise ValueError(f"System: parameter 'box_l' cannot change while a lattice-Boltzmann fluid is "
                             f"active (its lattice was made for box_l {self.box_l.tolist()}); remove the "
                             f"fluid (system.actors.remove), change the box, add a new fluid")
        self._check_cells_fit("box_l", box, box, self.periodicity)

    def _check_particles_inside(self, name, value, box, periodic):
        """Refuse a box or periodicity that leaves particles outside the box
        along an axis that is not periodic (as part.add refuses them)."""
        from .particle_data import outside_closed_axes
        if np.all(periodic) or len(self.part) == 0:
            return
        pos = self.part.all().pos
        found = outside_closed_axes(pos, box, periodic)
        if found is not None:
            k, axis, count = found
            raise ValueError(f"System: parameter '{name}' {np.asarray(value).tolist()} leaves "
                             f"{count} particles outside the box along the non-periodic "
                             f"{'xyz'[axis]} (particle id {int(self.part.all().id[k])} at {pos[k, axis]:g}); move "
                             f"them inside first")

    def _check_cells_fit(self, name, value, box, periodic):
        """Refuse a box or periodicity in which a cell the script holds would
        overlap its own periodic image."""
        for cell in self.cells:
            try:
                cell.check_fits(box, periodic)
            except ValueError as e:
                raise ValueError(f"System: parameter '{name}' {np.asarray(value).tolist()} does not fit "
                                 f"the cells: {e}") from None

    def _check_ready(self):
        if not self._time_step_set:
            raise RuntimeError("System: set system.time_step before integrating")

    def __setattr__(self, name, value):
        if name in ("box_l",):
            v = parse("System", [Param("box_l", "vec3")], {"box_l": value})["box_l"]
            if not np.all(v > 0):
                raise ValueError(f"System: parameter 'box_l' must be positive in every component, got {value!r}")
            check_not_metres("System: parameter 'box_l'", float(np.max(v)))
            self._check_box_change(v)
            self._check_particles_inside("box_l", v, v, self.periodicity)
            self._core.box_l = v
        elif name == "periodicity":
            v = parse("System", [Param("periodicity", "bool3")], {"periodicity": value})["periodicity"]
            self._check_cells_fit("periodicity", v, self.box_l, v)
            self._check_particles_inside("periodicity", v, self.box_l, v)
            self._core.periodicity = v
        elif name == "time_step":
            dt = parse("System", [Param("time_step", "float", check=positive)],
                       {"time_step": value})["time_step"]
            self._core.time_step = dt
            self.__dict__["_time_step_set"] = True
        elif name == "time":
            self._core.time = parse("System", [Param("time", "float")], {"time": value})["time"]
        elif name == "min_global_cut":
            self.__dict__[name] = parse("System", [Param("min_global_cut", "float", check=non_negative)],
                                        {name: value})[name]
        elif name == "cell_checks":
            self._core.cell_checks = parse("System", [Param("cell_checks", "bool")],
                                           {name: value})[name]
        elif name == "cell_drift_tolerance":
            self._core.cell_drift_tolerance = parse(
                "System", [Param("cell_drift_tolerance", "float", check=non_negative)],
                {name: value})[name]
        elif name == "max_oif_objects":
            self.__dict__[name] = parse("System", [Param("max_oif_objects", "int", check=non_negative)],
                                        {name: value})[name]
        else:
            raise AttributeError(f"System has no settable attribute '{name}'")

    @property
    def box_l(self):
        return np.array(self._core.box_l)

    @property
    def periodicity(self):
        return list(self._core.periodicity)

    @property
    def time_step(self):
        return self._core.time_step

    @property
    def time(self):
        return self._core.time

    @property
    def step_count(self):
        """MD steps integrated since the System was made (kept by checkpoints;
        the counter that keys the thermal noise). Read-only."""
        return int(self._core.step_count)

    @property
    def cell_checks(self):
        """Whether the steps of a run check the cells (default True): an
        inverted triangle or a volume below 1/4 or above 4 times the relaxed
        one raises SimulationInstability; a volume or surface that drifts
        beyond ``cell_drift_tolerance`` warns (CellDriftWarning)."""
        return self._core.cell_checks

    @property
    def cell_drift_tolerance(self):
        """Relative drift of a cell's volume or surface from its relaxed value
        that warns, once per cell and quantity (default 0.05; 0: never)."""
        return self._core.cell_drift_tolerance

    def check_settings(self):
        """Each modelling choice of the scene -- relaxation time, Mach number,
        precision, cells against agrid, mesh against agrid, time step against
        the membrane's stiffness, coupling, contacts -- with its value, the
        measured limit, the error to expect (doc/accuracy.md) and whether a
        cheaper setting would do. Returns a SettingsReport (a list of
        Setting; print it for the table). Collective under MPI."""
        from .settings_check import check_settings
        return check_settings(self)

    def _warn_drifted_cells(self):
        """CellDriftWarning for each note of the last run, on every rank (a
        cell is checked by the rank that owns it)."""
        import warnings
        from . import comm, size
        notes = self._core.take_drift_notes()
        if size > 1:
            notes = sorted(n for part in comm.allgather(notes) for n in part)
        for mol_id, quantity, ratio, time, step in notes:
            warnings.warn(
                f"cell with mol_id {mol_id}: its {quantity} drifted to {ratio:.4g} times the "
                f"relaxed value (tolerance {self.cell_drift_tolerance:g}) at step {step}, time "
                f"{time:g}; a cell squeezed by the flow or poorly held by its moduli (raise kv or "
                f"kag, lower the flow or the time step; system.cell_drift_tolerance sets the "
                f"threshold)", CellDriftWarning, stacklevel=3)

    # lbmd.checkpoint.save/load pickle the System (configuration) and write its
    # bulk state (particles, lattice) as datasets
    def __getstate__(self):
        from .checkpoint import system_state
        return system_state(self)

    def __setstate__(self, state):
        from .checkpoint import restore_system
        restore_system(self, state)

    def __repr__(self):
        return (f"System(box_l={self.box_l.tolist()}, periodicity={self.periodicity}, "
                f"time_step={self.time_step}, particles={len(self.part)})")
