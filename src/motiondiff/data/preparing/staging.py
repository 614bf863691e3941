"""Building a dataset folder beside the old one and swapping it in, so a killed `prepare` never leaves a mixture.

`staged_folder(out)` yields a temporary sibling (``.<name>.building-<pid>``) to write the whole dataset into. On
success the new folder takes the old one's place in one atomic exchange (Linux ``renameat2(RENAME_EXCHANGE)``;
Python has no call for it, so it goes through ctypes), and the old one is deleted. Where the exchange is missing
(another OS, a filesystem without it) the old folder is renamed aside (``.<name>.replaced-<pid>``) and the new one
renamed in; a kill between the two renames is repaired on the next start, which puts the old complete folder back.
On failure, Ctrl-C included, the temporary folder goes and the old dataset is untouched. Files in the old folder
that the new build did not write (a user's notes, a cache) are hard-linked into the new one before the swap.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import os
import re
import shutil
import time
from pathlib import Path

from motiondiff.data.preparing.writer import PrepareError, check_output
from motiondiff.runtime.processes import alive, take_lock

_AT_FDCWD, _RENAME_EXCHANGE = -100, 2
_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<kind>building|replaced)-(?P<pid>\d+)$")


def recover(out: Path) -> None:
    """Repair what a killed run left beside ``out``: a swap cut between its renames is undone (the old complete
    folder goes back), temporary build folders of dead runs are removed."""
    if not out.parent.is_dir():
        return
    for path in sorted(out.parent.iterdir()):
        m = _TEMP.match(path.name)
        if m is None or m["name"] != out.name or alive(int(m["pid"])):
            continue
        if m["kind"] == "replaced" and not out.exists():
            os.rename(path, out)  # killed between the fallback's two renames: the old dataset is still complete
        else:
            shutil.rmtree(path, ignore_errors=True)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically; False where the system cannot (then nothing has moved)."""
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is None:
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _keep_extra_files(old: Path, new: Path) -> None:
    for entry in old.iterdir():
        target = new / entry.name
        if target.exists() or _TEMP.match(entry.name):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.copytree(entry, target, symlinks=True, copy_function=os.link)
        else:
            os.link(entry, target, follow_symlinks=False)


def swap_in(build: Path, out: Path) -> None:
    """Put the finished ``build`` folder at ``out``, replacing what was there."""
    if not out.exists():
        os.rename(build, out)
        return
    _keep_extra_files(out, build)
    if _exchange(build, out):
        shutil.rmtree(build, ignore_errors=True)  # now the old dataset
        return
    aside = out.parent / f".{out.name}.replaced-{os.getpid()}"
    os.rename(out, aside)
    os.rename(build, out)
    shutil.rmtree(aside, ignore_errors=True)


@contextlib.contextmanager
def _one_writer(out: Path):
    """Hold ``out`` for this process (``.<name>.lock`` beside it, created exclusively): a second `prepare` into the
    same folder is refused while the first is alive, instead of both reporting success."""
    lock = out.parent / f".{out.name}.lock"

    def refuse_if_held() -> None:
        try:
            pid, young = int(lock.read_text() or 0), time.time() - lock.stat().st_mtime < 5
        except (OSError, ValueError):
            pid, young = 0, False
        if (pid and pid != os.getpid() and alive(pid)) or (not pid and young):  # empty: being written now
            raise PrepareError(f"another prepare (pid {pid or '?'}) is writing --out {out}: wait for it to "
                               "finish, or choose another --out") from None  # fmt: skip

    take_lock(lock, str(os.getpid()), refuse_if_held)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)


@contextlib.contextmanager
def staged_folder(out: str | Path, force: bool = False):
    """Yield an empty temporary sibling of ``out`` to build into; swap it in when the block completes. One writer
    at a time: ``out`` is locked, and checked again under the lock (`writer.check_output`: a dataset another run
    finished meanwhile is not replaced without ``force``)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with _one_writer(out):
        check_output(out, force)
        with _building(out) as build:
            yield build


@contextlib.contextmanager
def _building(out: Path):
    recover(out)
    build = out.parent / f".{out.name}.building-{os.getpid()}"
    shutil.rmtree(build, ignore_errors=True)
    build.mkdir()
    try:
        yield build
    except BaseException:
        shutil.rmtree(build, ignore_errors=True)
        raise
    swap_in(build, out)
