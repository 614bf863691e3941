"""The demo's GLB downloads follow the install: with Blender (the check of export=glb, monkeypatched here both ways,
and a stand-in for Blender's converter) each sample offers the GLB made from its BVH and the page says GLB is
included; without it the page says what GLB needs and offers BVH and NPZ; a Blender failure keeps the other files
and says so."""

from __future__ import annotations

from pathlib import Path

import pytest

from motiondiff.demo import models as demo_models
from motiondiff.demo.models import GLB_INCLUDED, GLB_MISSING, DemoModels, Sample, download_kinds, generate, glb_note


@pytest.mark.parametrize("command, available", [(None, False), (["/opt/blender/python", "-c"], True)])
def test_what_the_page_says_follows_blender(monkeypatch, command, available):
    monkeypatch.setattr(demo_models, "blender_command", lambda: command)
    models = DemoModels()
    assert models.glb is available
    note = glb_note(models.glb)
    if available:
        assert note == GLB_INCLUDED and "BVH, GLB and NPZ are offered" in note
        assert download_kinds(models.glb) == "BVH, GLB, NPZ"
    else:
        assert note == GLB_MISSING and "needs Blender's bpy" in note and "BVH and NPZ are offered" in note
        assert "pip install 'motiondiff[blender]'" in note and "MOTIONDIFF_BLENDER_PYTHON" in note
        assert download_kinds(models.glb) == "BVH, NPZ"
    failed = glb_note(True, "Blender could not write x.glb")
    assert "could not write it this time (Blender could not write x.glb)" in failed and "GLB, " not in failed


def test_downloads_list_the_glb_only_when_there_is_one():
    paths = {k: Path(f"m.{k}") for k in ("html", "mp4", "bvh", "npz", "glb")}
    without = Sample(0, "t", paths["html"], paths["mp4"], paths["bvh"], paths["npz"])
    assert without.downloads() == [paths["bvh"], paths["npz"]]
    with_glb = Sample(0, "t", paths["html"], paths["mp4"], paths["bvh"], paths["npz"], paths["glb"])
    assert with_glb.downloads() == [paths["bvh"], paths["glb"], paths["npz"]]


@pytest.fixture(scope="module")
def action_models():
    return DemoModels()


def test_generate_writes_a_glb_from_each_bvh_when_blender_is_there(monkeypatch, action_models, tmp_path):
    calls = []

    def fake_blender(bvh, out, fps):  # stands in for Blender's importer and glTF exporter
        calls.append((Path(bvh), Path(out), fps))
        Path(out).write_bytes(b"glTF")
        return Path(out)

    monkeypatch.setattr(demo_models, "convert_bvh", fake_blender)
    monkeypatch.setattr(action_models, "glb", False)
    _, samples = generate(action_models, "action", "walk", tmp_path / "none", seconds=0.5, steps=2)
    assert samples[0].glb is None and not calls and samples[0].downloads() == [samples[0].bvh, samples[0].npz]

    monkeypatch.setattr(action_models, "glb", True)
    _, samples = generate(action_models, "action", "walk", tmp_path / "glb", seconds=0.5, num_samples=2, steps=2)
    assert [c[:2] for c in calls] == [(s.bvh, s.bvh.with_suffix(".glb")) for s in samples] and calls[0][2] == 20.0
    for s in samples:
        assert s.glb.read_bytes() == b"glTF" and s.downloads() == [s.bvh, s.glb, s.npz] and s.glb_error is None


def test_a_blender_failure_keeps_the_other_files(monkeypatch, action_models, tmp_path):
    def broken_blender(bvh, out, fps):
        raise RuntimeError(f"Blender could not write {Path(out).name} from {Path(bvh).name}: no GPU context")

    monkeypatch.setattr(demo_models, "convert_bvh", broken_blender)
    monkeypatch.setattr(action_models, "glb", True)
    _, samples = generate(action_models, "action", "walk", tmp_path, seconds=0.5, steps=2)
    s = samples[0]
    assert s.glb is None and "no GPU context" in s.glb_error and s.bvh.is_file() and s.npz.is_file()
    assert "could not write it this time" in glb_note(action_models.glb, s.glb_error)
