"""Checkpoints: the whole state of a simulation in one HDF5 file, and a run
continued from it bit for bit.

``lbmd.checkpoint.save(path, system, **objects)`` writes everything the next
time step depends on -- box, time step, interactions and their parameters,
shapes, constraints, boundaries, thermostats, the fluid's populations, the
coupling's force field and its momentum ledger, the particles as stored
(folded positions with image counters, velocities, forces and normals of the
last step, types, mol ids, masses, external forces, fixed coordinates),
bonds with their reference values, exclusions, the pair list's reference
positions, and the step counter that keys every random number (the random
numbers are counter based: no generator state exists beyond the seeds and
the counter) -- plus any named Python objects (``oif`` cell types and cells,
a script's own state; anything picklable). ``ns = lbmd.checkpoint.load(path)``
returns them as attributes (``ns.system``, ``ns.cells``, ...), ready to run:
``ns.system.integrator.run(n)`` then gives bit for bit what the saved run
would have given at the same number of MPI ranks, and the same state to
round-off at another rank count.

The file (format "pyoif-checkpoint", version FORMAT_VERSION): HDF5 after a
user block of 512 bytes that holds the SHA-256 of the rest (checked before
anything is read: a damaged or truncated copy is refused; after editing a
checkpoint with h5py, ``lbmd.checkpoint.seal(path)`` writes it again);

- ``/`` attributes ``format``, ``version``, ``ranks`` (of the saving run),
  ``step``, ``time``, ``created``;
- ``/objects``: the pickled Python objects (configuration; bulk arrays are
  datasets, referred to by name);
- ``/system0/particles/<field>`` (local order), ``/system0/bonds/<id>/ids``
  and ``per_bond``, ``/system0/fluid/stored_population`` (nodes x, y, z, 19:
  the values as stored, float deviations from the rest state in single
  precision) and ``coupling_field`` (nodes, 4: deposited since the last
  update (1/0) and the 3 values), readable with h5py for inspection.

Under mpirun every rank calls save and load (collective): the particles are
replicated, the lattice is gathered with the node-block access, rank 0
writes (under a temporary name, renamed at the end: the previous checkpoint
stays until the new one is complete), rank 0 reads and hands the file to the
others.

Walltime: ``lbmd.checkpoint.stop_on_signal(path, system, **objects)`` makes
SIGTERM and SIGUSR1 end the run: the current step finishes, the ranks agree
on the step, a checkpoint is written to `path` and the process exits with
EXIT_CHECKPOINTED (75, EX_TEMPFAIL: "try again", as batch systems read it).
"""
import os
import pickle
import signal
import sys
import time as _time
import types

import numpy as np

from . import _lbmd

FORMAT = "pyoif-checkpoint"
FORMAT_VERSION = 1
#: exit status after a walltime signal's checkpoint (EX_TEMPFAIL of sysexits.h)
EXIT_CHECKPOINTED = 75

# While save() or load() pickles, the bulk arrays of each System go here
# (name -> numpy array) instead of into the pickle stream.
_context = None


class CheckpointError(ValueError):
    """A checkpoint file that cannot be loaded: missing, truncated, foreign,
    or of another format version (the message names the file and why)."""


