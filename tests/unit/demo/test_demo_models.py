"""The demo's model list, an action model's input checks and what one generation writes (no browser:
tests/e2e/test_demo.py drives the page); one real generation uses the shipped action model."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from motiondiff.demo.inputs import Sampling
from motiondiff.demo.models import DemoModels, released_choices
from motiondiff.demo.modes.generate import generate
from motiondiff.demo.requests import run_request
from motiondiff.model_files.resolve import SHIPPED_MODELS
from motiondiff.runtime.errors import UsageError

VIDEO = 128  # pixels: the smallest videos keep these tests quick


def test_released_models_are_offered_and_a_users_guidedmotion_checkpoint_too(tmp_path):
    choices = released_choices()
    keys = [c.key for c in choices]
    assert keys[:3] == ["text", "action", "guidedmotion"] and "bandai_mini_text_cpu" in keys  # not the aliased stems
    assert not {path.stem for path in SHIPPED_MODELS.values()} & set(keys)
    assert [c.key for c in choices if c.guided] == ["guidedmotion"]
    assert "guided" not in [c.key for c in DemoModels().choices]
    with pytest.raises(UsageError, match="no GuidedMotion checkpoint"):
        DemoModels(guided=tmp_path / "missing.ckpt")
    ckpt = tmp_path / "last.ckpt"
    ckpt.write_bytes(b"")  # listed, not loaded: a model loads when the page first uses it
    models = DemoModels(guided=ckpt)
    assert models.choice("guided").guided and models.choice("guided").source == str(ckpt)
    with pytest.raises(UsageError, match="unknown model 'nope'"):
        models.choice("nope")


@pytest.fixture(scope="module")
def action_models():
    models = DemoModels(blender=False)
    assert models.info("action").kind == "action"
    return models


def test_the_action_model_offers_its_actions_as_examples(action_models):
    info = action_models.info("action")
    assert "walk" in info.actions and info.max_seconds == 6.0 and info.examples == info.actions
    assert not info.checks_coverage  # coverage is a text model's
    assert all(len(t.splitlines()) == 3 and set(line.split(" : ")[0] for line in t.splitlines()) <= set(info.actions)
               for t in info.timelines)  # fmt: skip


def test_a_request_writes_viewer_video_bvh_npz_and_a_zip(action_models, tmp_path):
    def make():
        return generate(action_models, "action", "walk", seconds=0.5, sampling=Sampling(seed=3, steps=2, num_samples=2))

    result = run_request(action_models, tmp_path, "run", make, video_size=VIDEO)
    out, samples = result.out, result.samples
    assert [s.index for s in samples] == [0, 1] and out.prompts == ["walk", "walk"] and result.coverage == []
    for s in samples:
        assert 'class="motion-data"' in s.html.read_text() and s.mp4.stat().st_size > 1000
        assert s.bvh.read_text().startswith("HIERARCHY") and s.fbx is None and s.glb is None
        npz = np.load(s.npz)
        np.testing.assert_array_equal(npz["joints"], out.joints[s.index])
        np.testing.assert_array_equal(npz["features"], out.features[s.index])
        assert float(npz["fps"]) == out.fps == 20.0 and npz["joints"].shape == (10, 22, 3)
        assert s.downloads() == [s.bvh, s.npz]
    names = zipfile.ZipFile(result.zip).namelist()
    assert {s.bvh.name for s in samples} | {s.npz.name for s in samples} | {s.mp4.name for s in samples} <= set(names)
    assert "results.json" in names and result.zip.parent.parent == tmp_path  # in the request's own folder
    assert action_models.get("action") is action_models.get("action")  # loaded once


@pytest.mark.parametrize(
    "prompt, seconds, message",
    [("", 2.0, "choose an action"), ("fly", 2.0, "fly"), ("walk", 60.0, "longer than this model's maximum")],
)
def test_action_model_bad_input_is_a_usage_error(action_models, prompt, seconds, message):
    with pytest.raises(UsageError, match=message):
        generate(action_models, "action", prompt, seconds=seconds, sampling=Sampling(steps=2))
