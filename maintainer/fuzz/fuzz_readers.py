"""Randomized fuzzing of PyOIF's file readers (doc/sanitizers.md).

    pyoif maintainer/fuzz/fuzz_readers.py [-n N] [--seed S] [--target T ...]
                                          [--timeout SEC] [--out DIR]

Targets (each gets N inputs):

- ``dat``: oif.mesh_io.read_mesh(nodes.dat, triangles.dat), PyOIF's text
  tables; one or both files of a valid mesh (sphere162) mutated;
- ``meshio``: read_mesh(path, None) on the formats read through meshio
  (.off, .obj, .ply, .stl, .vtk, .msh, .vtu), valid files of the same mesh
  mutated;
- ``ckpt_bytes``: lbmd.checkpoint.load on a small valid checkpoint (fluid,
  particles, bonds, exclusions, Langevin) whose bytes are mutated;
- ``ckpt_h5``: the same checkpoint with its datasets and attributes changed
  through h5py (shapes, dtypes, NaN/inf/huge values, removed or replaced
  datasets, the format and version attributes, the pickled objects' bytes).
  A checkpoint that loads is also run for one step.

Byte/text mutations: bit flips, truncation, byte insertion and deletion,
swapped, duplicated, deleted and empty lines, numbers replaced by random
ones, NaN/inf tokens, huge and negative ids, binary junk.

Outcomes: *accepted* (the reader returned), *clean* (one of the documented
exceptions: ValueError -- lbmd.checkpoint.CheckpointError is one --,
TypeError, OSError; lbmd.SimulationInstability from the step after a load)
and *bad*: any other exception, a crash (the process died by a signal or a
sanitizer abort) or a hang (no result within --timeout seconds). Every input
runs in-process, in a child process that this script (the parent) watches:
after a crash or hang the parent saves the input and goes on with a new
child from the next input. Each bad input is written under --out
(bad-<target>-<i>-<kind>/ with the input files and the traceback). Inputs
are a function of (seed, target, i) alone: a run is reproducible, and
``--only I`` replays one input. Exit status 0 when no outcome was bad, 1
otherwise.
"""
import argparse
import collections
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback

import numpy as np

TARGETS = ("dat", "meshio", "ckpt_bytes", "ckpt_h5")
MESHIO_FORMATS = (".off", ".obj", ".ply", ".stl", ".vtk", ".msh", ".vtu")
CLEAN = (ValueError, TypeError, OSError)


class Hang(Exception):
    """Raised by the per-input alarm."""


# ---- mutations ------------------------------------------------------------------
SPECIAL_TOKENS = [b"nan", b"NaN", b"inf", b"-inf", b"1e308", b"1e309", b"-1e309", b"0", b"-0", b"-1",
                  b"2147483647", b"2147483648", b"-2147483649", b"9223372036854775807",
                  b"99999999999999999999999999", b"1e-320", b"0x10", b"1_000", b"", b"+", b"-", b"1.5",
                  b"\xff\xfe", b"\x00", b"\xc3\xa9", b"#", b"1,2"]


def _number_spans(data):
    """(start, end) of the number-like tokens in data."""
    spans, i, n = [], 0, len(data)
    digits = b"0123456789+-.eE"
    while i < n:
        if data[i] in digits:
            j = i
            while j < n and data[j] in digits:
                j += 1
            spans.append((i, j))
            i = j
        else:
            i += 1
    return spans


