"""Lattice-Boltzmann D3Q19 fluid (ESPResSo 4.2 ``espressomd.lb`` names).

``LBFluid(agrid=, dens=, visc=, tau=, bulk_visc=None, ext_force_density=[0, 0, 0],
kT=0, seed=None, collision="MRT", n_threads=0, single_precision=False)`` is an actor: add it with
``system.actors.add(lbf)``. Units are the MD units: agrid a length, tau the
lattice time step (an integer multiple of ``system.time_step``), dens mass per
volume, visc and bulk_visc kinematic viscosities (length^2 / time),
ext_force_density force per volume, kT energy. See doc/lb.md.
"""
import numbers

import numpy as np

from . import _lbmd
from .old_names import warn_old_name
from .validation import Param, ParameterObject, check_not_metres, non_negative, parse, positive

_COLLISIONS = ("MRT", "MRT_ESPRESSO", "TRT", "BGK")


def _cpus():
    """CPUs this process may run on (its affinity mask: a batch slot's share)."""
    import os
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _threads_param():
    # more threads than CPUs never helps the memory-bound kernel, but a
    # script written for a big node must still run on a laptop; absurd counts
    # are refused (a failed thread creation would end the interpreter
    # inside OpenMP)
    limit = max(256, 4 * _cpus())
    return Param("n_threads", "int", 0, check=(lambda n: 0 <= n <= limit, f"in 0..{limit}"))


#: lattice updates between two looks of the speed watch (lb/speed_watch.hpp):
#: 0.3-0.5 % of the update's time (doc/performance.md); the fluid's default
SPEED_WATCH_EVERY = 100


