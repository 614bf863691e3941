"""The prepare command on the real Bandai zips (../shared; skipped with a reason where absent)."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from motiondiff.data.formats.archive import Source, SourceError
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.preparing.prepare import PrepareError, main, prepare_bandai
from motiondiff.data.representations.hml_features import features_from_canonical, joints_from_features
from motiondiff.data.sources import bandai


@pytest.fixture(scope="module")
def zips(shared):
    root = shared("data", "bandai-namco")
    return [root / "bandai-ds1.zip", root / "bandai-ds2.zip"]


def test_both_zips_list_every_clip(zips):
    counts = []
    for z in zips:
        clips, skipped = bandai.list_clips(Source(z))
        assert skipped == []
        counts.append(len(clips))
    assert counts == [174, 2613] and sum(counts) == 2787


@pytest.fixture(scope="module")
def subset(zips, tmp_path_factory):
    """Every content x style group of both zips, one clip each, at most 4 s: the embedded dataset's recipe."""
    out = tmp_path_factory.mktemp("prepared") / "mini"
    report = prepare_bandai(zips, out, per_group=1, max_frames=80, compact=True, workers=2, progress=False)
    return out, report


def test_subset_report(subset):
    out, report = subset
    assert report["skipped"] == []
    assert sum(report["clips"].values()) == 156 + 70  # content x style groups present in ds1 / ds2
    for kind in ("per_content", "per_style", "per_dataset"):
        assert sum(sum(v.values()) for v in report[kind].values()) == 226
    assert all(report["clips"][s] > 0 for s in ("train", "val", "test"))
    assert json.loads((out / "report.json").read_text())["clips"] == report["clips"]
    assert "CC BY-NC 4.0" in (out / "README.md").read_text() and (out / "LICENSE").is_file()
    assert "generated" in json.loads((out / "meta.json").read_text())["captions"]
    # an action with fewer than 3 clips is train-only: its one clip is the only example a model could learn from
    per_content = report["per_content"]  # {split: {content: clips}}
    total = {c: sum(per_content[s].get(c, 0) for s in per_content) for c in per_content["train"]}
    rare = {c for c, n in total.items() if n < 3}
    assert rare and not rare & (set(per_content["val"]) | set(per_content["test"]))


def test_subset_arrays(subset):
    out, _ = subset
    data = load_split(out, "train")
    a = data.arrays
    n = data.num_clips
    assert a["frame_offsets"][-1] == len(a["joints"]) == len(a["native_rotations"]) == len(a["native_root"])
    assert len(a["features"]) == len(a["joints"]) - n and a["features"].shape[1] == 263
    assert a["lengths"].max() <= 80 and a["native_offsets"].shape == (n, 21, 3)  # joint_Root folded into Hips
    assert bool(a["captions_generated"]) and a["caption_offsets"][-1] == len(a["captions"])
    for i in range(0, n, 17):
        joints = a["joints"][data.clip_slice(i)]
        feats = a["features"][data.feature_slice(i)]
        # Canonical placement: floor at 0, start at the origin; features decode back to the joints.
        assert abs(joints[..., 1].min()) < 1e-6 and np.abs(joints[0, 0, [0, 2]]).max() < 1e-6
        assert np.abs(joints_from_features(feats) - joints[:-1]).max() < 1e-4
        # The native skeleton gets the same placement: on the floor, at the origin, a real head height (the
        # 22 joints are retargeted to HumanML3D's taller skeleton, so heights differ), same travel direction.
        native = a["native_positions"][data.clip_slice(i)]
        head = list(a["native_joint_names"]).index("Head")
        assert abs(native[..., 1].min()) < 1e-5 and np.abs(native[0, 0, [0, 2]]).max() < 1e-5
        assert 1.2 < np.median(native[:, head, 1]) < 1.6 and 1.4 < np.median(joints[:, 15, 1]) < 1.8
        travel_native, travel_22 = native[-1, 0, [0, 2]], joints[-1, 0, [0, 2]]
        if np.linalg.norm(travel_22) > 0.5:
            cos = travel_native @ travel_22 / np.linalg.norm(travel_native) / np.linalg.norm(travel_22)
            assert cos > 0.98
        assert len(data.captions(i)) >= 2 + 12  # label, measured, and 12 in varied wording (caption_variants)
        assert len(set(data.captions(i))) == len(data.captions(i))
    assert data.mean.shape == data.std.shape == (263,) and (data.std > 0).all()