def mutate_bytes(data, rng, text=True):
    """One to four random mutations of a byte string."""
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        op = rng.choice(("flip", "truncate", "insert", "delete", "junk", "number", "special", "swap_lines",
                         "dup_line", "del_line", "empty_lines", "huge_id", "negative_id", "overwrite")
                        if text else ("flip", "truncate", "insert", "delete", "junk", "overwrite", "zero_block"))
        n = len(data)
        pos = rng.randrange(n + 1)
        if op == "flip" and n:
            for _ in range(rng.randint(1, 8)):
                k = rng.randrange(n)
                data[k] ^= 1 << rng.randrange(8)
        elif op == "truncate":
            del data[pos:]
        elif op == "insert":
            data[pos:pos] = bytes([rng.randrange(256)]) * rng.choice((1, 1, 2, 16, 1000))
        elif op == "delete":
            del data[pos:pos + rng.choice((1, 2, 8, 100, 4096))]
        elif op == "junk":
            data[pos:pos] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 64)))
        elif op == "overwrite" and n:
            k = rng.randrange(n)
            data[k:k + 8] = bytes(rng.randrange(256) for _ in range(8))
        elif op == "zero_block":
            data[pos:pos + 512] = bytes(len(data[pos:pos + 512]))
        elif op in ("number", "special", "huge_id", "negative_id"):
            spans = _number_spans(data)
            if not spans:
                continue
            for _ in range(rng.choice((1, 1, 3, 20))):
                a, b = rng.choice(spans)
                if op == "number":
                    tok = repr(rng.choice((rng.uniform(-1e3, 1e3), rng.randint(-10, 1000), rng.random() * 1e-12,
                                           float(f"1e{rng.randint(-400, 400)}")))).encode()
                elif op == "special":
                    tok = rng.choice(SPECIAL_TOKENS)
                elif op == "huge_id":
                    tok = str(rng.choice((2**31, 2**32 + 1, 2**62, 2**63, 2**64, 10**30, 161, 162, 163))).encode()
                else:
                    tok = str(-rng.randint(1, 200)).encode()
                data[a:b] = tok
                spans = _number_spans(data)  # positions moved
                if not spans:
                    break
        elif op in ("swap_lines", "dup_line", "del_line", "empty_lines"):
            lines = bytes(data).split(b"\n")
            i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
            if op == "swap_lines":
                lines[i], lines[j] = lines[j], lines[i]
            elif op == "dup_line":
                lines.insert(j, lines[i])
            elif op == "del_line":
                del lines[i]
            else:
                lines[i:i] = [rng.choice((b"", b"   ", b"\t", b"\r", b"#"))] * rng.randint(1, 5)
            data = bytearray(b"\n".join(lines))
    return bytes(data)


def mutate_h5(path, rng):
    """Change one to three things of the checkpoint at path through h5py;
    returns what was done (for the log)."""
    import h5py
    done = []
    with h5py.File(path, "r+") as f:
        names = []
        f.visititems(lambda name, item: names.append(name) if isinstance(item, h5py.Dataset) else None)
        for _ in range(rng.randint(1, 3)):
            op = rng.choice(("attr_del", "attr_value", "ds_del", "ds_shape", "ds_dtype", "ds_values",
                             "ds_group", "objects_bytes", "ds_scalar"))
            if op.startswith("attr"):
                key = rng.choice(("format", "version", "ranks", "step", "time", "created"))
                if op == "attr_del":
                    if key in f.attrs:
                        del f.attrs[key]
                else:
                    f.attrs[key] = rng.choice((0, -1, 2, 2**62, 1.5, float("nan"), "1", b"pyoif-checkpoint",
                                               "pyoif-checkpoint", np.array([1, 1]), np.zeros(0), True))
                done.append(f"{op} {key}")
                continue
            if not names:
                continue
            name = rng.choice(names)
            if not isinstance(f.get(name), h5py.Dataset):  # removed or replaced by an earlier change
                continue
            if op == "objects_bytes":
                name = "objects"
                if name not in f or not isinstance(f[name], h5py.Dataset):
                    continue
            old = f[name][()]
            if op == "ds_del":
                del f[name]
            elif op == "ds_group":
                del f[name]
                f.create_group(name)
            elif op == "ds_scalar":
                del f[name]
                f[name] = rng.choice((0, 1.5, "text", float("nan")))
            elif op == "ds_shape":
                arr = np.asarray(old)
                if arr.ndim == 0 or arr.size == 0:
                    new = np.zeros(rng.choice(((0,), (3,), (2, 2))))
                else:
                    choice = rng.randrange(4)
                    if choice == 0:
                        new = arr[: rng.randrange(len(arr))]
                    elif choice == 1:
                        new = np.concatenate([arr, arr[:rng.randint(1, len(arr))]])
                    elif choice == 2:
                        new = arr.reshape(-1)
                    else:
                        new = arr.reshape(arr.shape + (1,))
                del f[name]
                f[name] = new
            elif op == "ds_dtype":
                arr = np.asarray(old)
                dtype = rng.choice((np.int8, np.int64, np.float32, np.complex128, np.uint64, "S3", bool))
                try:
                    new = arr.astype(dtype)
                except (ValueError, TypeError, OverflowError):
                    new = np.zeros(arr.shape, dtype=np.int8)
                del f[name]
                f[name] = new
            elif op in ("ds_values", "objects_bytes"):
                arr = np.array(old)
                if arr.size == 0 or arr.dtype.kind not in "fiub":
                    continue
                flat = arr.reshape(-1)
                for _ in range(rng.choice((1, 3, 30))):
                    k = rng.randrange(flat.size)
                    if arr.dtype.kind == "f":
                        flat[k] = rng.choice((np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, rng.uniform(-1e6, 1e6)))
                    elif arr.dtype.kind == "b":
                        flat[k] = not flat[k]
                    else:
                        info = np.iinfo(arr.dtype)
                        flat[k] = rng.choice((info.min, info.max, 0, -1 if info.min < 0 else 1,
                                              rng.randint(max(info.min, -1000), min(info.max, 1000))))
                f[name][...] = arr
            done.append(f"{op} {name}")
    return "; ".join(done)