class LBFluid(ParameterObject):
    """D3Q19 lattice-Boltzmann fluid; collision 'MRT' (default; fluctuating
    MRT when kT > 0; odd ghost modes at the magic rate, so walls stay midway
    at any viscosity), 'MRT_ESPRESSO' (every ghost mode at rate 1, as
    ESPResSo 4.2), 'TRT' (magic parameter 3/16) or 'BGK'."""

    _params = [Param("agrid", "float", check=positive, doc="lattice spacing"),
               Param("dens", "float", check=positive, doc="mass density"),
               Param("visc", "float", check=positive, doc="kinematic viscosity"),
               Param("tau", "float", check=positive, doc="lattice time step"),
               Param("bulk_visc", "float", None, check=positive,
                     doc="kinematic bulk viscosity (MRT; default visc)"),
               Param("ext_force_density", "vec3", np.zeros(3), doc="force per volume"),
               Param("kT", "float", 0.0, check=non_negative, doc="thermal energy"),
               Param("seed", "seed", None, check=non_negative, doc="RNG seed (required if kT > 0)"),
               Param("collision", "object", "MRT", cls=str,
                     check=(lambda s: s.upper() in _COLLISIONS, "one of 'MRT', 'MRT_ESPRESSO', 'TRT', 'BGK'")),
               _threads_param(),
               Param("single_precision", "bool", False,
                     doc="store the populations as float deviations from the rest state at "
                         "dens and collide them in float (half the memory traffic)"),
               Param("speed_watch_every", "int", SPEED_WATCH_EVERY, check=non_negative,
                     doc="lattice updates between two looks for the fastest node during a run "
                         "(a warning past the advised Mach number; 0: off)")]

    def __init__(self, *args, **kwargs):
        # ESPResSo <= 4.0 gave the coupling's friction to the fluid,
        # LBFluid(..., fric=gamma); since 4.1 it is thermostat.set_lb's gamma.
        # Kept: the fluid couples with it when added (system.actors.add)
        fric = kwargs.pop("fric", None)
        if fric is not None:
            fric = parse("LBFluid", [Param("fric", "float", check=non_negative)], {"fric": fric})["fric"]
            warn_old_name("LBFluid(fric=...)", "system.thermostat.set_lb(LB_fluid=lbf, gamma=...)")
        super().__init__(*args, **kwargs)
        object.__setattr__(self, "_old_fric", fric)

    def _validate(self):
        check_not_metres("LBFluid: parameter 'agrid'", self.agrid)
        if self.kT > 0 and self.seed is None:
            raise ValueError("LBFluid: parameter 'seed' is required when kT > 0")
        v = self.__dict__["_values"]
        v["collision"] = v["collision"].upper()
        if v["bulk_visc"] is None:
            v["bulk_visc"] = v["visc"]
        if v["seed"] is None:
            v["seed"] = 0
        object.__setattr__(self, "_core", None)
        object.__setattr__(self, "_system", None)
        from .open_boundaries import OpenBoundaries
        #: velocity inlets and pressure outlets on the box's faces (lbmd.open_boundaries)
        object.__setattr__(self, "open_boundaries", OpenBoundaries(self))

    def _restore_core(self):
        # made again when the unpickled System activates it (lbmd.checkpoint)
        object.__setattr__(self, "_core", None)
        object.__setattr__(self, "_system", None)

    # --- actor protocol -------------------------------------------------------
    def _activate(self, system):
        if self._core is not None:
            raise ValueError("LBFluid: this fluid is already active in a system")
        if not system._time_step_set:
            raise ValueError("LBFluid: set system.time_step before adding the fluid "
                             "(tau must be an integer multiple of it)")
        if any(isinstance(a, LBFluid) for a in system.actors):
            raise ValueError("LBFluid: the system already has a lattice-Boltzmann fluid")
        core = _lbmd.LBFluid(agrid=self.agrid, tau=self.tau, dens=self.dens, visc=self.visc,
                             bulk_visc=self.bulk_visc, ext_force_density=self.ext_force_density,
                             kT=self.kT, seed=self.seed, collision=self.collision,
                             n_threads=self.n_threads, box_l=system.box_l,
                             node_grid=system.cell_system._node_grid or [0, 0, 0],
                             balance=system.cell_system.balance == "fluid",
                             single_precision=self.single_precision)
        # (a checkpoint of an older version has no speed_watch_every)
        core.speed_watch_every = self.__dict__["_values"].get("speed_watch_every", SPEED_WATCH_EVERY)
        system.lbboundaries._apply(core)
        system._core.set_lb(core)
        object.__setattr__(self, "_core", core)
        object.__setattr__(self, "_system", system)
        self.open_boundaries._apply()

    def _deactivate(self, system):
        system._core.set_lb(None)
        object.__setattr__(self, "_core", None)
        object.__setattr__(self, "_system", None)

    def _checked_core(self):
        if self._core is None:
            raise RuntimeError("LBFluid: add the fluid to a system first (system.actors.add(lbf))")
        return self._core

    def _collective_core(self):
        """The core for a collective data access (node reads and writes,
        totals, the interpolated velocity, output): system.prepare() first,
        so that boundaries added since the last run are flagged."""
        core = self._checked_core()
        self._system.prepare()
        return core

    # --- properties -------------------------------------------------------------
    @property
    def shape(self):
        """Number of lattice nodes per axis."""
        return tuple(int(n) for n in self._checked_core().shape)

    def __setattr__(self, name, value):
        if name == "ext_force_density":
            f = Param("ext_force_density", "vec3").convert("LBFluid", value)
            if self._core is not None:
                self._core.set_ext_force_density(f)
            self.__dict__["_values"]["ext_force_density"] = f
        elif name == "n_threads":
            n = _threads_param().convert("LBFluid", value)
            if self._core is not None:
                self._core.n_threads = n
            self.__dict__["_values"]["n_threads"] = n
        else:
            raise AttributeError(f"LBFluid: '{name}' cannot be set after creation "
                                 "(settable: ext_force_density, n_threads)")

    def total_mass(self):
        return self._collective_core().total_mass()

    def total_momentum(self):
        """Momentum of the fluid (see doc/lb.md for the half-force convention):
        the coupling's impulse still in flight to the particles excluded."""
        self._collective_core()
        return np.asarray(self._system._core.fluid_momentum())

    def get_interpolated_velocity(self, pos):
        """Fluid velocity at pos, trilinear in the 8 surrounding nodes."""
        p = Param("pos", "vec3").convert("LBFluid.get_interpolated_velocity", pos)
        self._collective_core()
        return np.asarray(self._system._core.lb_interpolated_velocity(p))

    def write_vtk_velocity(self, path):
        """Legacy VTK structured points (ParaView) of the node velocities."""
        self._collective_core().write_vtk_velocity(_path(path))

    def write_vtk_boundary(self, path):
        """Legacy VTK structured points of the boundary flags (0 fluid, b + 1 boundary b)."""
        self._collective_core().write_vtk_boundary(_path(path))

    # --- ESPResSo <= 4.1 names (lbmd.old_names) ------------------------------
    def print_vtk_velocity(self, path, bb1=None, bb2=None):
        """ESPResSo <= 4.1 name of write_vtk_velocity (warns once). The
        sub-box ``bb1``, ``bb2`` of ESPResSo is not supported: the whole
        lattice is written."""
        warn_old_name("LBFluid.print_vtk_velocity", "LBFluid.write_vtk_velocity")
        for name, value in (("bb1", bb1), ("bb2", bb2)):
            if value is not None:
                raise ValueError(f"LBFluid.print_vtk_velocity: parameter '{name}' (a sub-box) is not "
                                 "supported: the whole lattice is written; leave bb1 and bb2 out")
        self.write_vtk_velocity(path)

    def print_vtk_boundary(self, path):
        """ESPResSo <= 4.1 name of write_vtk_boundary (warns once)."""
        warn_old_name("LBFluid.print_vtk_boundary", "LBFluid.write_vtk_boundary")
        self.write_vtk_boundary(path)

    def __getitem__(self, key):
        return LBFluidRoutines(self, key)


