"""The error boundary of every command: what a user sees when a run fails, and what it leaves on disk.

An expected failure (a user error, unreadable or corrupt input, a full or read-only disk, text that is not UTF-8)
is one ``error: ...`` line and exit code 2; Ctrl-C is one line and exit code 130. A bug still shows its traceback.
A Hydra run folder belongs to its run: it is locked while the run writes to it (a second run aimed at the same
folder is refused), and a failed run removes the folder it created, unless it holds checkpoints (training progress
is never thrown away; the line says where they are). A run killed outright (SIGKILL) cannot clean up: the next run
of the same command does it (``remove_stale_runs``), so a folder either ends complete, with its results.json, or goes.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import shutil
import signal
import socket
import sys
import threading
import time
from pathlib import Path

from motiondiff.runtime.atomic import TEMP_GLOB
from motiondiff.runtime.errors import DatasetNotFoundError, RepresentationError, UsageError
from motiondiff.runtime.processes import alive, take_lock

USER_ERRORS = (UsageError, DatasetNotFoundError, RepresentationError)  # raised with a message that names the fix
LOCK_NAME = ".motiondiff.lock"
KEPT_OUTPUTS = ("*.ckpt", "*.safetensors")  # what a failed run leaves in place
# torch.save's own write errors are RuntimeErrors, not OSErrors (a full disk while a checkpoint is written)
TORCH_WRITE_FAILURES = ("PytorchStreamWriter failed", "file write failed", "No space left on device")


def error_line(err: BaseException) -> str | None:
    """The one line for an expected failure, None for anything else (a bug, shown with its traceback)."""
    if isinstance(err, USER_ERRORS):
        return str(err)
    if isinstance(err, UnicodeDecodeError):
        return f"cannot read the input as UTF-8 text ({err.reason} at byte {err.start}): save it as UTF-8"
    if isinstance(err, MemoryError):
        return "out of memory: ask for fewer or shorter motions (num_samples=, length=) or a smaller batch"
    if isinstance(err, RuntimeError) and any(s in str(err) for s in TORCH_WRITE_FAILURES):
        return (
            "a file could not be written (torch.save: the disk is full or the folder went away): free some disk space"
        )
    if isinstance(err, OSError):
        name = f" {err.filename}" if err.filename else ""
        hint = {errno.ENOSPC: "free some disk space", errno.EACCES: "choose a folder you can write to",
                errno.EROFS: "choose a writable folder", errno.ENOENT: "check the path",
                errno.ENOTDIR: "a part of the path is a file, not a folder", errno.EDQUOT: "free some disk space",
                errno.EISDIR: "give a file, not a folder"}.get(err.errno, "check the path and its permissions")  # fmt: skip
        return f"{err.strerror or err}:{name} ({hint})"
    return None


def guarded(fn):
    """Run ``fn`` with expected failures as one ``error:`` line (exit 2) and Ctrl-C as exit 130."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except (Stopped, KeyboardInterrupt) as stop:  # reported here, after the run folder and any bar are closed
            _exit_stopped(stop)
        except Exception as err:  # noqa: BLE001 - sorted into expected (one line) and bugs (re-raised)
            stop = signal_behind(err)
            if stop is not None:  # a signal that C code turned into another error (an import, a drawing)
                _exit_stopped(stop)
            line = error_line(err)
            if line is None:
                raise
            print(f"error: {line}", file=sys.stderr)
            sys.exit(2)

    return wrapper


def _exit_stopped(stop: BaseException):
    """SIGTERM's line and exit 143, or Ctrl-C's and exit 130."""
    line, code = stop_report(stop)
    print(f"error: {line}", file=sys.stderr)
    sys.exit(code)


def stop_report(stop: BaseException) -> tuple[str, int]:
    """A stop's line (without ``error: ``) and exit code: SIGTERM's (`Stopped`) and 143, or Ctrl-C's and 130. The
    stop is then reported: a later command in this process starts with no signal noted."""
    _RECEIVED.clear()
    if isinstance(stop, Stopped):
        return stop.line, SIGTERM_EXIT
    return "interrupted (Ctrl-C)", 130


def signal_behind(err: BaseException) -> BaseException | None:
    """The SIGTERM (`Stopped`) or Ctrl-C that ``err`` was raised from or while handling, or that arrived before it,
    if any. A signal's exception raised inside C code can come out as another error: pybind11 turns one raised in a
    module's initialisation (a first `import`) into ``ImportError('initialization failed')`` raised from it, and
    matplotlib's Agg renderer, interrupted while it draws a path, drops it and raises ``ValueError('Invalid bounding
    box')`` with no link to it; the handlers `stop_on_sigterm` installs note each signal, so both are the stop."""
    seen = set()
    while err is not None and id(err) not in seen:
        seen.add(id(err))
        if isinstance(err, Stopped | KeyboardInterrupt):
            return err
        err = err.__cause__ or err.__context__
    return _RECEIVED[-1] if _RECEIVED else None