# --- what a System saves and restores (System.__getstate__/__setstate__) ------
def system_state(system):
    """The System's pickled state: its Python parts and the configuration of
    its C++ core; the bulk arrays go to the active save's dataset table."""
    if _context is None:
        raise TypeError("an lbmd.System is saved with lbmd.checkpoint.save(path, system, ...), "
                        "not pickled alone (its particles and fluid live in C++)")
    core = system._core
    prefix = f"system{len(_context['systems'])}"
    _context["systems"].append(prefix)
    arrays = _context["arrays"]
    part = core.checkpoint_particles()
    for name, value in part.items():
        arrays[f"{prefix}/particles/{name}"] = np.asarray(value)
    for bond_id in range(len(system.bonded_inter)):
        arrays[f"{prefix}/bonds/{bond_id}/ids"] = np.asarray(core.get_bonds(bond_id))
        arrays[f"{prefix}/bonds/{bond_id}/per_bond"] = np.asarray(core.bond_reference_values(bond_id))
    nonbonded = []
    from .interactions import NONBONDED_MODELS
    n_types = core.nonbonded_n_types
    for name, cls in NONBONDED_MODELS.items():
        getter = getattr(core, "get_" + name)
        for t1 in range(n_types):
            for t2 in range(t1, n_types):
                p = getter(t1, t2)
                values = {q.name: getattr(p, q.name) for q in cls._params}
                if any(v != 0 for v in values.values()):
                    nonbonded.append((name, t1, t2, values))
    fluid = system._core_fluid()
    fluid_state = None
    if fluid is not None:
        system.prepare()  # collective: populations of the flagged lattice
        shape = tuple(int(n) for n in fluid.shape)
        for prop in ("stored_population", "coupling_field"):
            # on the writing rank only (rank 0): the others send their own
            # nodes and hold no more (an empty array there, never written)
            arrays[f"{prefix}/fluid/{prop}"] = np.asarray(fluid.gather_block(prop, [0, 0, 0], list(shape), 0))
        any_deposit, ledger_step, in_flight = core.coupling_ledger_state()
        fluid_state = {"n_updates": int(fluid.n_updates), "ledger": (bool(any_deposit), int(ledger_step),
                                                                     tuple(in_flight)),
                       "open_gains": list(fluid.open_boundary_gains())}
    lang = core.langevin
    state = {k: v for k, v in system.__dict__.items() if k != "_core"}
    state["_checkpoint"] = {
        "prefix": prefix, "box_l": list(core.box_l), "periodicity": list(core.periodicity),
        "time_step": core.time_step, "time": core.time, "step_count": int(core.step_count),
        "lb_substep": int(core.lb_substep), "forces_valid": bool(core.forces_valid), "skin": core.skin, "cell_checks": core.cell_checks,
        "cell_drift_tolerance": core.cell_drift_tolerance,
        "langevin": (bool(lang.active), lang.kT, lang.gamma, int(lang.seed)),
        "nonbonded": nonbonded, "fluid": fluid_state}
    return state


