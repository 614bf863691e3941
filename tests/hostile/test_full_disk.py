"""A full disk, for real: each case mounts a small tmpfs (root or CAP_SYS_ADMIN; skipped with the reason where a
mount is refused) and points a command's output at it. The run folder's disk is checked for room before Hydra
writes there; a `prepare` whose disk fills while it writes, and a training run whose checkpoint does not fit, end
with one ``error:`` line (exit 2) that says to free disk space, and leave nothing half-written on that disk."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from hostile_cli import assert_refused, run_in_process
from kill_runs import BANDAI


@pytest.fixture
def small_disk(tmp_path):
    """``make(kib, free_kib)``: a tmpfs of ``kib`` KiB under tmp_path, filled (a file named filler) until about
    ``free_kib`` KiB are left; unmounted after the test."""
    mounted = []

    def make(kib: int, free_kib: int | None = None) -> Path:
        disk = tmp_path / f"disk{len(mounted)}"
        disk.mkdir()
        proc = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={kib}k", "tmpfs", str(disk)],
                              capture_output=True, text=True)  # fmt: skip
        if proc.returncode != 0:
            pytest.skip(f"cannot mount a small tmpfs here ({proc.stderr.strip()[:120]}): needs root or CAP_SYS_ADMIN")
        mounted.append(disk)
        if free_kib is not None:
            (disk / "filler").write_bytes(b"\0" * max(0, shutil.disk_usage(disk).free - free_kib * 1024))
        return disk

    yield make
    for disk in mounted:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def left_on(disk: Path) -> list[str]:
    return sorted(p.relative_to(disk).as_posix() for p in disk.rglob("*") if p.name != "filler")


def test_a_run_folder_on_a_full_disk_is_refused_before_hydra_writes(tmp_path, small_disk):
    disk = small_disk(2048, free_kib=200)
    proc = run_in_process(tmp_path, "sample", "checkpoint=shipped", "text=a person walks", "length=1",
                          "export=none", f"hydra.run.dir={disk / 'run'}")  # fmt: skip
    assert_refused(proc, "KiB free", "free some disk space")
    assert left_on(disk) == []


@pytest.mark.skipif(not BANDAI.is_file(), reason=f"needs the Bandai Namco data at {BANDAI}")
def test_prepare_on_a_disk_that_fills_is_one_line_and_leaves_no_half_dataset(tmp_path, small_disk):
    disk = small_disk(4096, free_kib=96)
    proc = run_in_process(tmp_path, "prepare", "bandai", "--src", str(BANDAI), "--per-group", "1", "--max-frames",
                          "40", "--workers", "1", "--caption-variants", "0", "--out", str(disk / "ds"))  # fmt: skip
    assert_refused(proc, "No space left on device", "free some disk space")
    assert left_on(disk) == [], "a half-written dataset, build folder or lock was left"


def test_a_training_checkpoint_that_does_not_fit_is_one_line_and_leaves_no_half_file(tmp_path, small_disk):
    disk = small_disk(4096, free_kib=1536)  # room for Hydra's files and the logs, not for a 12 MB checkpoint
    proc = run_in_process(tmp_path, "train", "model.d_model=256", "model.num_layers=2", "model.num_heads=4",
                          "model.ff_size=512", "condition=none", "logger=csv", "trainer.max_steps=4",
                          "checkpoint_every=2", "callbacks.evaluation=null", f"hydra.run.dir={disk / 'run'}")  # fmt: skip
    assert_refused(proc, "No space left on device", "checkpoints/step", "free some disk space")
    assert not [name for name in left_on(disk) if ".tmp" in name or name.endswith(".ckpt")], left_on(disk)
