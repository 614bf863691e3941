"""A dataset folder is built beside the old one and swapped in: old or new, never a mixture."""

from __future__ import annotations

import subprocess
import sys

import pytest

from motiondiff.data.preparing import staging
from motiondiff.data.preparing.staging import recover, staged_folder
from motiondiff.data.preparing.writer import PrepareError


def dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(proc.stdout)


def old_dataset(tmp_path):
    out = tmp_path / "ds"
    out.mkdir()
    (out / "train.npz").write_text("old")
    (out / "meta.json").write_text("old")
    (out / "notes.txt").write_text("the user's")
    return out


@pytest.mark.parametrize("exchange", [True, False], ids=["renameat2", "two_renames"])
def test_the_new_folder_replaces_the_old_and_keeps_files_it_did_not_write(tmp_path, monkeypatch, exchange):
    if not exchange:
        monkeypatch.setattr(staging, "_exchange", lambda a, b: False)
    out = old_dataset(tmp_path)
    with staged_folder(out, force=True) as build:
        assert build.parent == out.parent and build.name.startswith(".ds.building-")
        (build / "train.npz").write_text("new")
        assert (out / "train.npz").read_text() == "old", "the old dataset stays in place while the new one builds"
        (build / "meta.json").write_text("new")
    assert (out / "train.npz").read_text() == (out / "meta.json").read_text() == "new"
    assert (out / "notes.txt").read_text() == "the user's"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]


def test_a_failed_build_leaves_the_old_dataset_and_no_temporary_folder(tmp_path):
    out = old_dataset(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        with staged_folder(out, force=True) as build:
            (build / "train.npz").write_text("half")
            raise KeyboardInterrupt
    assert (out / "train.npz").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]


def test_the_next_start_repairs_a_killed_swap_and_removes_dead_builds(tmp_path):
    pid = dead_pid()
    aside = tmp_path / f".ds.replaced-{pid}"  # killed between the fallback's two renames: no ds at all
    aside.mkdir()
    (aside / "meta.json").write_text("old")
    dead_build = tmp_path / f".ds.building-{pid}"
    dead_build.mkdir()
    other = tmp_path / f".other.building-{pid}"  # another dataset's: not ours to touch
    other.mkdir()
    recover(tmp_path / "ds")
    assert (tmp_path / "ds" / "meta.json").read_text() == "old"
    assert not aside.exists() and not dead_build.exists() and other.exists()


def test_a_second_writer_is_refused_while_the_first_is_alive_and_a_dead_ones_lock_is_taken_over(tmp_path):
    out = tmp_path / "ds"
    lock = tmp_path / ".ds.lock"
    with subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]) as other:
        try:
            lock.write_text(str(other.pid))  # a live prepare holds the folder
            with pytest.raises(PrepareError, match=f"another prepare \\(pid {other.pid}\\) is writing --out"):
                with staged_folder(out):
                    pass
            assert not out.exists() and lock.read_text() == str(other.pid)
        finally:
            other.kill()
    lock.write_text(str(dead_pid()))  # its prepare was killed
    with staged_folder(out) as build:
        (build / "meta.json").write_text("new")
        assert lock.read_text() != ""
    assert (out / "meta.json").read_text() == "new" and not lock.exists()


def test_a_dataset_finished_by_another_run_meanwhile_is_not_replaced_without_force(tmp_path):
    out = old_dataset(tmp_path)
    with pytest.raises(PrepareError, match="already holds a prepared dataset; pass --force"):
        with staged_folder(out):
            pass
    assert (out / "train.npz").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ds"]
