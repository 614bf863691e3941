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
from fixtures.in_process import run_entry, user_error

from motiondiff.model_files.resolve import SHIPPED_MODELS


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
        "export=gif", "video.size=160", "sampler.steps=4", env_dir=tmp_path, process=True,
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
                "export=none", "sampler.steps=3", "seed=7", "precision=32", env_dir=d, process=k == 1)  # fmt: skip
        outs.append(np.load(next((d / "outputs" / "sample").glob("*/a_person_bows_00_joints.npy"))))
    np.testing.assert_array_equal(outs[0], outs[1])


def test_timestep_spacing_switches_ddim_to_the_official_mdm_steps_and_is_recorded(text_ckpt, tmp_path):
    """timestep_spacing=leading (MDM's DDIM steps, never t = T−1) changes the motion of a seed and lands in
    results.json; the default keeps the model's own (null: the sampler's uniform steps)."""
    joints, recorded = {}, {}
    for spacing in ("null", "leading"):
        d = tmp_path / spacing
        d.mkdir()
        run_cli("sample.py", f"checkpoint={text_ckpt}", "text=a person bows", "num_samples=1", "length=1",
                "export=none", "sampler=ddim", "sampler.steps=4", "seed=7", "precision=32",
                f"timestep_spacing={spacing}", env_dir=d)  # fmt: skip
        out = next((d / "outputs" / "sample").iterdir())
        recorded[spacing] = json.loads((out / "results.json").read_text())["timestep_spacing"]
        joints[spacing] = np.load(out / "a_person_bows_00_joints.npy")
    assert recorded == {"null": None, "leading": "leading"}
    assert np.abs(joints["null"] - joints["leading"]).max() > 1e-4


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
        (["text=a person walks", "length=0"], "length=0: must be a number > 0"),
        (["text=a person walks", "length=-2"], "length=-2: must be a number > 0"),
        (["text=a person walks", "length=60"], "longer than this model's maximum"),
        (["action=walk"], "this model is text-conditioned"),
        (["checkpoint=/nonexistent/model.ckpt", "text=a person walks"], "checkpoint /nonexistent/model.ckpt not found"),
    ],
)
def test_sample_errors_are_one_clear_line(text_ckpt, tmp_path, overrides, message):
    args = list(overrides)
    if not any(a.startswith("checkpoint=") for a in args):
        args.insert(0, f"checkpoint={text_ckpt}")
    if overrides == ["text=   "]:  # one through the CLI: exit code 2, one line (the others in-process: same check)
        proc = run_cli("sample.py", *args, "export=none", env_dir=tmp_path, check=False)
        assert proc.returncode == 2
        assert message in proc.stderr and "Traceback" not in proc.stderr
    else:
        assert message in user_error("sample", tmp_path, *args, "export=none")
    assert not list((tmp_path / "outputs").glob("sample/*/*.npy"))  # nothing written


def test_unknown_action_lists_the_known_ones(action_ckpt, tmp_path):
    err = user_error("sample", tmp_path, f"checkpoint={action_ckpt}", "action=moonwalk")
    assert "unknown action 'moonwalk'" in err
    assert "walk-turn-left" in err and "raise-up-both-hands" in err


@pytest.mark.parametrize("override, group", [("backbone=nope", "backbone"), ("dataset=nope", "dataset")])
def test_unknown_config_names(tmp_path, override, group):
    if group == "dataset":  # through the CLI: Hydra's message on stderr
        proc = run_cli("train.py", override, env_dir=tmp_path, check=False)
        assert proc.returncode != 0
        err = proc.stderr
    else:  # the same message from the composition itself
        from hydra.errors import MissingConfigException

        with pytest.raises(MissingConfigException) as info:
            run_entry("train", tmp_path, override)
        err = str(info.value)
    assert f"Could not find '{group}/nope'" in err and ("Available options" in err or f"'{group}' is one of" in err)
    assert "trans_enc" in err or "bandai_mini" in err


def _final_weights(folder):
    last = next((folder / "outputs").glob("train/*/checkpoints/last.ckpt"))
    return torch.load(last, map_location="cpu", weights_only=True)


