"""Issue 41's command-line cases that need more than a refusal (docs/reliability.md, "Issue 41's cases and their
tests"), each as a real process of the command the issue names: a 200 MB prompts file refused before it is read (the
child's peak memory measured), a full disk at three moments (small tmpfs mounts), a SIGTERM'd edit and a run aimed at
its folder while it writes, Ctrl-C in evaluate, a `$_$` prompt in a video title, `python edit.py ... --cfg job`, and
what held in the issue's probe or was fixed before it and must stay (BVH variants, a read-only output folder, a
prompt written as an interpolation, two runs in one second).
A refusal is one ``error:`` line with its exit code and no traceback, and leaves the user's files as they were."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from datetime import datetime
from pathlib import Path

import numpy as np
import pytest
import test_full_disk
from bounds_files import bvh_text, write
from hostile_cli import REPO, assert_refused, cli_env, files_under, popen_cli, run_cli, run_in_process
from issue41_files import bvh_folder, changed, tree
from test_bounds import run_measured
from test_full_disk import left_on
from test_interrupts import _as_at_a_terminal, wait_for

MODEL = "checkpoint=shipped"
CLIP = "input=test:dataset-1_walk_active_001"
small_disk = test_full_disk.small_disk  # the fixture: a small tmpfs, filled to a given room
TINY_TRAIN = ("model.d_model=256", "model.num_layers=2", "model.num_heads=4", "model.ff_size=512", "condition=none",
              "logger=csv", "callbacks.evaluation=null")  # fmt: skip


def _lock_of(tmp: Path, task: str) -> Path | None:
    return next((tmp / "outputs" / task).glob("*/.motiondiff.lock"), None)


def _ended(proc: subprocess.Popen, timeout: float = 120) -> subprocess.CompletedProcess:
    out, err = proc.communicate(timeout=timeout)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def test_a_200_mb_one_line_prompts_file_is_refused_before_it_is_read(tmp_path):
    big = tmp_path / "prompts.txt"
    with big.open("w") as f:  # one line of 200 MiB, no newline
        for _ in range(200):
            f.write("a person walks " * (2**20 // 15) + "x" * (2**20 % 15))
    try:
        before = tree(tmp_path)
        proc, peak = run_measured(tmp_path, "sample", MODEL, "prompts_file=prompts.txt")
        assert_refused(proc, f"prompts.txt has {200 * 2**20:,} bytes; at most", "split it")
        # the command alone peaks near 0.45 GiB; reading the file as text would add at least twice its 0.2 GiB
        assert peak < 0.75 * 2**30, f"peak RSS {peak / 2**30:.2f} GiB: the file was read"
        assert changed(before, tree(tmp_path)) == []
    finally:
        big.unlink()  # pytest keeps the last runs' folders: not 200 MB of them


# ---- a full disk: before Hydra writes, while prepare writes, while a checkpoint is written ------------------------


def test_a_run_folder_on_a_full_disk_is_refused_before_hydra_writes(tmp_path, small_disk):
    disk = small_disk(2048, free_kib=200)
    proc = run_cli(tmp_path, "sample", MODEL, "text=a person walks", "length=1", "export=none",
                   f"hydra.run.dir={disk / 'run'}")  # fmt: skip
    assert_refused(proc, "KiB free", "free some disk space")
    assert left_on(disk) == []


def test_prepare_on_a_disk_that_fills_is_one_line_and_leaves_no_half_dataset(tmp_path, small_disk):
    disk = small_disk(1024, free_kib=16)  # the tiny dataset takes about 0.1 MB
    bvh_folder(tmp_path / "src")
    proc = run_cli(tmp_path, "prepare", "bvh", "--src", "src", "--workers", "1", "--out", str(disk / "ds"))
    assert_refused(proc, "No space left on device", "free some disk space")
    assert left_on(disk) == [], "a half-written dataset, build folder or lock was left"


def test_a_training_checkpoint_that_does_not_fit_is_one_line_and_leaves_no_half_file(tmp_path, small_disk):
    disk = small_disk(4096, free_kib=1536)  # room for Hydra's files and the logs, not for a 12 MB checkpoint
    proc = run_cli(tmp_path, "train", *TINY_TRAIN, "trainer.max_steps=4", "checkpoint_every=2",
                   f"hydra.run.dir={disk / 'run'}")  # fmt: skip
    assert_refused(proc, "No space left on device", "checkpoints/step", "free some disk space")
    assert not [name for name in left_on(disk) if ".tmp" in name or name.endswith(".ckpt")], left_on(disk)


def test_an_output_folder_on_a_read_only_disk_is_one_line(tmp_path, small_disk):
    disk = small_disk(1024)
    remount = subprocess.run(["mount", "-o", "remount,ro", str(disk)], capture_output=True, text=True)
    if remount.returncode != 0:
        pytest.skip(f"cannot remount the tmpfs read-only ({remount.stderr.strip()[:120]})")
    proc = run_cli(tmp_path, "sample", MODEL, "text=a person walks", "length=1", "export=none",
                   f"paths.output_dir={disk}")  # fmt: skip
    assert_refused(proc, "cannot make the run folder", "Read-only file system", "set a writable paths.output_dir=")
    assert left_on(disk) == []


# ---- signals and a second run while the first writes -------------------------------------------------------------


def test_a_run_into_a_live_edits_folder_changes_nothing_and_a_sigtermed_edit_leaves_no_folder(tmp_path):
    """The edit is paused (SIGSTOP) once it holds its folder, so the second run surely meets it alive; then SIGTERM."""
    edit = popen_cli(tmp_path, "edit", MODEL, CLIP, "num_samples=1", "export=none", "steps=50",
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert wait_for(lambda: _lock_of(tmp_path, "edit") is not None or edit.poll() is not None, 600)
        edit.send_signal(signal.SIGSTOP)
        lock = _lock_of(tmp_path, "edit")
        assert lock is not None, "the edit ended before it could be stopped"
        run_dir = lock.parent
        before = tree(run_dir)
        second = run_cli(tmp_path, "sample", MODEL, "text=a person walks", "length=1", "export=none",
                         f"hydra.run.dir={run_dir}")  # fmt: skip
        assert_refused(second, "another run", "is writing to", str(run_dir))
        assert changed(before, tree(run_dir)) == [], "the refused run rewrote the live run's records"
        edit.send_signal(signal.SIGTERM)
        edit.send_signal(signal.SIGCONT)
        stopped = _ended(edit)
    finally:
        edit.kill()
    assert_refused(stopped, "stopped by SIGTERM", "nothing of this run is kept", code=143)
    assert files_under(tmp_path / "outputs") == [] and not run_dir.exists(), "the SIGTERM'd edit left its folder"


def test_ctrl_c_in_evaluate_is_one_line_exit_130_and_leaves_no_folder(tmp_path):
    proc = popen_cli(tmp_path, "evaluate", MODEL, "replications=1", "mm_replications=0", "steps=2", "batch_size=16",
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_as_at_a_terminal)  # fmt: skip
    try:
        assert wait_for(lambda: _lock_of(tmp_path, "evaluate") is not None or proc.poll() is not None, 600)
        assert proc.poll() is None, "evaluate ended before it could be interrupted"
        proc.send_signal(signal.SIGINT)
        done = _ended(proc)
    finally:
        proc.kill()
    assert_refused(done, "interrupted (Ctrl-C)", code=130)
    assert files_under(tmp_path / "outputs") == []


# ---- what must run, not fail ----------------------------------------------------------------------------------------


def _no_error(proc: subprocess.CompletedProcess) -> None:
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr + proc.stdout and "error:" not in proc.stderr, proc.stderr[-3000:]


def test_a_prompt_that_looks_like_mathtext_is_sampled_and_drawn_in_its_video(tmp_path):
    proc = run_cli(tmp_path, "sample", MODEL, "text='$_$'", "num_samples=1", "length=1", "export=mp4",
                   "sampler=ddim", "steps=2")  # fmt: skip
    _no_error(proc)
    (results,) = (tmp_path / "outputs").rglob("results.json")
    (row,) = json.loads(results.read_text())["samples"]
    assert row["prompt"] == "$_$" and Path(row["video"]).suffix == ".mp4" and Path(row["video"]).stat().st_size > 0


def test_edit_py_with_hydras_cfg_flag_after_an_override_prints_the_config(tmp_path):
    proc = subprocess.run([sys.executable, str(REPO / "edit.py"), "clip_x0=static", "--cfg", "job"], cwd=tmp_path,
                          env=cli_env(tmp_path), capture_output=True, text=True, timeout=300)  # fmt: skip
    _no_error(proc)
    assert "clip_x0: static" in proc.stdout and "unrecognized arguments" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_bvh_files_in_unicode_crlf_with_a_bom_or_nested_300_deep_are_read_or_skipped_with_the_reason(tmp_path):
    src = bvh_folder(tmp_path / "src", copies=9)
    text = bvh_text(40)
    write(src / "walk_ünïcödé_歩く.bvh", text)
    (src / "crlf.bvh").write_bytes(text.replace("\n", "\r\n").encode())
    (src / "bom.bvh").write_bytes(b"\xef\xbb\xbf" + text.encode())
    head = ["HIERARCHY", "ROOT Hips", "{", "OFFSET 0 0 0", "CHANNELS 6 Xposition Yposition Zposition Zrotation "
            "Xrotation Yrotation"]  # fmt: skip
    nested = [f"JOINT J{k}\n{{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation" for k in range(300)]
    rows = [" ".join(["0"] * (6 + 3 * 300))] * 3
    write(src / "deep.bvh", "\n".join([*head, *nested, "End Site\n{\nOFFSET 0 1 0\n}", *["}"] * 301, "MOTION",
                                       "Frames: 3", "Frame Time: 0.05", *rows, ""]))  # fmt: skip
    proc = run_cli(tmp_path, "prepare", "bvh", "--src", "src", "--workers", "1", "--out", "ds")
    _no_error(proc)
    ids = {str(i) for split in ("train", "val", "test") for i in np.load(tmp_path / "ds" / f"{split}.npz")["ids"]}
    assert {"walk_ünïcödé_歩く", "crlf", "bom"} <= ids and len(ids) == 12
    (skipped,) = json.loads((tmp_path / "ds" / "report.json").read_text())["skipped"]
    assert skipped["clip"] == "deep" and "nested more than 200 deep" in skipped["reason"]


def test_a_prompt_that_looks_like_an_interpolation_is_written_as_typed(tmp_path):
    text = "${oc.env:MOTIONDIFF_TEST_SECRET}"
    proc = run_cli(tmp_path, "sample", MODEL, f"text='{text}'", "num_samples=1", "length=1", "export=bvh",
                   "sampler=ddim", "steps=2", env={"MOTIONDIFF_TEST_SECRET": "secret-value"})  # fmt: skip
    _no_error(proc)
    (results,) = (tmp_path / "outputs").rglob("results.json")
    assert [row["prompt"] for row in json.loads(results.read_text())["samples"]] == [text]
    assert not [p for p in (tmp_path / "outputs").rglob("*") if p.is_file() and b"secret-value" in p.read_bytes()]


def test_two_runs_in_one_second_get_a_folder_each(tmp_path, monkeypatch):
    """In this process, with Hydra's clock stopped: two processes differ by pid anyway, one process twice must too."""
    import hydra.core.utils

    class Stopped(datetime):
        @classmethod
        def now(cls, tz=None):
            return datetime(2026, 12, 6, 12, 0, 0)

    monkeypatch.setattr(hydra.core.utils, "datetime", Stopped)
    args = (MODEL, "text=a person walks", "num_samples=1", "length=1", "export=none", "sampler=ddim", "steps=2")
    for _ in range(2):
        _no_error(run_in_process(tmp_path, "sample", *args))
    runs = sorted((tmp_path / "outputs" / "sample").iterdir())
    assert len(runs) == 2 and all(p.name.startswith("2026-12-06_12-00-00_") for p in runs), runs
    assert all((p / "results.json").is_file() for p in runs)