# ---- seeds ------------------------------------------------------------------------
def mesh_seed():
    import oif
    return oif.mesh_files("sphere162")


def make_seeds(seed_dir):
    """Valid inputs: the .dat pair, the meshio formats, a checkpoint."""
    os.makedirs(seed_dir, exist_ok=True)
    nodes_file, tris_file = mesh_seed()
    shutil.copy(nodes_file, os.path.join(seed_dir, "nodes.dat"))
    shutil.copy(tris_file, os.path.join(seed_dir, "triangles.dat"))
    import meshio
    from oif import mesh_io
    data = mesh_io.read_mesh(nodes_file, tris_file)
    mesh = meshio.Mesh(data.nodes, [("triangle", mesh_io.outward(data.triangles))])
    for ext in MESHIO_FORMATS:
        kw = {"binary": False} if ext in (".ply", ".stl", ".vtk", ".vtu") else {}
        if ext == ".msh":
            kw = {"file_format": "gmsh22", "binary": False}
        if ext == ".vtu":
            kw = {"binary": False}
        meshio.write(os.path.join(seed_dir, "mesh" + ext), mesh, **kw)
    write_checkpoint(os.path.join(seed_dir, "checkpoint.h5"))


def write_checkpoint(path):
    """A small checkpoint: a fluid coupled to particles with bonds, an
    exclusion, contacts and fixed coordinates, a wall constraint."""
    import lbmd
    from lbmd import lb, shapes
    s = lbmd.System(box_l=[6.0, 6.0, 6.0])
    s.time_step = 0.05
    s.cell_system.skin = 0.2
    lbf = lb.LBFluid(agrid=1.0, dens=1.0, visc=1.0, tau=0.1, kT=0.0, seed=7)
    s.actors.add(lbf)
    rng = np.random.default_rng(1)
    s.part.add(pos=rng.uniform(1, 5, (8, 3)), type=[0] * 8)
    bond = lbmd.interactions.HarmonicBond(k=1.0, r_0=1.0)
    s.bonded_inter.add(bond)
    for i in range(0, 8, 2):
        s.part.by_id(i).add_bond((bond, i + 1))
    s.part.by_id(2).add_exclusion(5)
    s.part.by_id(3).fix = [True, False, False]
    s.non_bonded_inter[0, 0].soft_sphere.set_params(a=0.01, n=2.0, cutoff=1.0)
    s.constraints.add(shape=shapes.Wall(normal=[0, 0, 1], dist=0.5), particle_type=10, penetrable=False)
    s.thermostat.set_lb(LB_fluid=lbf, gamma=1.0, seed=3)
    s.integrator.run(2)
    lbmd.checkpoint.save(path, s, lbf=lbf, note={"a": [1, 2, 3]})