def test_kill_and_resume_ends_with_the_uninterrupted_weights(tmp_path):
    """SIGKILL a run at a random step; resuming from its last checkpoint ends with the weights of a run that was
    never interrupted (same seed, CPU), having lost at most one checkpoint interval. The runs cross epoch ends
    (4 batches per epoch) and the killed one stops mid-epoch, so the training order and random state must both
    come back exactly."""
    import random

    every, total = 3, 36
    common = [*TINY, "condition=none", "trainer.check_val_every_n_epoch=3", "callbacks.evaluation.num_clips=8",
              "callbacks.evaluation.steps=3", f"checkpoint_every={every}", "callbacks.evaluation.videos.count=1",
              "callbacks.evaluation.videos.seconds=1"]  # one short unconditioned video per evaluation  # fmt: skip
    reference, killed = tmp_path / "reference", tmp_path / "killed"
    reference.mkdir(), killed.mkdir()
    run_cli("train.py", *common, f"trainer.max_steps={total}", env_dir=reference)
    assert list((reference / "outputs").glob("train/*/videos/step*/0_unconditioned.gif"))
    env = {**os.environ, "MOTIONDIFF_OUTPUT_DIR": str(killed / "outputs"), "MOTIONDIFF_CACHE_DIR": str(killed / "c"),
           "WANDB_MODE": "offline"}  # fmt: skip
    cmd = [sys.executable, str(REPO / "train.py"), *common, "trainer.max_steps=100000",
           "+logger.csv.flush_logs_every_n_steps=1"]  # fmt: skip
    proc = subprocess.Popen(cmd, cwd=killed, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    target = random.Random().randint(2, 8)  # checkpoints on disk before the kill: a random step in 6..24 or so
    deadline = time.time() + 240
    ckpts = []
    while time.time() < deadline and len(ckpts) < target:
        time.sleep(0.05)
        ckpts = list((killed / "outputs").glob("train/*/checkpoints/step*.ckpt"))
    time.sleep(random.Random().uniform(0, 0.3))  # the kill lands anywhere in the next interval
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert len(ckpts) >= target, "no checkpoints were written before the deadline"
    (run,) = (killed / "outputs" / "train").iterdir()
    last = run / "checkpoints" / "last.ckpt"
    saved = torch.load(last, map_location="cpu", weights_only=True)["global_step"]
    rows = (run / "csv" / "version_0" / "metrics.csv").read_text().splitlines()
    logged = [int(r.split(",")[rows[0].split(",").index("step")]) for r in rows[1:] if r]
    lost = max(logged) + 1 - saved  # steps trained after the checkpoint and lost with the kill
    assert 0 <= lost <= every and saved < total
    run_cli("train.py", *common, f"trainer.max_steps={total}", f"ckpt_path={last}", env_dir=killed)
    done = max((killed / "outputs" / "train").iterdir(), key=lambda p: p.stat().st_mtime)
    resumed = torch.load(done / "checkpoints" / "last.ckpt", map_location="cpu", weights_only=True)
    expected = _final_weights(reference)
    assert resumed["global_step"] == expected["global_step"] == total
    diff = max(
        (resumed["state_dict"][k].float() - v.float()).abs().max().item()
        for k, v in expected["state_dict"].items()
        if v.numel()
    )
    print(f"\nkilled at step ~{saved + lost} (checkpoint at {saved}, {lost} steps lost); resumed to {total}: "
          f"largest weight difference from the uninterrupted run {diff:.3g}")  # fmt: skip
    assert diff == 0.0


def test_shipped_model_samples_with_every_export(tmp_path):
    """checkpoint=shipped loads the released safetensors model (no training needed) and export= writes a BVH that
    reads back as the saved joints and a self-contained HTML viewer next to the arrays."""
    from motiondiff.data.formats.bvh import read_bvh

    run_cli("sample.py", "checkpoint=shipped", "text=a person walks forward", "num_samples=1", "length=1",
            "sampler.steps=3", "export=[bvh,html]", env_dir=tmp_path)  # fmt: skip
    out = next((tmp_path / "outputs" / "sample").iterdir())
    summary = json.loads((out / "results.json").read_text())
    assert summary["checkpoint"].endswith(SHIPPED_MODELS["text"].name)
    (row,) = summary["samples"]
    exports = row["exports"]
    assert set(exports) >= {"bvh", "html"} and row["video"] is None
    # a BVH has one bone length per bone; generated joints stretch bones by ~1 cm, which IK cannot follow
    assert exports["bvh_max_error_m"] < 0.03 and exports["bvh_method"] == "ik"
    joints = np.load(row["joints"])
    motion = read_bvh(exports["bvh"])
    assert motion.num_frames == len(joints)
    with open(exports["html"], encoding="utf-8") as viewer:  # the viewer's script and the motion inside: opens offline
        assert 'class="motion-data"' in viewer.read() and os.path.getsize(exports["html"]) <= 300_000


def test_shipped_action_model_samples_an_action_by_name(tmp_path):
    """checkpoint=shipped with action= loads the released action-conditioned model (not the text one), and its
    action names are the full Bandai set's."""
    run_cli("sample.py", "checkpoint=shipped", "action=wave-right-hand", "num_samples=2", "length=1",
            "sampler.steps=3", "export=none", env_dir=tmp_path)  # fmt: skip
    out = next((tmp_path / "outputs" / "sample").iterdir())
    summary = json.loads((out / "results.json").read_text())
    assert summary["checkpoint"].endswith("bandai_action_trans_dec_14k.safetensors")
    assert len(summary["samples"]) == 2 and np.load(summary["samples"][0]["joints"]).shape[1:] == (22, 3)
    proc = run_cli("sample.py", "checkpoint=shipped", "action=moonwalk", "export=none", env_dir=tmp_path, check=False)
    assert proc.returncode == 2 and "unknown action 'moonwalk'" in proc.stderr and "wave-right-hand" in proc.stderr


def test_bad_export_format_is_named_before_sampling(tmp_path):
    proc = run_cli("sample.py", "checkpoint=shipped", "text=a person waves", "export=[mp4,usd]", env_dir=tmp_path,
                   check=False)  # fmt: skip
    assert proc.returncode == 2
    assert "unknown export format(s) usd; choose from mp4, gif, bvh, html" in proc.stderr
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
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "error: ckpt_path=" in proc.stderr and "nothing was run" in proc.stderr
    assert not marker.exists()