def restore_system(system, state):
    """Rebuild the System from its pickled state and the loaded arrays."""
    if _context is None:
        raise TypeError("an lbmd.System is loaded with lbmd.checkpoint.load(path)")
    saved = state.pop("_checkpoint")
    arrays = _context["arrays"]
    prefix = saved["prefix"]
    fields = ("id", "folded_pos", "image", "v", "f", "ext_force", "normal", "mass", "type", "mol_id", "fixed",
              "rebuild_reference", "exclusions")
    _require_arrays(arrays, [f"{prefix}/particles/{k}" for k in fields]
                    + [f"{prefix}/bonds/{i}/{k}" for i in range(len(state["bonded_inter"]))
                       for k in ("ids", "per_bond")]
                    + ([f"{prefix}/fluid/stored_population", f"{prefix}/fluid/coupling_field"]
                       if saved["fluid"] is not None else []))
    d = system.__dict__
    d.update(state)
    core = _lbmd.System(np.asarray(saved["box_l"], dtype=float), list(saved["periodicity"]))
    d["_core"] = core
    core.time_step = saved["time_step"]
    core.skin = saved["skin"]
    core.cell_checks = saved["cell_checks"]
    core.cell_drift_tolerance = saved["cell_drift_tolerance"]
    for bond in system.bonded_inter:
        core.add_bonded_interaction(bond._core_object())
    from .interactions import NONBONDED_MODELS
    for name, t1, t2, values in saved["nonbonded"]:
        getattr(core, "set_" + name)(t1, t2, NONBONDED_MODELS[name]._core_params(**values))
    for c in system.constraints:
        core.add_constraint(c._core)
        c.__dict__["_system_core"] = core
    active, kT, gamma, seed = saved["langevin"]
    if active:
        core.set_langevin(kT, gamma, seed)
    # the fluid: made again from its parameters (split for this rank count)
    actors = list(system.actors._list)
    system.actors._list.clear()
    from mpi4py import MPI
    grid = system.cell_system._node_grid
    if grid is not None and int(np.prod(grid)) != MPI.COMM_WORLD.Get_size():
        system.cell_system._node_grid = None  # saved at another rank count
    for actor in actors:
        actor._activate(system)
        system.actors._list.append(actor)
    lb = system.thermostat._lb
    if lb is not None:
        core.set_lb_coupling(lb[1], lb[2])
    # particles in the saved local order, their bonds and exclusions
    part = {k[len(prefix) + 11:]: v for k, v in arrays.items() if k.startswith(prefix + "/particles/")}
    if len(part["id"]):
        core.add_particles(part["id"].astype(np.int32), part["folded_pos"], part["v"], part["mass"],
                           part["type"].astype(np.int32), part["mol_id"].astype(np.int32),
                           part["ext_force"], part["fixed"].astype(np.int32))
    for bond_id in range(len(system.bonded_inter)):
        ids = arrays[f"{prefix}/bonds/{bond_id}/ids"]
        if ids.size:
            core.add_bonds(bond_id, np.ascontiguousarray(ids.ravel(), dtype=np.int32),
                           np.ascontiguousarray(arrays[f"{prefix}/bonds/{bond_id}/per_bond"], dtype=float))
    exclusions = np.asarray(arrays[f"{prefix}/particles/exclusions"], dtype=np.int32).reshape(-1, 2)
    if len(exclusions):
        core.add_exclusions(np.ascontiguousarray(exclusions))  # in one call: millions for dense scenes
    fluid = system._core_fluid()
    if fluid is not None and saved["fluid"] is not None:
        system.prepare()  # collective: the restored boundaries flagged before the populations
        shape = [int(n) for n in fluid.shape]
        for prop in ("stored_population", "coupling_field"):
            # read on rank 0 only (_OnRoot elsewhere); each rank receives its own nodes
            block = arrays[f"{prefix}/fluid/{prop}"]
            if list(block.shape[:3]) != shape:
                raise CheckpointError(f"checkpoint: the fluid has {list(block.shape[:3])} nodes, "
                                      f"the restored lattice {shape}")
            values = (np.ascontiguousarray(block, dtype=float).ravel() if isinstance(block, np.ndarray)
                      else np.zeros(0))
            fluid.scatter_block(prop, [0, 0, 0], shape, values, 0)
        fluid.set_n_updates(saved["fluid"]["n_updates"])
        gains = saved["fluid"].get("open_gains", [])
        if gains and len(gains) == len(fluid.open_boundary_gains()):
            fluid.set_open_boundary_gains(gains)
        any_deposit, ledger_step, in_flight = saved["fluid"]["ledger"]
        core.set_coupling_ledger_state(any_deposit, ledger_step, np.asarray(in_flight, dtype=float))
    core.time = saved["time"]
    core.set_step_count(saved["step_count"])
    core.restore_run_state(part["folded_pos"], part["image"].astype(np.int32), part["f"], part["normal"],
                           part["rebuild_reference"].reshape(-1, 3), saved["lb_substep"],
                           saved.get("forces_valid", True))  # checkpoints before 29 Nov 2026: valid


# --- save and load ------------------------------------------------------------
def save(path, system, **objects):
    """Write a checkpoint of `system` and the named `objects` to `path`
    (HDF5). Collective under mpirun. Returns the path."""
    global _context
    from .system import System
    from .file_output import on_writer, replace_atomically
    if not isinstance(system, System):
        raise TypeError(f"checkpoint.save: parameter 'system' must be an lbmd.System, got "
                        f"{type(system).__name__}")
    if "system" in objects:
        raise TypeError("checkpoint.save: 'system' is the second argument; name the other objects otherwise")
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"checkpoint.save: parameter 'path' must be a file name, got {type(path).__name__}")
    _context = {"arrays": {}, "systems": []}
    try:
        try:
            blob = pickle.dumps({"system": system, **objects}, protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError) as e:
            raise TypeError(f"checkpoint.save: cannot save the objects given: {e} (objects passed "
                            f"by name must be picklable: no open files, lambdas or modules)") from None
        arrays = _context["arrays"]
    finally:
        _context = None
    from mpi4py import MPI
    attrs = {"format": FORMAT, "version": FORMAT_VERSION, "ranks": MPI.COMM_WORLD.Get_size(),
             "step": int(system._core.step_count), "time": float(system._core.time),
             "created": _time.strftime("%Y-%m-%dT%H:%M:%S%z")}

    def write_to(tmp):
        import h5py
        with h5py.File(tmp, "w", userblock_size=USERBLOCK) as f:
            f.attrs.update(attrs)
            f.create_dataset("objects", data=np.frombuffer(blob, dtype=np.uint8))
            for name, value in arrays.items():
                f.create_dataset(name, data=value)
            f.flush()
        seal(tmp)
        with open(tmp, "rb") as fh:  # on disk before the rename
            os.fsync(fh.fileno())

    on_writer(lambda: replace_atomically(path, "checkpoint.save", write_to))
    return os.fspath(path)


