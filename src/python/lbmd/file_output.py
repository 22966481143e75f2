"""Safe file output shared by lbmd and oif: under MPI only rank 0 writes
(every rank calls; a failure on the writer is raised on every rank), and a
file is written under a temporary name in its folder and renamed over the
final name, so readers never see a half-written file."""
import os
import stat


def is_writer():
    """True on the rank that writes files (rank 0; True without MPI)."""
    try:
        from mpi4py import MPI
        return MPI.COMM_WORLD.Get_rank() == 0
    except ImportError:  # pragma: no cover
        return True


def on_writer(action):
    """Run action() on the writing rank only; an exception it raises is
    raised on every rank, so that all ranks of an SPMD script see the same
    outcome (a rank that raised alone would leave the others waiting)."""
    try:
        from mpi4py import MPI
        comm = MPI.COMM_WORLD
    except ImportError:  # pragma: no cover
        comm = None
    if comm is None or comm.Get_size() == 1:
        action()
        return
    error = None
    if comm.Get_rank() == 0:
        try:
            action()
        except Exception as e:  # handed to every rank below
            error = e
    error = comm.bcast(error, root=0)
    if error is not None:
        raise error


def output_path(path, owner="output"):
    """Check an output file name and prepare its folder: returns the path to
    write (symlinks resolved, so that the link keeps pointing at the data).
    Raises TypeError/ValueError naming the path for a non-string, an empty
    name, a name that is a directory or another non-regular file (device,
    fifo), or a folder part that is a regular file; creates missing folders."""
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise TypeError(f"{owner}: file name must be a string, got {type(path).__name__}")
    path = os.fspath(path)
    if not isinstance(path, str):  # a PathLike returning bytes
        raise TypeError(f"{owner}: file name must be a string, got {path!r}")
    if not path:
        raise ValueError(f"{owner}: file name is empty")
    if path.endswith(os.sep) or os.path.isdir(path):
        raise ValueError(f"{owner}: '{path}' is a directory, not a file name")
    real = os.path.realpath(path)  # write to the target of a symlink, not over the link
    if os.path.lexists(real):
        mode = os.stat(real).st_mode if os.path.exists(real) else 0
        if not stat.S_ISREG(mode):
            raise ValueError(f"{owner}: '{path}' exists and is not a regular file (a directory, device, "
                             f"fifo or broken link); give the name of a regular file")
    # the first existing ancestor must be a folder: 'afile/x.vtk' cannot be created
    folder = os.path.dirname(real)
    probe = folder
    while probe and not os.path.exists(probe):
        probe = os.path.dirname(probe)
    if probe and not os.path.isdir(probe):
        raise ValueError(f"{owner}: cannot write '{path}': '{probe}' is a file, not a folder")
    if folder and not os.path.isdir(folder):
        try:
            os.makedirs(folder, exist_ok=True)
        except OSError as e:
            raise OSError(f"{owner}: cannot create the folder of '{path}': {e.strerror or e}") from None
    return real


def replace_atomically(path, owner, write_to):
    """write_to(temporary name) in the folder of path, then renamed over the
    target (readers never see a half-written file); the temporary file is
    removed on any failure, and the error names owner and path. On the
    writing rank only (call it inside on_writer)."""
    real = output_path(path, owner)
    tmp = real + ".tmp"
    try:
        write_to(tmp)
        os.replace(tmp, real)
    except OSError as e:
        raise OSError(f"{owner}: cannot write '{path}': {e.strerror or e}") from None
    finally:
        if os.path.lexists(tmp) and os.path.isfile(tmp):
            try:
                os.remove(tmp)
            except OSError:  # pragma: no cover - the original error is the one to report
                pass


def write_text(path, text, owner="output"):
    """Write text to path through a temporary file in the same folder, renamed
    over the target at the end (readers never see a half-written file); the
    temporary file is removed on any failure. The name is checked and the
    folder created by the writing rank only, which hands its outcome to the
    others (on_writer): a check that came out differently on another rank
    (a node-local folder) cannot make one rank raise alone."""

    def write_to(tmp):
        with open(tmp, "w") as f:
            f.write(text)

    on_writer(lambda: replace_atomically(path, owner, write_to))