# ---- one input ----------------------------------------------------------------------
def make_input(target, i, seed, seed_dir, cur):
    """Write input i of target into the folder cur; returns (run, what):
    run() reads it."""
    from oif import mesh_io
    rng = random.Random(f"{seed}:{target}:{i}")
    if os.path.isdir(cur):
        shutil.rmtree(cur)
    os.makedirs(cur)

    def read(name):
        with open(os.path.join(seed_dir, name), "rb") as fh:
            return fh.read()

    def write(name, data):
        with open(os.path.join(cur, name), "wb") as fh:
            fh.write(data)
        return os.path.join(cur, name)

    if target == "dat":
        which = rng.choice(("nodes", "triangles", "both"))
        nodes = read("nodes.dat")
        tris = read("triangles.dat")
        if which in ("nodes", "both"):
            nodes = mutate_bytes(nodes, rng)
        if which in ("triangles", "both"):
            tris = mutate_bytes(tris, rng)
        n, t = write("nodes.dat", nodes), write("triangles.dat", tris)
        return (lambda: mesh_io.read_mesh(n, t)), f"mutated {which}"
    if target == "meshio":
        ext = rng.choice(MESHIO_FORMATS)
        p = write("mesh" + ext, mutate_bytes(read("mesh" + ext), rng))
        return (lambda: mesh_io.read_mesh(p, None)), f"mutated {ext}"
    if target == "ckpt_bytes":
        p = write("checkpoint.h5", mutate_bytes(read("checkpoint.h5"), rng, text=False))
        return (lambda: load_and_step(p)), "mutated bytes"
    p = write("checkpoint.h5", read("checkpoint.h5"))
    what = mutate_h5(p, rng)
    return (lambda: load_and_step(p)), what


def load_and_step(path):
    import lbmd
    ns = lbmd.checkpoint.load(path)
    ns.system.integrator.run(1)
    return ns


def clean_types():
    import lbmd
    return CLEAN + (lbmd.SimulationInstability,)


# ---- child: runs inputs, logs one line per input ----------------------------------------
def child(args):
    import warnings
    warnings.simplefilter("ignore")
    clean = clean_types()
    cur = os.path.join(args.out, "current")

    def on_alarm(signum, frame):
        raise Hang()
    signal.signal(signal.SIGALRM, on_alarm)
    with open(os.path.join(args.out, "log.jsonl"), "a") as log, \
            open(os.path.join(args.out, "heartbeat"), "w") as beat:
        for target, i in plan(args)[args.start:]:
            heartbeat(beat, [target, i, "making the input"])
            run, what = make_input(target, i, args.seed, args.seed_dir, cur)
            heartbeat(beat, [target, i, what])
            signal.alarm(args.timeout)
            outcome, detail = "accepted", ""
            try:
                run()
            except Hang:
                outcome, detail = "hang", f"no result within {args.timeout} s"
            except clean as e:
                outcome, detail = "clean", f"{type(e).__name__}: {str(e)[:300]}"
                if target in ("dat", "meshio") and cur not in str(e):
                    # a mesh reader's message must name the file (and line)
                    outcome, detail = "bad", "message does not name the file: " + traceback.format_exc()
            except BaseException as e:  # noqa: B902 - anything else is a finding
                outcome, detail = "bad", traceback.format_exc()
                if isinstance(e, KeyboardInterrupt):
                    raise
            finally:
                signal.alarm(0)
            if outcome in ("bad", "hang"):
                save_bad(args.out, target, i, outcome, what, detail)
            log.write(json.dumps({"target": target, "i": i, "outcome": outcome, "what": what,
                                  "detail": detail.splitlines()[-1] if detail else ""}) + "\n")
            log.flush()
    return 0


def heartbeat(f, value):
    f.seek(0)
    f.truncate()
    f.write(json.dumps(value))
    f.flush()


def save_bad(out, target, i, kind, what, detail):
    dest = os.path.join(out, f"bad-{target}-{i}-{kind}")
    if os.path.isdir(dest):
        shutil.rmtree(dest)
    shutil.copytree(os.path.join(out, "current"), dest)
    with open(os.path.join(dest, "README.txt"), "w") as f:
        f.write(f"target {target}, input {i} ({what}): {kind}\n\n{detail}\n")


def plan(args):
    """The (target, i) sequence: targets interleaved."""
    if args.only is not None:
        return [(t, args.only) for t in args.target]
    return [(t, i) for i in range(args.n) for t in args.target]