# The file starts with a user block of USERBLOCK bytes (HDF5 leaves it to the
# application) holding MAGIC and the SHA-256 of everything after it: a file
# damaged or cut anywhere is refused before the HDF5 library reads it (the
# library itself can crash on some damaged files).
USERBLOCK = 512
MAGIC = b"PyOIF checkpoint\nsha256 "


def seal(path):
    """Write the user block's checksum of an HDF5 file made with
    userblock_size=USERBLOCK (save does; a tool that edits a checkpoint with
    h5py calls it afterwards)."""
    import hashlib
    digest = hashlib.sha256()
    with open(path, "r+b") as f:
        f.seek(USERBLOCK)
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
        header = MAGIC + digest.hexdigest().encode() + b"\n"
        f.seek(0)
        f.write(header.ljust(USERBLOCK, b"\0"))


def _verify(path):
    """CheckpointError unless the file's user block holds the checksum of the
    rest of it."""
    import hashlib
    with open(path, "rb") as f:
        head = f.read(USERBLOCK)
        if not head.startswith(MAGIC):
            if head.startswith(b"\x89HDF\r\n\x1a\n"):
                raise CheckpointError(f"checkpoint '{path}': an HDF5 file, but not a PyOIF checkpoint (no PyOIF "
                                      f"header before the HDF5 data)")
            raise CheckpointError(f"checkpoint '{path}': not a PyOIF checkpoint (no PyOIF header; not a "
                                  f"readable HDF5 file, or truncated)")
        expected = head[len(MAGIC):len(MAGIC) + 64]
        digest = hashlib.sha256()
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    if digest.hexdigest().encode() != expected:
        raise CheckpointError(f"checkpoint '{path}': damaged or truncated: its checksum does not match its "
                              f"content (a copy cut short, a disk error, or an edit without "
                              f"lbmd.checkpoint.seal)")


def _read(path):
    """(attrs, blob, arrays) of a checkpoint file, or CheckpointError."""
    import h5py
    if not os.path.isfile(path):
        raise CheckpointError(f"checkpoint '{path}': no such file")
    _verify(path)
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise CheckpointError(f"checkpoint '{path}': not a readable HDF5 file (truncated, or not a "
                              f"checkpoint): {e}") from None
    # h5py raises OSError, KeyError, ValueError, TypeError or RuntimeError
    # ("object visitation failed") on a damaged file, wherever it reads
    damaged = (OSError, KeyError, ValueError, TypeError, RuntimeError)
    with f:
        try:
            fmt = f.attrs.get("format")
            version = f.attrs.get("version")
        except damaged as e:
            raise CheckpointError(f"checkpoint '{path}': damaged: its attributes cannot be read ({e})") from None
        if isinstance(fmt, bytes):
            fmt = fmt.decode(errors="replace")
        if fmt != FORMAT:
            raise CheckpointError(f"checkpoint '{path}': an HDF5 file, but not a PyOIF checkpoint "
                                  f"(attribute 'format' is {fmt!r}, expected {FORMAT!r})")
        if version != FORMAT_VERSION:
            raise CheckpointError(f"checkpoint '{path}': format version {version}, this PyOIF reads "
                                  f"version {FORMAT_VERSION} (write it again with the version that made it)")
        arrays = {}
        try:
            attrs = dict(f.attrs)
            objects = f.get("objects")
            if not isinstance(objects, h5py.Dataset) or objects.ndim != 1 or objects.dtype != np.uint8:
                raise CheckpointError(f"checkpoint '{path}': the dataset 'objects' (bytes) is missing or not "
                                      f"a byte array")
            blob = objects[()].tobytes()

            def visit(name, item):
                if isinstance(item, h5py.Dataset) and name != "objects":
                    arrays[name] = item[()]
            f.visititems(visit)
        except damaged as e:
            raise CheckpointError(f"checkpoint '{path}': damaged ({e})") from None
    return attrs, blob, arrays