# The stop signals that arrived since this command installed its handlers (`stop_on_sigterm`), newest last.
_RECEIVED: list[BaseException] = []


SIGTERM_EXIT = 143  # 128 + SIGTERM, as a shell reports a process the signal ended


class Stopped(SystemExit):
    """SIGTERM, raised by `stop_on_sigterm`'s handler and reported by the command's boundary with its one line (by
    then the run folder is cleaned and progress bars have finished their lines)."""

    def __init__(self, line: str):
        super().__init__(SIGTERM_EXIT)
        self.line = line


def stop_on_sigterm(out: Path | None = None, kept: str | None = None):
    """Make SIGTERM (`kill`, a scheduler's time limit) end a command like Ctrl-C does: one line, exit code 143, and
    the run folder ``out`` cleaned by `run_folder` (a training run keeps its checkpoints, and the line says from
    which step and how to resume). Without it Python dies at once and leaves its lock; Lightning's own handler would
    end training with exit code 0. ``kept``: what the line says is left instead (a command without a run folder).
    Main thread only. Returns a function that puts back the handlers it replaced and forgets the signals noted, for
    a command called in-process (it does nothing where nothing was installed)."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    _RECEIVED.clear()

    def stop(signum, frame):
        _RECEIVED.append(Stopped(f"stopped by SIGTERM{_resume_hint(out) if kept is None else kept}"))
        raise _RECEIVED[-1]

    def interrupt(signum, frame):
        _RECEIVED.append(KeyboardInterrupt())
        raise _RECEIVED[-1]

    previous = {signal.SIGTERM: signal.signal(signal.SIGTERM, stop)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # an ignored Ctrl-C (nohup) stays ignored
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, interrupt)  # Python's own KeyboardInterrupt, noted

    def restore() -> None:
        for signum, handler in previous.items():
            if handler is not None:  # None: a handler installed outside Python, which cannot be put back from here
                signal.signal(signum, handler)
        _RECEIVED.clear()

    return restore


def _resume_hint(out: Path | None) -> str:
    """Where a stopped training run can go on from: its last checkpoint and that checkpoint's step. A stop that
    lands between a step checkpoint and its last.ckpt copy names the step checkpoint (the newest one kept)."""
    if out is None:
        return "; nothing of this run is kept"
    folder = Path(out) / "checkpoints"
    steps = sorted((int(p.stem[4:]), p) for p in folder.glob("step*.ckpt") if p.stem[4:].isdigit())
    last = folder / "last.ckpt"
    if last.is_file() and (not steps or last.stat().st_mtime >= steps[-1][1].stat().st_mtime):
        at = f" (step {steps[-1][0]})" if steps else ""
        return f"; its last checkpoint{at} is kept: resume with ckpt_path={last}"
    if steps:  # last.ckpt not yet copied from the newest step checkpoint
        return f"; its last checkpoint (step {steps[-1][0]}) is kept: resume with ckpt_path={steps[-1][1]}"
    return "; nothing of this run is kept"


def _fresh(out: Path, job_name: str) -> bool:
    """Whether ``out`` holds only what Hydra writes at a run's start (its own folder, not a user's existing one)."""
    return set(os.listdir(out)) <= {".hydra", f"{job_name}.log", LOCK_NAME}


def _read_lock(lock: Path) -> tuple[int, bool]:
    """(pid, whether the run created its folder) from a lock file; (0, False) when unreadable or written on
    another machine (a shared filesystem: its pid says nothing here)."""
    try:
        pid, fresh, host = (lock.read_text().split() + ["0", ""])[:3]
        return (int(pid), fresh == "1") if host == socket.gethostname() else (0, False)
    except (OSError, ValueError):
        return 0, False


def _holder(lock: Path) -> int | None:
    """The pid of a live process holding ``lock``, None when the lock is stale or unreadable."""
    pid, _ = _read_lock(lock)
    return pid if pid != os.getpid() and alive(pid) else None


def refuse_if_in_use(out: Path) -> None:
    """Refuse ``out`` while another live run holds its lock (checked before Hydra writes its own files there too)."""
    pid = None if _worker_process() else _holder(Path(out) / LOCK_NAME)  # DDP's other ranks share rank 0's folder
    if pid is not None:
        raise UsageError(f"another run (pid {pid}) is writing to {out}: wait for it, or give this run its own folder "
                         "(leave hydra.run.dir unset)")  # fmt: skip


RUN_RECORDS = (".hydra", "results.json", "run.json")  # what marks a folder as an earlier run's


def refuse_used_folder(run_dir: Path, ckpt_path: str | None = None) -> None:
    """Refuse a run folder that holds an earlier run's records (checked before Hydra rewrites them): a second run
    there would mix its files with the first's, and a training run would print a checkpoint path that still holds
    the old model. Resuming a training run in its own folder (``ckpt_path`` inside it) is the one exception."""
    run_dir = Path(run_dir)
    if _worker_process() or not run_dir.is_dir():
        return
    remove_stale_runs(run_dir.parent)  # a killed run's folder is cleaned as its failure would have cleaned it
    if not run_dir.is_dir():
        return
    records = [name for name in RUN_RECORDS if (run_dir / name).exists()]
    if not records:
        return
    if ckpt_path and Path(ckpt_path).resolve().is_relative_to(run_dir.resolve()):
        return
    last = run_dir / "checkpoints" / "last.ckpt"
    resume = f"; to go on training that run, pass ckpt_path={last}" if last.is_file() else ""
    raise UsageError(f"{run_dir} holds an earlier run ({', '.join(records)}), which this run would overwrite: leave "
                     f"hydra.run.dir unset for a fresh folder, or name a new one{resume}")  # fmt: skip


def remove_stale_runs(parent: Path) -> None:
    """Run folders under ``parent`` left by killed runs (SIGKILL, power loss: their lock names a dead process) are
    cleaned as a failed run would have cleaned them: removed when the run created them and no checkpoint is in
    them, else only unlocked. Their ``results.json`` was never written, so nothing complete is lost."""
    if not parent.is_dir():
        return
    for lock in parent.glob(f"*/{LOCK_NAME}"):
        pid, fresh = _read_lock(lock)
        if pid > 0 and _holder(lock) is None:
            lock.unlink(missing_ok=True)
            _remove_failed(lock.parent, fresh, quiet=True)
    for hydra in parent.glob("*/.hydra"):  # killed before its lock: an hour on, it is dead
        out = hydra.parent
        if not (out / LOCK_NAME).exists() and _only_start_files(out) and time.time() - out.stat().st_mtime > 3600:
            shutil.rmtree(out, ignore_errors=True)


def _only_start_files(out: Path) -> bool:
    """Nothing but Hydra's config folder and empty logs: a run that never got to work (nor finished: it logs)."""
    return all(p.name == ".hydra" or (p.suffix == ".log" and p.stat().st_size == 0) for p in out.iterdir())


