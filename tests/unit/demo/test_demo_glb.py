"""The demo's FBX/GLB downloads follow the install: with Blender (the check of export=fbx,glb, monkeypatched here both
ways, and a stand-in for Blender's converter) each motion offers the FBX and GLB made from its BVH, in the zip too, and
the page says they are included; without it the page says what they need and offers BVH and NPZ; a Blender failure
keeps the other files, leaves no half-written FBX/GLB, and says so."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from motiondiff.demo import files as demo_files
from motiondiff.demo.files import (
    BLENDER_INCLUDED,
    BLENDER_MISSING,
    BLENDER_OFF,
    Sample,
    blender_note,
    download_kinds,
    write_samples,
    zip_folder,
)
from motiondiff.demo.inputs import Sampling
from motiondiff.demo.models import DemoModels
from motiondiff.demo.modes.generate import generate
from motiondiff.export import blender as export_blender
from motiondiff.export import outputs as export_outputs

BLENDER = ["/opt/blender/python", "-c"]


def _blender(monkeypatch, command) -> None:
    """Blender there (``command``) or not, for the demo's check and for export=fbx,glb's."""
    monkeypatch.setattr(demo_files, "blender_command", lambda: command)
    monkeypatch.setattr(export_blender, "blender_command", lambda: command)


@pytest.mark.parametrize("command, available", [(None, False), (BLENDER, True)])
def test_what_the_page_says_follows_blender(monkeypatch, command, available):
    _blender(monkeypatch, command)
    models = DemoModels()
    assert models.glb is available
    note = blender_note(models.glb)
    if available:
        assert note == BLENDER_INCLUDED and "BVH, FBX, GLB and NPZ are offered" in note
        assert download_kinds(models.glb) == "BVH, FBX, GLB, NPZ"
        assert DemoModels(blender=False).glb is False and blender_note(False) == BLENDER_OFF  # turned off on purpose
    else:
        assert note == BLENDER_MISSING and "need Blender's bpy" in note and "BVH and NPZ are offered" in note
        assert "MOTIONDIFF_BLENDER_PYTHON" in note and "docs/usage.md" in note
        assert download_kinds(models.glb) == "BVH, NPZ" and DemoModels(blender=True).glb is False
    failed = blender_note(True, "Blender could not write x.glb")
    assert "could not write them this time (Blender could not write x.glb)" in failed and "GLB and NPZ" not in failed


def test_downloads_list_fbx_and_glb_only_when_there_are_some():
    paths = {k: Path(f"m.{k}") for k in ("html", "mp4", "bvh", "npz", "fbx", "glb")}
    without = Sample(0, "t", paths["html"], paths["mp4"], paths["bvh"], paths["npz"])
    assert without.downloads() == [paths["bvh"], paths["npz"]]
    both = Sample(0, "t", paths["html"], paths["mp4"], paths["bvh"], paths["npz"], paths["fbx"], paths["glb"])
    assert both.downloads() == [paths["bvh"], paths["fbx"], paths["glb"], paths["npz"]]


@pytest.fixture(scope="module")
def walks():
    return generate(DemoModels(blender=False), "action", "walk", seconds=0.5, sampling=Sampling(steps=2, num_samples=2))


def test_each_motion_gets_an_fbx_and_a_glb_from_its_bvh_when_blender_is_there(monkeypatch, walks, tmp_path):
    calls = []

    def fake_blender(bvh, out, fps, **_):  # stands in for Blender's importer and FBX/glTF exporters
        calls.append((Path(bvh), Path(out), fps))
        Path(out).write_bytes(b"glTF" if str(out).endswith(".glb") else b"Kaydara FBX Binary")
        return Path(out)

    _blender(monkeypatch, BLENDER)
    monkeypatch.setattr(export_outputs, "convert_bvh", fake_blender)
    samples, error = write_samples(walks, tmp_path / "motions", blender=True, video_size=128)
    assert error is None and len(calls) == 4 and {c[2] for c in calls} == {20.0}
    for s in samples:
        assert [c[1] for c in calls if c[0] == s.bvh] == [s.bvh.with_suffix(".fbx"), s.bvh.with_suffix(".glb")]
        assert s.glb.read_bytes() == b"glTF" and s.fbx.read_bytes().startswith(b"Kaydara")
        assert s.downloads() == [s.bvh, s.fbx, s.glb, s.npz]
    names = zipfile.ZipFile(zip_folder(tmp_path / "motions", tmp_path / "all.zip")).namelist()
    assert {p.name for s in samples for p in s.downloads()} <= set(names)


def test_a_blender_failure_keeps_the_other_files(monkeypatch, walks, tmp_path):
    def broken_blender(bvh, out, fps, **_):
        Path(out).with_name(f".{Path(out).stem}.partial.glb").write_bytes(b"half")  # as a crash could leave
        raise RuntimeError(f"Blender could not write {Path(out).name} from {Path(bvh).name}: no GPU context")

    _blender(monkeypatch, BLENDER)
    monkeypatch.setattr(export_outputs, "convert_bvh", broken_blender)
    samples, error = write_samples(walks, tmp_path / "motions", blender=True, video_size=128)
    assert "no GPU context" in error and "could not write them this time" in blender_note(True, error)
    for s in samples:
        assert s.fbx is None and s.glb is None and s.bvh.is_file() and s.npz.is_file() and s.mp4.is_file()
    assert not [p for p in (tmp_path / "motions").iterdir() if "partial" in p.name or p.suffix in (".fbx", ".glb")]