_LATTICE_BLOCKS = ("/fluid/stored_population", "/fluid/coupling_field")


class _OnRoot:
    """A lattice block that rank 0 holds; the other ranks know its shape."""

    def __init__(self, shape):
        self.shape = tuple(shape)


def _without_lattice(result):
    """What rank 0 broadcasts of a read checkpoint: the lattice blocks as
    their shapes (_OnRoot), everything else as read."""
    if isinstance(result, Exception):
        return result
    attrs, blob, arrays = result
    return attrs, blob, {name: _OnRoot(value.shape) if name.endswith(_LATTICE_BLOCKS) else value
                         for name, value in arrays.items()}


def _require_arrays(arrays, names):
    """CheckpointError naming the first of the datasets missing."""
    for name in names:
        if name not in arrays:
            raise CheckpointError(f"the dataset '{name}' is missing (a damaged or edited file)")


def load(path):
    """The objects of the checkpoint at `path` as a namespace: ``ns.system``
    and every name given to save. Collective under mpirun (any rank count).
    Raises CheckpointError naming the file and what is wrong."""
    global _context
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"checkpoint.load: parameter 'path' must be a file name, got {type(path).__name__}")
    path = os.fspath(path)
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    result = None
    if comm.Get_rank() == 0:
        try:
            result = _read(path)
        except CheckpointError as e:
            result = e
    if comm.Get_size() > 1:
        # the lattice's blocks stay on rank 0 (scatter_block sends each rank
        # its own nodes): the others get their shapes only
        shared = comm.bcast(_without_lattice(result) if comm.Get_rank() == 0 else None, root=0)
        if comm.Get_rank() != 0:
            result = shared
    if isinstance(result, Exception):
        raise result
    attrs, blob, arrays = result
    _context = {"arrays": arrays, "systems": []}
    try:
        try:
            objects = pickle.loads(blob)
        except CheckpointError as e:
            raise CheckpointError(f"checkpoint '{path}': {e}") from None
        except Exception as e:  # damaged bytes can raise anything while unpickling
            raise CheckpointError(f"checkpoint '{path}': the objects cannot be read back "
                                  f"({type(e).__name__}: {e})") from None
    finally:
        _context = None
    if not isinstance(objects, dict) or "system" not in objects:
        raise CheckpointError(f"checkpoint '{path}': no system in the saved objects")
    return types.SimpleNamespace(**objects)


# --- walltime ---------------------------------------------------------------
_stop = None


def stop_on_signal(path, system, objects=None, signals=(signal.SIGTERM, signal.SIGUSR1)):
    """From now on, SIGTERM or SIGUSR1 (a batch system's walltime warning,
    ``scancel --signal=USR1``, ``kill``) ends the running integration after the
    current step: the ranks agree on the step, a checkpoint of `system` and
    `objects` (a dict, or a function returning one: a script's own state at
    that moment) is written to `path`, and the process exits with
    EXIT_CHECKPOINTED (75). A signal outside a run is acted on at the next
    run. ``stop_on_signal(None, None)`` switches it off."""
    global _stop
    if path is None:
        _stop = None
        _lbmd.arm_stop_signals([])
        return
    if objects is not None and not (callable(objects) or isinstance(objects, dict)):
        raise TypeError("checkpoint.stop_on_signal: parameter 'objects' must be a dict or a function "
                        f"returning one, got {type(objects).__name__}")
    _stop = (os.fspath(path), system, objects)
    _lbmd.arm_stop_signals([int(s) for s in signals])


def _after_stop():
    """Called by Integrator.run when a stop signal ended the run."""
    path, system, objects = _stop
    named = objects() if callable(objects) else (objects or {})
    save(path, system, **named)
    from mpi4py import MPI
    if MPI.COMM_WORLD.Get_rank() == 0:
        sys.stderr.write(f"stop signal: checkpoint of step {system._core.step_count} (time "
                         f"{system.time:g}) written to {path}; exiting with status {EXIT_CHECKPOINTED}\n")
        sys.stderr.flush()
    sys.stdout.flush()
    MPI.COMM_WORLD.Barrier()
    os._exit(EXIT_CHECKPOINTED) if MPI.COMM_WORLD.Get_size() > 1 else sys.exit(EXIT_CHECKPOINTED)
