"""README commands end to end: train, sample (text, action, sweep), clear errors, kill and resume."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import torch
from cli_helpers import REPO, TINY, run_cli


def test_train_writes_checkpoint_and_logs(text_ckpt):
    run = text_ckpt.parents[1]
    assert (run / ".hydra" / "config.yaml").is_file()  # the full resolved config of the run
    assert list(run.glob("csv/*/metrics.csv"))
    ckpt = torch.load(text_ckpt, map_location="cpu", weights_only=True)  # loads without running pickled code
    hp = ckpt["hyper_parameters"]
    assert ckpt["global_step"] == 4 and hp["condition"]["kind"] == "text" and hp["text_encoder"]["name"] == "minilm"
    record = json.loads((run / "run.json").read_text())  # what produced the run: config, code and packages
    assert record["train_steps"] == 4 and record["provenance"]["config"]["trainer"]["max_steps"] == 4
    assert record["provenance"]["packages"]["lightning"] == "2.6.6" and "commit" in record["provenance"]["git"]
    assert len(hp["mean"]) == len(hp["std"]) == 263


def test_sample_text_writes_joints_features_and_video(text_ckpt, tmp_path):
    run_cli(
        "sample.py", f"checkpoint={text_ckpt}", "text=a person walks forward", "num_samples=2", "length=1.5",
        "export=gif", "sampler.steps=4", env_dir=tmp_path,
    )  # fmt: skip
    out = next((tmp_path / "outputs" / "sample").iterdir())
    results = json.loads((out / "results.json").read_text())["samples"]
    assert len(results) == 2
    for r in results:
        joints = np.load(r["joints"])
        assert joints.shape == (30, 22, 3) and np.isfinite(joints).all()
        assert os.path.getsize(r["video"]) > 1000 and r["video"].endswith(".gif")
    assert np.load(str(out / "a_person_walks_forward_00_features.npy")).shape == (30, 263)


def test_sample_is_deterministic_for_a_seed(text_ckpt, tmp_path):
    outs = []
    for k in range(2):
        d = tmp_path / str(k)
        d.mkdir()
        run_cli("sample.py", f"checkpoint={text_ckpt}", "text=a person bows", "num_samples=1", "length=1",
                "export=none", "sampler.steps=3", "seed=7", env_dir=d)  # fmt: skip
        outs.append(np.load(next((d / "outputs" / "sample").glob("*/a_person_bows_00_joints.npy"))))
    np.testing.assert_array_equal(outs[0], outs[1])


def test_action_sampling_and_guidance_sweep(action_ckpt, tmp_path):
    run_cli("sample.py", "-m", f"checkpoint={action_ckpt}", "action=walk", "guidance=1,3", "num_samples=1",
            "length=1", "export=none", "sampler.steps=3", env_dir=tmp_path)  # fmt: skip
    sweep = next((tmp_path / "outputs" / "sample_multirun").iterdir())
    assert sorted(p.name for p in sweep.iterdir() if p.is_dir()) == ["guidance=1", "guidance=3"]
    for sub in ("guidance=1", "guidance=3"):
        assert json.loads((sweep / sub / "results.json").read_text())["samples"][0]["prompt"] == "walk"


@pytest.mark.parametrize(
    "overrides, message",
    [
        (["text=   "], "the text is empty"),
        (["text=a person walks", "length=0"], "length must be positive"),
        (["text=a person walks", "length=-2"], "length must be positive"),
        (["text=a person walks", "length=60"], "longer than this model's maximum"),
        (["action=walk"], "this model is text-conditioned"),
        (["checkpoint=/nonexistent/model.ckpt", "text=a person walks"], "checkpoint /nonexistent/model.ckpt not found"),
    ],
)
def test_sample_errors_are_one_clear_line(text_ckpt, tmp_path, overrides, message):
    args = [a if a.startswith("checkpoint=") else a for a in overrides]
    if not any(a.startswith("checkpoint=") for a in args):
        args.insert(0, f"checkpoint={text_ckpt}")
    proc = run_cli("sample.py", *args, "export=none", env_dir=tmp_path, check=False)
    assert proc.returncode == 2
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert not list((tmp_path / "outputs").glob("sample/*/*.npy"))  # nothing written


def test_unknown_action_lists_the_known_ones(action_ckpt, tmp_path):
    proc = run_cli("sample.py", f"checkpoint={action_ckpt}", "action=moonwalk", env_dir=tmp_path, check=False)
    assert proc.returncode == 2 and "unknown action 'moonwalk'" in proc.stderr
    assert "walk-turn-left" in proc.stderr and "raise-up-both-hands" in proc.stderr


@pytest.mark.parametrize("override, group", [("backbone=nope", "backbone"), ("dataset=nope", "dataset")])
def test_unknown_config_names(tmp_path, override, group):
    proc = run_cli("train.py", override, env_dir=tmp_path, check=False)
    assert proc.returncode != 0
    assert f"Could not find '{group}/nope'" in proc.stderr and "Available options" in proc.stderr
    assert "trans_enc" in proc.stderr or "bandai_mini" in proc.stderr


def test_kill_and_resume_continues_from_saved_step(tmp_path):
    """SIGKILL a training run after a checkpoint exists; resuming starts at that checkpoint's step."""
    env = {
        **os.environ,
        "MOTIONDIFF_OUTPUT_DIR": str(tmp_path / "outputs"),
        "MOTIONDIFF_CACHE_DIR": str(tmp_path / "c"),
    }
    cmd = [
        sys.executable,
        str(REPO / "train.py"),
        *TINY,
        "condition=none",
        "trainer.max_steps=100000",
        "checkpoint_every=3",
    ]
    proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 240
    ckpts = []
    while time.time() < deadline and len(ckpts) < 2:
        time.sleep(0.5)
        ckpts = sorted((tmp_path / "outputs").glob("train/*/checkpoints/step*.ckpt"))
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert len(ckpts) >= 2, "no checkpoints were written before the deadline"
    last = next((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"))
    saved = torch.load(last, map_location="cpu", weights_only=True)["global_step"]
    assert saved >= 3 and saved % 3 == 0
    run_cli("train.py", *TINY, "condition=none", f"trainer.max_steps={saved + 3}", f"ckpt_path={last}",
            env_dir=tmp_path)  # fmt: skip
    resumed = sorted((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"), key=lambda p: p.stat().st_mtime)[-1]
    assert resumed != last
    assert torch.load(resumed, map_location="cpu", weights_only=True)["global_step"] == saved + 3
    metrics = next(resumed.parents[1].glob("csv/*/metrics.csv")).read_text().splitlines()
    steps = [int(row.split(",")[metrics[0].split(",").index("step")]) for row in metrics[1:] if row]
    assert min(steps) >= saved  # the resumed run logged only steps after the checkpoint
    print(f"\nkilled with {len(ckpts)} checkpoints on disk; resumed from step {saved}, first logged step {min(steps)}, "
          f"finished at {saved + 3}")  # fmt: skip


def test_shipped_model_samples_with_every_export(tmp_path):
    """checkpoint=shipped loads the released safetensors model (no training needed) and export= writes a BVH that
    reads back as the saved joints and a self-contained HTML viewer next to the arrays."""
    from motiondiff.data.bvh import read_bvh

    run_cli("sample.py", "checkpoint=shipped", "text=a person walks forward", "num_samples=1", "length=1",
            "sampler.steps=3", "export=[bvh,html]", env_dir=tmp_path)  # fmt: skip
    out = next((tmp_path / "outputs" / "sample").iterdir())
    summary = json.loads((out / "results.json").read_text())
    assert summary["checkpoint"].endswith("bandai_mini_text_cpu.safetensors")
    (row,) = summary["samples"]
    exports = row["exports"]
    assert set(exports) >= {"bvh", "html"} and row["video"] is None
    # a BVH has one bone length per bone; generated joints stretch bones by ~1 cm, which IK cannot follow
    assert exports["bvh_max_error_m"] < 0.03 and exports["bvh_method"] == "ik"
    joints = np.load(row["joints"])
    motion = read_bvh(exports["bvh"])
    assert motion.num_frames == len(joints)
    assert os.path.getsize(exports["html"]) > 1_000_000  # plotly.js inside: opens offline


def test_bad_export_format_is_named_before_sampling(tmp_path):
    proc = run_cli("sample.py", "checkpoint=shipped", "text=a person waves", "export=[mp4,fbx]", env_dir=tmp_path,
                   check=False)  # fmt: skip
    assert proc.returncode == 2
    assert "unknown export format(s) fbx; choose from mp4, gif, bvh, html" in proc.stderr
    assert not (tmp_path / "outputs" / "sample").exists() or not any((tmp_path / "outputs" / "sample").rglob("*.npy"))


def test_resuming_from_a_crafted_checkpoint_runs_no_code(tmp_path):
    """train.py ckpt_path= goes through Lightning's loader with weights_only=True: a pickle that would create a
    marker file while loading is refused before training starts."""
    import torch

    marker = tmp_path / "code_ran"

    class Payload:
        def __reduce__(self):
            return (open, (str(marker), "w"))

    crafted = tmp_path / "last.ckpt"
    torch.save({"state_dict": {}, "payload": Payload()}, crafted)
    proc = run_cli("train.py", *TINY, "trainer.max_steps=2", f"ckpt_path={crafted}", env_dir=tmp_path, check=False)
    assert proc.returncode != 0 and "Weights only load failed" in proc.stdout + proc.stderr
    assert not marker.exists()