# ---- parent: restarts the child after a crash or hang -------------------------------------
def parent(args):
    os.makedirs(args.out, exist_ok=True)
    for name in ("log.jsonl", "heartbeat"):
        if os.path.exists(os.path.join(args.out, name)):
            os.remove(os.path.join(args.out, name))
    args.seed_dir = os.path.join(args.out, "seeds")
    make_seeds(args.seed_dir)
    todo = plan(args)
    start, t0 = 0, time.time()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    while start < len(todo):
        cmd = [sys.executable, os.path.abspath(__file__), "--child", "--start", str(start),
               "--seed-dir", args.seed_dir] + child_args(args)
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        last, since = None, time.time()
        err = b""
        while True:
            try:
                _, e = proc.communicate(timeout=0.5)
                err += e or b""
                break
            except subprocess.TimeoutExpired:
                pass
            beat = read_heartbeat(args.out)
            if beat != last:
                last, since = beat, time.time()
            elif time.time() - since > 2 * args.timeout + 10:  # stuck where the alarm cannot reach
                proc.kill()
                proc.communicate()
                break
        done = count_logged(args.out)
        if done >= len(todo):
            break
        # the child stopped early: the input it was on crashed or hung
        target, i = todo[done]
        kind = "hang" if proc.returncode == -signal.SIGKILL else "crash"
        try:
            what = json.loads(read_heartbeat(args.out))[2]
        except (TypeError, ValueError, IndexError):
            what = "?"
        detail = f"child exit status {proc.returncode}\n{err.decode(errors='replace')[-4000:]}"
        save_bad(args.out, target, i, kind, what, detail)
        with open(os.path.join(args.out, "log.jsonl"), "a") as log:
            log.write(json.dumps({"target": target, "i": i, "outcome": kind, "what": what,
                                  "detail": f"exit status {proc.returncode}"}) + "\n")
        start = done + 1
    return report(args, time.time() - t0)


def child_args(args):
    a = ["-n", str(args.n), "--seed", str(args.seed), "--timeout", str(args.timeout), "--out", args.out,
         "--target"] + list(args.target)
    if args.only is not None:
        a += ["--only", str(args.only)]
    return a


def read_heartbeat(out):
    try:
        with open(os.path.join(out, "heartbeat")) as f:
            return f.read()
    except OSError:
        return None


def count_logged(out):
    try:
        with open(os.path.join(out, "log.jsonl")) as f:
            return sum(1 for _ in f)
    except OSError:
        return 0


def report(args, seconds):
    counts = collections.defaultdict(collections.Counter)
    bad = []
    with open(os.path.join(args.out, "log.jsonl")) as f:
        for line in f:
            r = json.loads(line)
            counts[r["target"]][r["outcome"]] += 1
            if r["outcome"] in ("bad", "crash", "hang"):
                bad.append(r)
    print(f"fuzz_readers: seed {args.seed}, {seconds:.1f} s, out {args.out}")
    for t in args.target:
        c = counts[t]
        print(f"  {t:11s} inputs {sum(c.values()):6d}  accepted {c['accepted']:6d}  clean {c['clean']:6d}  "
              f"bad {c['bad']:4d}  crash {c['crash']:4d}  hang {c['hang']:4d}")
    for r in bad[:20]:
        print(f"  BAD {r['target']} input {r['i']} ({r['outcome']}, {r['what']}): {r['detail']}")
    summary = {t: dict(counts[t]) for t in args.target}
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump({"seed": args.seed, "n": args.n, "seconds": seconds, "counts": summary}, f, indent=1)
    return 1 if bad else 0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("-n", type=int, default=200, help="inputs per target (default 200)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--target", nargs="+", choices=TARGETS, default=list(TARGETS))
    p.add_argument("--timeout", type=int, default=20, help="seconds per input before it counts as a hang")
    p.add_argument("--out", default=None, help="folder for the log, the seeds and bad inputs "
                                                "(default: a new temporary folder)")
    p.add_argument("--only", type=int, default=None, help="replay input I of each target")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--start", type=int, default=0, help=argparse.SUPPRESS)
    p.add_argument("--seed-dir", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.n < 1 or args.timeout < 1:
        p.error("-n and --timeout must be at least 1")
    if args.child:
        return child(args)
    if args.out is None:
        args.out = tempfile.mkdtemp(prefix="pyoif-fuzz-")
    args.out = os.path.abspath(args.out)
    return parent(args)


if __name__ == "__main__":
    sys.exit(main())
