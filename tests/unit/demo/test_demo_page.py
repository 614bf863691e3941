"""The page's handlers without a browser (tests/e2e/test_demo.py drives the real page): picking the action model
swaps the prompt box for its action list and sets its length limit and guidance; an unknown action is a status line
with the fix, not an exception."""

from __future__ import annotations

import pytest

pytest.importorskip("gradio", reason="gradio is not installed: `pip install -e '.[demo]'`")


@pytest.fixture(scope="module")
def page_folder(tmp_path_factory):
    return tmp_path_factory.mktemp("page")


@pytest.fixture(scope="module")
def handlers(page_folder):
    from motiondiff.demo import DemoModels, build_demo

    demo = build_demo(DemoModels(), "action", seconds=1.0, steps=2, output_dir=page_folder)
    return {f.name: f.fn for f in demo.fns.values()}


def test_the_action_model_shows_its_actions_instead_of_the_prompt(handlers):
    text, action, weights, seconds, guidance, parts = handlers["on_model"]("action")
    assert text["visible"] is False and action["visible"] is True and weights["visible"] is False
    assert "walk" in action["choices"] and action["value"] == "bow"
    assert seconds["maximum"] == 6.0 and guidance["value"] == 2.0  # the action model's limit and default
    assert "upper_body" in parts["choices"] and parts["value"] == ["upper_body"]


def test_an_unknown_action_is_a_status_line_with_the_fix(handlers):
    status, last, column, *_ = handlers["on_generate"](
        "action", "", "fly", 1.0, 2.0, 0, 1, 2, "", progress=lambda *a, **k: None
    )
    assert status.startswith("**Please fix:** unknown action 'fly'") and "walk" in status
    assert column["visible"] is False and last is None


@pytest.mark.parametrize("blender", [False, True])
def test_the_status_and_downloads_say_whether_glb_is_there(monkeypatch, tmp_path, blender):
    from motiondiff.demo import DemoModels, build_demo
    from motiondiff.demo import models as demo_models

    def fake_blender(bvh, out, fps):  # stands in for Blender's importer and glTF exporter
        out.write_bytes(b"glTF")
        return out

    monkeypatch.setattr(demo_models, "blender_command", lambda: ["blender-python", "-c"] if blender else None)
    monkeypatch.setattr(demo_models, "convert_bvh", fake_blender)
    demo = build_demo(DemoModels(), "action", seconds=1.0, steps=2, output_dir=tmp_path)
    on_generate = {f.name: f.fn for f in demo.fns.values()}["on_generate"]
    status, _, column, _, _, video, files, *_ = on_generate("action", "", "walk", 0.5, 2.0, 0, 1, 2, "",
                                                        progress=lambda *a, **k: None)  # fmt: skip
    assert column["visible"] is True and video.endswith(".mp4")
    assert [f.rsplit(".", 1)[1] for f in files] == (["bvh", "glb", "npz"] if blender else ["bvh", "npz"])
    assert status.endswith(demo_models.GLB_INCLUDED if blender else demo_models.GLB_MISSING)


def test_the_edit_regenerates_the_chosen_parts_and_keeps_the_rest(handlers):
    """parts= names the REGENERATED parts on the page too (as edit.py and MotionPipeline.edit_parts): the legs of
    sample 1 stay where they were, the arms move."""
    import numpy as np

    status, last, *_ = handlers["on_generate"]("action", "", "walk", 1.0, 2.0, 0, 1, 2, "",
                                               progress=lambda *a, **k: None)  # fmt: skip
    status, edited, column, *_ = handlers["on_edit"]("action", last, "", "wave-right-hand", ["upper_body"], 2.0, 1, 2)
    assert status.startswith("Regenerated **upper_body** of sample 1") and column["visible"] is True
    legs = list(last.skeleton.parts["lower_body"])
    arms = [j for j in last.skeleton.parts["upper_body"] if j not in legs]
    before, after = last.joints[0], edited.joints[0]
    assert np.abs(after[:, legs] - before[:, legs]).max() < 1e-4
    assert np.abs(after[:, arms] - before[:, arms]).max() > 1e-2
    status, same, *_ = handlers["on_edit"]("action", None, "", "walk", ["upper_body"], 2.0, 0, 2)
    assert status.startswith("**Please fix:** generate a motion first") and same is None


def test_a_refused_request_leaves_no_request_folder(handlers, page_folder):
    before = sorted(p.name for p in page_folder.iterdir())
    status, *_ = handlers["on_generate"]("action", "", "fly", 1.0, 2.0, 0, 1, 2, "", progress=lambda *a, **k: None)
    assert status.startswith("**Please fix:**")
    assert sorted(p.name for p in page_folder.iterdir()) == before


def test_an_out_of_range_slider_value_names_its_field():
    import gradio as gr

    from motiondiff.demo.app import named_slider

    slider = named_slider(0.5, 6.0, value=2.0, label="seconds")
    assert slider.preprocess(2.0) == 2.0
    with pytest.raises(gr.Error, match=r"Please fix seconds: Value 1000000000.0 is greater than maximum value 6.0"):
        slider.preprocess(1e9)