def test_compact_and_full_files_load_identically(zips, tmp_path, subset):
    out_compact, _ = subset
    full = prepare_bandai([zips[0]], tmp_path / "full", per_group=1, max_frames=80, workers=1, progress=False)
    assert full["skipped"] == []
    compact = prepare_bandai(
        [zips[0]], tmp_path / "compact", per_group=1, max_frames=80, compact=True, workers=1, progress=False
    )
    assert compact["clips"] == full["clips"]
    a = load_split(tmp_path / "full", "val").arrays
    b = load_split(tmp_path / "compact", "val").arrays
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    np.testing.assert_array_equal(
        a["features"][: a["lengths"][0] - 1], features_from_canonical(a["joints"][: a["lengths"][0]])
    )


# ---- bad input: one clear error, nothing written ----------------------------------------------------------------
def test_zip_without_labels(tmp_path, zips):
    bad = tmp_path / "nolabels.zip"
    with zipfile.ZipFile(zips[0]) as src, zipfile.ZipFile(bad, "w") as dst:
        for name in src.namelist()[:20]:
            if name.startswith("data/"):
                dst.writestr(name, src.read(name))
    out = tmp_path / "out"
    with pytest.raises(bandai.BandaiLayoutError, match=r"nolabels\.zip: no cfg/content_label\.txt"):
        prepare_bandai([bad], out, progress=False)
    assert not out.exists()


def test_output_is_a_file(tmp_path, zips):
    out = tmp_path / "taken"
    out.write_text("precious")
    with pytest.raises(PrepareError, match="is a file, not a folder"):
        prepare_bandai([zips[0]], out, progress=False)
    assert out.read_text() == "precious"


def test_unknown_caption_wording_is_refused_before_any_work(tmp_path, zips):
    out = tmp_path / "out"
    with pytest.raises(PrepareError, match=r"caption_wording='messy': choose plain or broad"):
        prepare_bandai([zips[0]], out, caption_wording="messy", progress=False)
    assert not out.exists()


def test_unreadable_zip_and_missing_source(tmp_path):
    broken = tmp_path / "broken.zip"
    broken.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(SourceError, match=r"broken\.zip: cannot read it as a zip"):
        prepare_bandai([broken], tmp_path / "out", progress=False)
    with pytest.raises(SourceError, match="no such file or folder"):
        prepare_bandai([tmp_path / "absent.zip"], tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


def test_refuses_to_overwrite_without_force(subset, zips):
    out, _ = subset
    before = (out / "train.npz").stat().st_mtime_ns
    with pytest.raises(PrepareError, match="--force"):
        prepare_bandai(zips, out, progress=False)
    assert (out / "train.npz").stat().st_mtime_ns == before


def test_truncated_and_bad_channel_clips_are_named_and_skipped(tmp_path, zips, capsys):
    """A release with a truncated BVH and one with an unknown channel: both named with their reason, rest kept."""
    src_dir = tmp_path / "release"
    with zipfile.ZipFile(zips[0]) as z:
        z.extractall(src_dir, [n for n in z.namelist() if "_bow_" in n or n.startswith("cfg/") or n == "LICENSE"])
    bvhs = sorted((src_dir / "data").glob("*.bvh"))
    text = bvhs[0].read_text()
    bvhs[0].write_text(text[: len(text) // 2])
    bvhs[1].write_text(bvhs[1].read_text().replace("Zrotation", "Zrotashun", 1))
    code = main(["bandai", "--src", str(src_dir), "--out", str(tmp_path / "out"), "--workers", "1", "--per-group", "9"])
    printed = capsys.readouterr().out
    assert code == 0
    assert f"{bvhs[0].stem}: " in printed and "truncated" in printed
    assert f"{bvhs[1].stem}: " in printed and "unknown channel 'Zrotashun'" in printed
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert len(report["skipped"]) == 2 and sum(report["clips"].values()) == len(bvhs) - 2