def _worker_process() -> bool:
    """Whether this process is one of a distributed run's other ranks (launched by Lightning's DDP or SLURM)."""
    return any(os.environ.get(name, "0") not in ("", "0") for name in ("LOCAL_RANK", "RANK", "SLURM_PROCID"))


@contextlib.contextmanager
def run_folder(out: Path, job_name: str):
    """Hold ``out`` for this run: refuse a folder another live run is writing to; on failure (any exception,
    Ctrl-C, exit code != 0) remove the folder if this run created it and it holds no checkpoint."""
    out = Path(out)
    if _worker_process():  # the parent process of a multi-process run holds the folder for all of them
        yield
        return
    fresh = _fresh(out, job_name)
    remove_stale_runs(out.parent)
    lock = out / LOCK_NAME
    take_lock(lock, f"{os.getpid()} {int(fresh)} {socket.gethostname()}", lambda: refuse_if_in_use(out))
    failed = True
    try:
        yield
        failed = False
    except SystemExit as exit_:
        failed = exit_.code not in (0, None)
        raise
    finally:
        lock.unlink(missing_ok=True)
        if failed:
            _remove_failed(out, fresh)


def _remove_failed(out: Path, fresh: bool, quiet: bool = False) -> None:
    kept = [p for pattern in KEPT_OUTPUTS for p in out.rglob(pattern) if not p.name.startswith(".")]
    if kept:
        for temp in out.rglob(TEMP_GLOB):  # half-written files of the killed run (never a complete one)
            temp.unlink(missing_ok=True)
        if not quiet:
            print(f"note: the failed run's checkpoints are kept in {out}", file=sys.stderr)
    elif fresh:
        shutil.rmtree(out, ignore_errors=True)
        if not quiet:
            _remove_new_parents(out)


# The folders above this process's run folder that did not exist before it started (`note_new_parents`, called
# before Hydra makes them): a refused or failed run takes them away again when they are left empty.
_NEW_PARENTS: list[Path] = []


def note_new_parents(run_dir: Path | None) -> None:
    """Note which folders above ``run_dir`` do not exist yet (None: none, as for a sweep's runs)."""
    _NEW_PARENTS[:] = [p for p in Path(run_dir).absolute().parents if not p.exists()] if run_dir else []


def _remove_new_parents(out: Path) -> None:
    for parent in _NEW_PARENTS:  # deepest first; one that is not empty (another run's) stops the walk
        if parent not in Path(out).absolute().parents:
            break
        try:
            parent.rmdir()
        except OSError:
            break