def _path(path):
    import os
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"LBFluid: path must be a string, got {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str) or not path or "\0" in path:  # C would cut the name at a NUL
        raise ValueError(f"LBFluid: path must be a non-empty file name without NUL characters, got {path!r}")
    return path


class LBFluidRoutines:
    """Nodes ``lbf[i, j, k]`` (integers or slices): velocity, density,
    population (19 values, ESPResSo/DSL order), boundary (0 fluid, b + 1 for
    the b-th LBBoundary), pressure_tensor (3 x 3, sum_q c c f). Setting a
    slice sets its fluid nodes (boundary nodes are skipped); setting a single
    boundary node is an error."""

    _shapes = {"velocity": (3,), "density": (), "boundary": (), "population": (19,),
               "pressure_tensor": (3, 3)}

    def __init__(self, fluid, key):
        shape = fluid.shape
        if not isinstance(key, tuple) or len(key) != 3:
            raise IndexError("LBFluid: index with three indices or slices, lbf[i, j, k]")
        self._fluid = fluid
        self._lo, self._hi, self._sub, self._drop = [], [], [], []
        for axis, (k, n) in enumerate(zip(key, shape)):
            if isinstance(k, slice):
                r = range(*k.indices(n))
                if len(r) == 0:
                    raise IndexError(f"LBFluid: empty slice on axis {axis}")
                lo, hi = min(r), max(r) + 1
                self._sub.append(slice(r.start - lo, None, r.step) if r.step > 0
                                 else slice(r.start - lo, None, r.step))
                self._drop.append(False)
            elif isinstance(k, numbers.Integral) and not isinstance(k, bool):
                if not 0 <= k < n:
                    raise IndexError(f"LBFluid: node index {k} on axis {axis} out of range [0, {n})")
                lo, hi = int(k), int(k) + 1
                self._sub.append(slice(None))
                self._drop.append(True)
            else:
                raise IndexError(f"LBFluid: index on axis {axis} must be an integer or a slice, "
                                 f"got {k!r}")
            self._lo.append(lo)
            self._hi.append(hi)

    def _get(self, prop):
        block = np.asarray(self._fluid._collective_core().get_block(prop, self._lo, self._hi))
        block = block[tuple(self._sub)]
        block = block.reshape(block.shape[:3] + self._shapes[prop])
        idx = tuple(0 if d else slice(None) for d in self._drop)
        out = block[idx]
        if out.ndim == 0:
            return int(out) if prop == "boundary" else float(out)
        return out.astype(int) if prop == "boundary" else out

    def _set(self, prop, value):
        core = self._fluid._collective_core()
        full = np.asarray(core.get_block(prop, self._lo, self._hi))
        full = full.reshape(full.shape[:3] + self._shapes[prop])
        try:
            value = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"LBFluid: {prop} must be numeric") from None
        if not np.all(np.isfinite(value)):
            raise ValueError(f"LBFluid: {prop} must be finite")
        idx = tuple(0 if d else s for d, s in zip(self._drop, self._sub))
        target_shape = full[idx].shape
        try:
            full[idx] = np.broadcast_to(value, target_shape)
        except ValueError:
            raise ValueError(f"LBFluid: {prop} of shape {value.shape} does not fit the "
                             f"selected nodes, shape {target_shape}") from None
        if prop == "density" and np.any(value <= 0):
            raise ValueError("LBFluid: density must be > 0")
        if prop == "population" and np.any(full[idx].sum(axis=-1) <= 0):
            raise ValueError("LBFluid: the populations of a node must add up to a density > 0")
        core.set_block(prop, self._lo, self._hi, np.ascontiguousarray(full))

    velocity = property(lambda self: self._get("velocity"),
                        lambda self, v: self._set("velocity", v))
    density = property(lambda self: self._get("density"),
                       lambda self, v: self._set("density", v))
    population = property(lambda self: self._get("population"),
                          lambda self, v: self._set("population", v))
    boundary = property(lambda self: self._get("boundary"))
    pressure_tensor = property(lambda self: self._get("pressure_tensor"))

    def __setattr__(self, name, value):
        # a misspelt property (lbf[0, 0, 0].vel = ...) would otherwise be
        # stored on this temporary object and change nothing
        if name.startswith("_") or name in ("velocity", "density", "population"):
            object.__setattr__(self, name, value)
        elif name in self._shapes:
            raise AttributeError(f"LBFluid: node property '{name}' is read-only")
        else:
            raise AttributeError(f"LBFluid: nodes have no property '{name}' (settable: velocity, "
                                 f"density, population; readable also: boundary, pressure_tensor)")
