"""SIGKILL at random points of the commands that write: what is left is the old complete result or the new complete
one. Each test first times one complete run (T), then kills ten runs, the k-th at a random moment in the k-th tenth
of T (so start-up, work and the final writes are all hit), and checks what is on disk after every kill."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import torch
from conftest import REPO, command, run_cli

KILLS = 10
BANDAI = REPO.parent / "shared" / "data" / "bandai-namco" / "bandai-ds1.zip"
HYDRA_START = {".hydra", ".motiondiff.lock"}  # what a run has written before its first result


def kill_points(duration: float, seed: int) -> list[float]:
    rng = np.random.default_rng(seed)
    return [float(rng.uniform(k, k + 1) * duration / KILLS) for k in range(KILLS)]


def timed(tmp: Path, name: str, *args: str) -> float:
    start = time.perf_counter()
    proc = run_cli(tmp, name, *args)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return time.perf_counter() - start


def killed(tmp: Path, name: str, *args: str, after: float) -> None:
    """Start ``motiondiff-<name> *args`` in ``tmp`` and SIGKILL it (and any worker it started) ``after`` seconds."""
    env = {**os.environ, "MOTIONDIFF_OUTPUT_DIR": str(tmp / "outputs"), "HYDRA_FULL_ERROR": "0"}
    proc = subprocess.Popen([*command(name), *args], cwd=tmp, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
    try:
        proc.wait(timeout=after)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


# ---- prepare --force ---------------------------------------------------------------------------------------------
PREPARE = ("bandai", "--src", str(BANDAI), "--per-group", "1", "--max-frames", "40", "--compact", "--workers", "1",
           "--caption-variants", "0", "--rare-to-train", "0")  # fmt: skip


def dataset_fingerprint(out: Path) -> str:
    """One hash of everything a prepared dataset holds (the npz members by value: zip headers carry times)."""
    h = hashlib.sha256()
    for name in ("meta.json", "report.json", "Mean.npy", "Std.npy", "README.md", "LICENSE"):
        h.update((out / name).read_bytes())
    for split in ("train", "val", "test"):
        with np.load(out / f"{split}.npz") as z:
            for key in sorted(z.files):
                h.update(key.encode() + np.ascontiguousarray(z[key]).tobytes())
    return h.hexdigest()


@pytest.mark.skipif(not BANDAI.is_file(), reason=f"needs the Bandai Namco data at {BANDAI}")
def test_prepare_force_killed_anywhere_leaves_the_old_dataset_or_the_new_one(tmp_path):
    out = tmp_path / "data" / "ds"
    duration = timed(tmp_path, "prepare", *PREPARE, "--seed", "0", "--out", str(out))
    old = dataset_fingerprint(out)
    seen = []
    for at in kill_points(duration, seed=1):
        killed(tmp_path, "prepare", *PREPARE, "--seed", "1", "--force", "--out", str(out), after=at)
        seen.append(dataset_fingerprint(out))  # raises if a file is missing or unreadable
    timed(tmp_path, "prepare", *PREPARE, "--seed", "1", "--force", "--out", str(out))
    new = dataset_fingerprint(out)
    assert old != new, "the two seeds must give different datasets for the test to mean anything"
    assert set(seen) <= {old, new}, "a killed prepare left a dataset that is neither the old one nor the new one"
    assert sorted(p.name for p in out.parent.iterdir()) == ["ds"], "the next start did not clear the killed builds"


# ---- sampling several prompts ------------------------------------------------------------------------------------
PROMPTS = "a person walks forward\na person jumps\na person waves\n"
SAMPLE = ("checkpoint=shipped", "prompts_file=prompts.txt", "num_samples=2", "length=1", "export=bvh")


def check_sample_folders(root: Path) -> tuple[int, int]:
    """(complete, incomplete) run folders; a complete one has results.json and every file it lists, an
    incomplete one nothing but what a run writes at its start and its sample files, and is still locked."""
    complete = incomplete = 0
    for run in sorted(p for p in root.glob("*") if p.is_dir()):
        results = run / "results.json"
        if results.is_file():
            rows = json.loads(results.read_text())["samples"]
            assert len(rows) == 6, f"{run.name}: {len(rows)} samples listed"
            for row in rows:
                assert np.load(row["joints"]).ndim == 3 and Path(row["exports"]["bvh"]).stat().st_size > 0
            complete += 1
        else:
            names = {p.name for p in run.iterdir()}
            assert ".motiondiff.lock" in names or names <= HYDRA_START | {"sample.log"}, (
                f"{run.name} has results but is neither complete nor marked as a run in progress: {sorted(names)}"
            )
            incomplete += 1
    return complete, incomplete


def test_sampling_several_prompts_killed_anywhere_leaves_no_mixed_folder(tmp_path):
    (tmp_path / "prompts.txt").write_text(PROMPTS)
    duration = timed(tmp_path, "sample", *SAMPLE)
    root = tmp_path / "outputs" / "sample"
    for at in kill_points(duration, seed=2):
        killed(tmp_path, "sample", *SAMPLE, after=at)
        check_sample_folders(root)
    timed(tmp_path, "sample", *SAMPLE)
    complete, _ = check_sample_folders(root)
    leftovers = [p for p in root.iterdir() if not (p / "results.json").exists() and any(
        f.name not in HYDRA_START | {"sample.log"} for f in p.iterdir())]  # fmt: skip
    assert leftovers == [], f"the next start did not clear the killed runs' partial samples: {leftovers}"
    assert complete >= 2


# ---- training ----------------------------------------------------------------------------------------------------
TRAIN = ("model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
         "condition=none", "checkpoint_every=1", "trainer.check_val_every_n_epoch=1000",
         "+trainer.limit_val_batches=0")  # fmt: skip


def newest_last(root: Path) -> Path | None:
    found = sorted(root.glob("*/checkpoints/last.ckpt"), key=lambda p: p.stat().st_mtime)
    return found[-1] if found else None


def test_training_killed_anywhere_leaves_loadable_checkpoints_and_resumes(tmp_path):
    duration = timed(tmp_path, "train", *TRAIN, "trainer.max_steps=30")
    root = tmp_path / "outputs" / "train"
    for at in kill_points(duration, seed=3):
        last = newest_last(root)  # each run resumes the last one's progress, as a user would after a crash
        resume = (f"ckpt_path={last}",) if last is not None else ()
        killed(tmp_path, "train", *TRAIN, "trainer.max_steps=100000", *resume, after=at)
        for ckpt in root.glob("*/checkpoints/[!.]*.ckpt"):  # .<name>.*.tmp.ckpt: a write cut by the kill
            state = torch.load(ckpt, map_location="cpu", weights_only=True)
            assert state["global_step"] > 0 and state["state_dict"], ckpt
    last = newest_last(root)
    step = torch.load(last, map_location="cpu", weights_only=True)["global_step"]
    timed(tmp_path, "train", *TRAIN, f"trainer.max_steps={step + 2}", f"ckpt_path={last}")
    final = torch.load(newest_last(root), map_location="cpu", weights_only=True)
    assert final["global_step"] == step + 2
    cut = sorted(p.name for p in root.glob("*/checkpoints/.*.tmp*"))
    assert cut == [], f"the next start did not remove the killed runs' half-written checkpoints: {cut}"
