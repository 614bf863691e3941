"""Run folders of the error boundary: locks, the cleanup of a failed run, and of runs killed outright."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from motiondiff.runtime.boundary import LOCK_NAME, remove_stale_runs, run_folder
from motiondiff.runtime.errors import UsageError


def dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(proc.stdout)


def killed_run(parent, name, fresh=True, host=None, files=("a_joints.npy",)):
    folder = parent / name
    (folder / ".hydra").mkdir(parents=True)
    for f in files:
        (folder / f).write_bytes(b"x")
    (folder / LOCK_NAME).write_text(f"{dead_pid()} {int(fresh)} {host or socket.gethostname()}")
    return folder


def test_a_killed_runs_folder_goes_at_the_next_start_unless_it_holds_checkpoints_or_was_not_its_own(tmp_path):
    partial = killed_run(tmp_path, "partial")
    trained = killed_run(tmp_path, "trained", files=())
    (trained / "last.ckpt").write_bytes(b"weights")
    users = killed_run(tmp_path, "users", fresh=False)
    elsewhere = killed_run(tmp_path, "elsewhere", host="another-machine")
    complete = tmp_path / "complete"
    complete.mkdir()
    (complete / "results.json").write_text("{}")
    remove_stale_runs(tmp_path)
    assert not partial.exists()
    assert (trained / "last.ckpt").is_file() and not (trained / LOCK_NAME).exists()
    assert (users / "a_joints.npy").is_file() and not (users / LOCK_NAME).exists()
    assert (elsewhere / LOCK_NAME).exists(), "a lock from another machine says nothing about its process here"
    assert (complete / "results.json").is_file()


def test_a_live_runs_folder_is_refused_and_kept(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / LOCK_NAME).write_text(f"{os.getppid()} 1 {socket.gethostname()}")
    with pytest.raises(UsageError, match="another run"):
        with run_folder(out, "sample"):
            pass
    remove_stale_runs(tmp_path)
    assert (out / LOCK_NAME).exists()


def test_a_failed_run_removes_its_fresh_folder_and_a_worker_rank_leaves_it_to_its_parent(tmp_path, monkeypatch):
    out = tmp_path / "run"
    out.mkdir()
    with pytest.raises(RuntimeError):
        with run_folder(out, "sample"):
            (out / "half.npy").write_bytes(b"x")
            raise RuntimeError("failed")
    assert not out.exists()
    out.mkdir()
    monkeypatch.setenv("LOCAL_RANK", "1")
    with pytest.raises(RuntimeError):
        with run_folder(out, "sample"):
            assert not (out / LOCK_NAME).exists()
            raise RuntimeError("failed")
    assert out.exists(), "rank 1 must not remove the folder rank 0 is writing"


def test_a_run_killed_before_its_lock_goes_an_hour_later_and_a_logged_one_stays(tmp_path):
    def started(name: str, log: str, age_s: float) -> Path:
        out = tmp_path / name
        (out / ".hydra").mkdir(parents=True)
        (out / "sample.log").write_text(log)
        then = time.time() - age_s
        os.utime(out, (then, then))
        return out

    old, recent, logged = started("old", "", 7200), started("recent", "", 60), started("logged", "done\n", 7200)
    remove_stale_runs(tmp_path)
    assert not old.exists()
    assert recent.exists(), "a run may be between Hydra's start files and its lock right now"
    assert logged.exists(), "a run that logged got to work: never removed without a lock"


def test_the_sigterm_line_names_the_checkpoint_that_is_kept(tmp_path):
    from motiondiff.runtime.boundary import _resume_hint

    folder = tmp_path / "checkpoints"
    assert _resume_hint(tmp_path) == "; nothing of this run is kept"
    folder.mkdir()
    (folder / "step5.ckpt").write_bytes(b"x")  # stopped between the step checkpoint and its last.ckpt copy
    (folder / "step10.ckpt").write_bytes(b"x")
    assert (
        _resume_hint(tmp_path)
        == f"; its last checkpoint (step 10) is kept: resume with ckpt_path={folder / 'step10.ckpt'}"
    )
    (folder / "last.ckpt").write_bytes(b"x")
    os.utime(folder / "last.ckpt", (time.time() - 60, time.time() - 60))  # the copy of step 5, not yet of step 10
    assert _resume_hint(tmp_path).endswith(f"ckpt_path={folder / 'step10.ckpt'}")
    os.utime(folder / "last.ckpt")
    assert (
        _resume_hint(tmp_path)
        == f"; its last checkpoint (step 10) is kept: resume with ckpt_path={folder / 'last.ckpt'}"
    )
