"""The page's handlers without a browser (tests/e2e/test_demo.py drives the real page), on the shipped action model
with 2 DDIM steps: picking the action model swaps the prompt box for its action list and sets its length limit,
guidance and examples; every mode answers with its files (generate, edit of a chosen sample or an uploaded BVH,
in-between, timeline); a mistake is a status line with the fix, not an exception, and leaves no request folder."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gradio", reason="gradio is not installed: `pip install -e '.[demo]'`")

VIDEO = 128  # pixels: the smallest videos keep these tests quick
ON_PAGE, UPLOADED = "a sample on the page", "an uploaded file"


@pytest.fixture(scope="module")
def page_folder(tmp_path_factory):
    return tmp_path_factory.mktemp("page")


@pytest.fixture(scope="module")
def handlers(page_folder):
    from motiondiff.demo import DemoModels, build_demo

    demo = build_demo(DemoModels(blender=False), "action", seconds=1.0, steps=2, video_size=VIDEO,
                      output_dir=page_folder)  # fmt: skip
    return {f.name: f.fn for f in demo.fns.values()}


@pytest.fixture(scope="module")
def two_walks(handlers):
    """Two walks on the page (1 s, seed 0): what the edits start from."""
    status, coverage, last, zipped, bar, *slots = handlers["on_generate"]("action", "", "walk", 1.0, 2.0, 0, 2, 2,
                                                                          VIDEO, "")  # fmt: skip
    assert status.startswith("Generated 2 motion(s) of 'walk' with `action`") and len(last) == 2
    assert zipped["visible"] is True and zipped["value"].endswith(".zip") and bar["visible"] is False
    assert [slots[5 * i]["visible"] for i in range(4)] == [True, True, False, False]  # side by side: two columns
    return last, slots


def test_the_action_model_shows_its_actions_instead_of_the_prompt(handlers):
    text, action, weights, seconds, guidance, parts, examples, timelines, lines, note = handlers["on_model"]("action")
    assert text["visible"] is False and action["visible"] is True and weights["visible"] is False
    assert "walk" in action["choices"] and action["value"] == "bow"
    assert seconds["maximum"] == 6.0 and guidance["value"] == 2.0  # the action model's limit and default
    assert "upper_body" in parts["choices"] and parts["value"] == ["upper_body"]
    assert examples.visible is False  # the action list is the examples
    assert timelines.visible is True and lines["value"] == timelines.raw_samples[0][0]
    assert all(line.split(" : ")[0] in action["choices"] for line in lines["value"].splitlines())
    assert note["value"] == ""  # no prompt text to check against training captions


def test_an_unknown_action_is_a_status_line_with_the_fix(handlers):
    status, coverage, last, zipped, bar, column, *_ = handlers["on_generate"]("action", "", "fly", 1.0, 2.0, 0, 1, 2,
                                                                              VIDEO, "")  # fmt: skip
    assert status.startswith("**Please fix:** unknown action 'fly'") and "walk" in status
    assert column["visible"] is False and last is None and zipped["visible"] is False and coverage["visible"] is False


def test_the_edit_regenerates_the_chosen_parts_of_the_chosen_sample(handlers, two_walks):
    """parts= names the REGENERATED parts on the page too (as edit.py and MotionPipeline.edit_parts): the legs of
    sample 2 stay where they were, the arms move."""
    last, _ = two_walks
    status, _, edited, *_ = handlers["on_edit"]("action", last, ON_PAGE, 2, None, "", "wave-right-hand",
                                                ["upper_body"], 2.0, 1, 1, 2, VIDEO)  # fmt: skip
    assert status.startswith("Regenerated **upper_body** of sample 2 on the page from 'wave-right-hand'")
    legs = list(last.skeleton.parts["lower_body"])
    arms = [j for j in last.skeleton.parts["upper_body"] if j not in legs]
    assert np.abs(edited.joints[0][:, legs] - last.joints[1][:, legs]).max() < 1e-4
    assert np.abs(edited.joints[0][:, legs] - last.joints[0][:, legs]).max() > 1e-2  # not sample 1's legs
    assert np.abs(edited.joints[0][:, arms] - last.joints[1][:, arms]).max() > 1e-2
    for source, motion, fix in [(ON_PAGE, None, "generate a motion first"), (UPLOADED, None, "upload a motion first"),
                                (ON_PAGE, last, "sample must be a whole number in 1..2")]:  # fmt: skip
        status, _, same, *_ = handlers["on_edit"]("action", motion, source, 3, None, "", "walk", ["upper_body"], 2.0,
                                                  0, 1, 2, VIDEO)  # fmt: skip
        assert status.startswith(f"**Please fix:** {fix}") and same is None


def test_an_uploaded_bvh_is_edited_and_inbetweened(handlers, two_walks):
    last, slots = two_walks
    bvh = next(f for f in slots[4] if f.endswith(".bvh"))  # sample 1's BVH download, as a user uploads it
    status, *_ = handlers["on_edit"]("action", None, UPLOADED, 1, bvh, "", "bow", ["arms"], 2.0, 0, 1, 2, VIDEO)
    assert status.startswith(f"Regenerated **arms** of the upload {bvh.rsplit('/', 1)[1]}"), status
    status, _, between, *_ = handlers["on_inbetween"]("action", None, UPLOADED, 1, bvh, "", "bow", 25, 25, 2.0, 0, 1,
                                                      2, VIDEO)  # fmt: skip
    frames = len(between.joints[0])
    assert status.startswith(f"Kept the first {round(frames / 4)} and the last {round(frames / 4)} of {frames} frames "
                             "of the upload"), status  # fmt: skip


def test_the_inbetween_keeps_the_start_of_a_sample_on_the_page(handlers, two_walks):
    last, _ = two_walks
    status, _, between, *_ = handlers["on_inbetween"]("action", last, ON_PAGE, 1, None, "", "bow", 30, 20, 2.0, 0, 1,
                                                      2, VIDEO)  # fmt: skip
    assert status.startswith("Kept the first 6 and the last 4 of 20 frames of sample 1 on the page"), status
    assert np.abs(between.joints[0][:6] - last.joints[0][:6]).max() < 1e-4


def test_a_timeline_chains_its_prompts_and_draws_its_bar(handlers):
    status, _, out, zipped, bar, column, *_ = handlers["on_timeline"]("action", "walk : 1\nwave-right-hand", 0.5, 2.0,
                                                                      0, 1, 2, VIDEO)  # fmt: skip
    assert status.startswith("Made 1 motion(s) of 1.5 s through 2 timed prompts with `action`"), status
    assert len(out.joints[0]) == 30 and column["visible"] is True and zipped["visible"] is True
    assert bar["visible"] is True and bar["value"].count('class="segment"') == 2
    assert (
        ">walk <small>0.0-1.0 s</small>" in bar["value"] and ">wave-right-hand <small>1.0-1.5 s</small>" in bar["value"]
    )


@pytest.mark.parametrize("blender", [False, True])
def test_the_status_and_downloads_say_whether_fbx_and_glb_are_there(monkeypatch, tmp_path, blender):
    from motiondiff.demo import DemoModels, build_demo
    from motiondiff.demo import files as demo_files
    from motiondiff.export import blender as export_blender
    from motiondiff.export import outputs as export_outputs

    def fake_blender(bvh, out, fps, **_):  # stands in for Blender's importer and exporters
        out.write_bytes(b"glTF")
        return out

    command = (lambda: ["blender-python", "-c"]) if blender else (lambda: None)
    monkeypatch.setattr(demo_files, "blender_command", command)
    monkeypatch.setattr(export_blender, "blender_command", command)
    monkeypatch.setattr(export_outputs, "convert_bvh", fake_blender)
    demo = build_demo(DemoModels(), "action", seconds=1.0, steps=2, video_size=VIDEO, output_dir=tmp_path)
    on_generate = {f.name: f.fn for f in demo.fns.values()}["on_generate"]
    status, _, _, _, _, column, _, _, video, files, *_ = on_generate("action", "", "walk", 0.5, 2.0, 0, 1, 2, VIDEO, "")
    assert column["visible"] is True and video.endswith(".mp4")
    assert [f.rsplit(".", 1)[1] for f in files] == (["bvh", "fbx", "glb", "npz"] if blender else ["bvh", "npz"])
    assert status.endswith(demo_files.BLENDER_INCLUDED if blender else demo_files.BLENDER_MISSING)


def test_a_refused_request_leaves_no_request_folder(handlers, page_folder):
    before = sorted(p.name for p in page_folder.iterdir())
    status, *_ = handlers["on_generate"]("action", "", "fly", 1.0, 2.0, 0, 1, 2, VIDEO, "")
    assert status.startswith("**Please fix:**")
    status, *_ = handlers["on_timeline"]("action", "", 1.0, 2.0, 0, 1, 2, VIDEO)
    assert status.startswith("**Please fix:** the timeline is empty")
    assert sorted(p.name for p in page_folder.iterdir()) == before


def test_an_out_of_range_slider_value_names_its_field():
    import gradio as gr

    from motiondiff.demo.controls import named_slider

    slider = named_slider(0.5, 6.0, value=2.0, label="seconds")
    assert slider.preprocess(2.0) == 2.0
    with pytest.raises(gr.Error, match=r"Please fix seconds: Value 1000000000.0 is greater than maximum value 6.0"):
        slider.preprocess(1e9)
