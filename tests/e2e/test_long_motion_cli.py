"""Timed prompts end to end: `sample.py prompts="[...:2, ...:2, ...:2]"` writes ONE motion longer than the model's
max_frames with a boundary report per seam; the prompt syntax and its errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import run_cli

from motiondiff.cli.common import UsageError
from motiondiff.cli.prompt_inputs import parse_timed_prompts

FAST = ["sampler=ddim", "steps=5", "export=none", "num_samples=1"]


def results_of(tmp_path) -> tuple[dict, object]:
    out = next((tmp_path / "outputs" / "sample").iterdir())
    return json.loads((out / "results.json").read_text()), out


def test_three_timed_prompts_make_one_long_motion(text_ckpt, tmp_path):
    prompts = "prompts=[a person walks forward:2, a person waves both hands:2, a person walks back:2]"
    run_cli("sample.py", f"checkpoint={text_ckpt}", prompts, "overlap=0.5", "smooth_sigma=1.5", *FAST,
            env_dir=tmp_path)  # fmt: skip
    results, out = results_of(tmp_path)
    long = results["long_motion"]
    assert long["frames"] == 120 and long["seconds"] == 6 and long["frames"] > long["max_frames"] == 80
    assert [(s["label"], s["start"], s["end"]) for s in long["segments"]] == [
        ("a person walks forward", 0, 40),
        ("a person waves both hands", 40, 80),
        ("a person walks back", 80, 120),
    ]
    assert long["overlap_frames"] == 10 and long["blend_frames"] == 5 and long["edit_mode"] == "overwrite"
    (sample,) = results["samples"]
    assert sample["frames"] == 120 and sample["prompt"].startswith("a person walks forward:2, a person waves")
    seams = [b["frame"] for b in sample["boundaries"]]
    assert seams == [w["start"] for w in long["windows"][1:]] and {40, 80} <= set(seams)
    for b in sample["boundaries"]:
        assert b["ratio"] == pytest.approx(b["speed"] / b["median_speed"]) and "ratio_smoothed" in b
    assert sample["max_boundary_ratio"] == max(b["ratio"] for b in sample["boundaries"])
    joints = np.load(sample["joints"])
    assert joints.shape == (120, 22, 3) and np.isfinite(joints).all()
    assert np.load(sample["joints"].replace("_joints.npy", "_joints_raw.npy")).shape == (120, 22, 3)
    assert np.load(sample["joints"].replace("_joints.npy", "_features.npy")).shape == (120, 263)
    smoothing = sample["smoothing"]
    assert smoothing["sigma_frames"] == 1.5 and smoothing["smoothness_after"] >= smoothing["smoothness_before"]
    print(f"\nboundary ratios (tiny 4-step model): {[round(b['ratio'], 2) for b in sample['boundaries']]}")


def test_timed_actions_make_one_long_motion(action_ckpt, tmp_path):
    run_cli("sample.py", f"checkpoint={action_ckpt}", "action=[walk:3, walk:2.5]", *FAST, env_dir=tmp_path)
    results, _ = results_of(tmp_path)
    assert results["long_motion"]["frames"] == 110 and results["samples"][0]["frames"] == 110
    assert [s["label"] for s in results["long_motion"]["segments"]] == ["walk", "walk"]


@pytest.mark.parametrize(
    "overrides, message",
    [
        (["prompts=[a person walks:2, a person waves]"], "these have no time: 'a person waves'"),
        (["prompts=[a person walks:2, a person waves:0]"], "seconds after the colon must be a number in"),
        (["prompts=[a person walks:2, a person waves:2]", "overlap=4"], "overlap is the seconds"),
        (["prompts=[a person walks:2, a person waves:2]", "overlap=0.5", "blend=0.5"], "blend is the seconds"),
    ],
)
def test_timed_prompt_errors_are_one_clear_line(text_ckpt, tmp_path, overrides, message):
    if overrides == ["prompts=[a person walks:2, a person waves]"]:  # one through the CLI: exit code 2, one line
        proc = run_cli("sample.py", f"checkpoint={text_ckpt}", *overrides, "export=none", env_dir=tmp_path, check=False)
        assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr
        return
    from hydra import compose, initialize_config_dir

    from motiondiff.cli.prompt_inputs import split_timed
    from motiondiff.cli.sample import collect_prompts
    from motiondiff.edit.long_motion import check_long_settings
    from motiondiff.model_files.loading import load_model
    from motiondiff.runtime.errors import UsageError
    from motiondiff.runtime.paths import CONF_DIR
    from motiondiff.runtime.scripting import register_resolvers

    register_resolvers()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("sample", overrides=[f"checkpoint={text_ckpt}", *overrides])
    with pytest.raises(UsageError, match=message):
        plain, seconds = split_timed(cfg)
        module = load_model(text_ckpt)
        check_long_settings(module, collect_prompts(plain, module), seconds, cfg.overlap, cfg.blend, cfg.edit_mode,
                            cfg.resample)  # fmt: skip


def test_parse_timed_prompts():
    assert parse_timed_prompts(["a person walks forward:4", "waves: 2.5s", "jumps : .5"]) == [
        ("a person walks forward", 4.0), ("waves", 2.5), ("jumps", 0.5)]  # fmt: skip
    assert parse_timed_prompts(["a person walks", "a person: bows"]) is None  # untimed: separate samples, as before
    assert parse_timed_prompts(["note: 3 steps:2"]) == [("note: 3 steps", 2.0)]  # the last colon carries the time
    for items, message in [
        (["walks:4", "waves"], "these have no time: 'waves'"),
        (["walks:4", "waves:-1"], "must be a number in"),
        (["walks:0"], "must be a number in"),
        ([":3"], "no prompt before the colon"),
    ]:
        with pytest.raises(UsageError, match=message):
            parse_timed_prompts(items)
