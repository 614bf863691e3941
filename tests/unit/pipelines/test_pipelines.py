"""The pipeline API with the released models: generate, edit, chain, save and export, and one clear error for each
kind of bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiondiff.data.formats.bvh import read_bvh
from motiondiff.pipelines import MotionOutput, MotionPipeline
from motiondiff.runtime.errors import UsageError

CLIP = "test:dataset-1_walk_active_001"


@pytest.fixture(scope="module")
def pipe():
    return MotionPipeline.from_pretrained("text")


def test_text_to_motion_and_reproducible_seeds(pipe):
    out = pipe(["a person walks forward", "a person waves"], seconds=[2, 3], num_samples=2, steps=5, seed=1)
    assert isinstance(out, MotionOutput) and len(out) == 4 and out.fps == pipe.fps == 20
    assert [len(j) for j in out.joints] == [40, 40, 60, 60] and out.joints[0].shape[1:] == (22, 3)
    assert out.prompts == ["a person walks forward"] * 2 + ["a person waves"] * 2
    assert np.isfinite(np.concatenate([j.reshape(-1) for j in out.joints])).all()
    again = pipe(["a person walks forward", "a person waves"], seconds=[2, 3], num_samples=2, steps=5, seed=1)
    assert all(np.array_equal(a, b) for a, b in zip(out.joints, again.joints, strict=True))
    assert not np.array_equal(out.joints[0], out.joints[1])  # two samples of one prompt differ
    assert out.info["steps"] == 5 and out.info["guidance"] == pipe.model.default_guidance


def test_the_default_sampler_is_the_models_own(pipe, monkeypatch):
    out = pipe("a person walks forward", seconds=1)
    assert out.info["sampler"] == "dpmpp" and out.info["steps"] == 10 and np.isfinite(out.joints[0]).all()  # its JSON
    assert pipe("a person walks forward", seconds=1, sampler="ddim").info["steps"] == 50
    monkeypatch.setitem(pipe.model.hparams.model, "sample_sampler", "ddim")  # a recipe that chose DDIM on val
    assert pipe("a person walks forward", seconds=1, steps=3).info["sampler"] == "ddim"
    with pytest.raises(UsageError, match="sampler must be auto or one of"):
        pipe("a person walks forward", seconds=1, sampler="euler")


def test_the_models_own_sampler_runs_its_own_steps(pipe, monkeypatch):
    from omegaconf import OmegaConf

    from motiondiff.cli.common import sampling_steps
    from motiondiff.runtime.paths import REPO_DIR

    monkeypatch.setitem(pipe.model.hparams.model, "sample_steps", 12)  # a recipe that chose DPM-Solver++-12 on val
    assert pipe.model.default_steps("dpmpp") == 12 and pipe.model.default_steps("ddim") == 50
    assert pipe("a person walks forward", seconds=1).info["steps"] == 12
    assert pipe("a person walks forward", seconds=1, sampler="dpmpp").info["steps"] == 12
    assert pipe("a person walks forward", seconds=1, sampler="ddim").info["steps"] == 50
    assert pipe("a person walks forward", seconds=1, steps=4).info["steps"] == 4
    for sampler, steps, expected in (("auto", None, 12), ("dpmpp", None, 12), ("ddim", None, 50), ("auto", 3, 3)):
        cfg = OmegaConf.create(
            {"sampler": OmegaConf.load(REPO_DIR / "conf" / "sampler" / f"{sampler}.yaml"), "steps": steps}
        )
        assert sampling_steps(cfg, pipe.model) == expected, (sampler, steps)


def test_save_and_export(pipe, tmp_path):
    out = pipe("a person walks forward", seconds=2, steps=3)
    rows = out.save(tmp_path / "walk", formats=["bvh", "html"])
    assert rows[0]["joints"].endswith("walk/a_person_walks_forward_00_joints.npy")  # as sample.py names it
    assert np.load(rows[0]["joints"]).shape == (40, 22, 3)
    assert read_bvh(rows[0]["exports"]["bvh"]).num_frames == 40
    assert (tmp_path / "walk" / "results.json").is_file() and rows[0]["exports"]["html"].endswith(".html")
    assert json.loads((tmp_path / "walk" / "results.json").read_text())["samples"][0]["prompt"] == out.prompts[0]
    shown = out.show()
    assert out.to_bvh().startswith("HIERARCHY") and "<html" in getattr(shown, "data", shown).lower()


def test_editing_keeps_what_it_should(pipe):
    middle = pipe.inbetween(CLIP, "a person jumps", steps=5)
    kept = middle.info["prefix_frames"][0]
    assert kept > 0 and middle.info["kind"] == "inbetween"
    parts = pipe.edit_parts(CLIP, "a person raises both hands", parts="upper_body", steps=5)
    assert "l_hip" in parts.info["kept_joints"] and "l_wrist" not in parts.info["kept_joints"]
    made = pipe("a person walks forward", seconds=3, steps=3)
    again = pipe.inbetween(made, "a person waves", steps=3)  # a motion it made can be edited too
    assert len(again.joints[0]) >= 50


def test_long_motion_through_prompts_in_order(pipe):
    long = pipe.long(["a person walks forward:3", "a person waves:2"], steps=3)
    assert len(long.joints[0]) == 100 and [s["label"] for s in long.info["segments"]] == [
        "a person walks forward",
        "a person waves",
    ]


def test_action_model_takes_action_names():
    pipe = MotionPipeline.from_pretrained("action")
    out = pipe(pipe.actions[:2], seconds=1, steps=3)
    assert out.prompts == pipe.actions[:2] and pipe.condition_kind == "action"
    assert out.info["sampler"] == "ddim"  # its recipe kept DDIM-50: DPM-Solver++-7 missed its val FID
    with pytest.raises(UsageError, match="unknown action 'fly'"):
        pipe("fly")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"prompt": ""}, "text is empty"),
        ({"prompt": "walk", "seconds": 60}, "longer than this model's maximum"),
        ({"prompt": "walk", "seconds": float("nan")}, "seconds must be a number"),
        ({"prompt": "walk", "num_samples": 0}, "num_samples"),
        ({"prompt": "walk", "num_samples": 100000}, "num_samples=100000: must be a whole number from 1 to 1000"),
        ({"prompt": "walk", "guidance": -1}, "guidance"),
        ({"prompt": "walk", "steps": 5000}, "steps must be"),
        ({"prompt": "walk", "sampler": "euler"}, "sampler"),
        ({"prompt": ["a", "b"], "seconds": [1, 2, 3]}, "one per prompt"),
    ],
)
def test_bad_input_is_one_clear_error(pipe, kwargs, message):
    prompt = kwargs.pop("prompt")
    with pytest.raises(UsageError, match=message):
        pipe(prompt, **kwargs)


def test_long_motion_samples_at_most_one_batch(pipe):
    with pytest.raises(UsageError, match="num_samples=65: must be a whole number from 1 to 64"):
        pipe.long(["a person walks:2", "a person waves:2"], num_samples=65)


def test_unknown_model_and_edit_inputs_name_the_fix(pipe, tmp_path):
    with pytest.raises(UsageError, match="released model"):
        MotionPipeline.from_pretrained("no_such_model")
    with pytest.raises(UsageError, match="not found"):
        pipe.inbetween(tmp_path / "missing.bvh")
    with pytest.raises(UsageError, match="whole body"):
        pipe.edit_parts(CLIP, "a person waves", parts=list(range(22)))
