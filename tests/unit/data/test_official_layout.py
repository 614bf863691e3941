"""Official HumanML3D / KIT-ML loaders on tiny roots built in that exact layout (HumanML3D from the real
reference sample 012314, KIT from random 251-wide features since no KIT sample is shared)."""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch

from motiondiff.data.official_datamodules import HumanML3DDataModule, KITDataModule
from motiondiff.data.sources.humanml3d import KIT, load_official_split, parse_caption_line, read_split_ids
from motiondiff.runtime.errors import DatasetNotFoundError

W1 = "a person walks forward and turns around.#a/DET person/NOUN walk/VERB forward/ADV and/CCONJ turn/VERB around/ADV"
W2 = "someone strolls ahead, then spins.#someone/PRON stroll/VERB ahead/ADV then/ADV spin/VERB"
HML_TEXTS = {
    "012314": [
        f"{W1}#0.0#0.0",
        f"{W2}#0.0#0.0",
        "a person steps forward.#a/DET person/NOUN step/VERB forward/ADV#1.5#6.0",  # [30:120]
        "a person turns.#a/DET person/NOUN turn/VERB#6.0#7.0",  # 20 frames < 40: dropped
        "the person walks.#the/DET person/NOUN walk/VERB#nan#nan",  # NaN/NaN = whole motion
        "a person starts walking.#a/DET person/NOUN start/VERB walk/VERB#nan#3.0",  # NaN start = 0: [0:60]
        "a person walks then stops.#a/DET person/NOUN walk/VERB then/ADV stop/VERB#1.52#6.07",  # [30:121]
        "a person keeps walking.#a/DET person/NOUN keep/VERB walk/VERB#5.0#12.0",  # past the end: [100:170]
    ],
    "000001": [
        f"{W1}#0.0#0.0",
        f"{W2}#0.0#0.0",
        "a person walks.#a/DET person/NOUN walk/VERB#0.5#2.5",  # [10:50], 40 frames: kept
        "a person walks.#a/DET person/NOUN walk/VERB#0.5#2.45",  # [10:49], 39 frames: dropped
    ],
    "000002": [f"{W1}#0.0#0.0"],
    "000003": [f"{W1}#0.0#0.0"],
    "000004": [f"{W2}#0.0#0.0"],
    # only a span (0.0 start but nonzero end is a span): a segment record and no whole-clip record
    "000005": ["a person starts walking.#a/DET person/NOUN start/VERB walk/VERB#0.0#3.0"],
}
TRAIN_IDS = ["012314", "000001", "000002", "000003", "000004", "000005", "000006", "009999"]


def _write_texts(root: Path, texts: dict[str, list[str]]) -> None:
    (root / "texts").mkdir(parents=True, exist_ok=True)
    for clip_id, lines in texts.items():
        (root / "texts" / f"{clip_id}.txt").write_text("\n".join(lines) + "\n")


def _write_splits(root: Path, splits: dict[str, list[str]]) -> None:
    for split, ids in splits.items():
        (root / f"{split}.txt").write_text("\n".join(ids) + "\n")


def build_hml_root(root: Path, ref: Path) -> dict[str, np.ndarray]:
    """HumanML3D layout from the real sample; returns the features written per id."""
    for sub in ("new_joint_vecs", "new_joints"):
        (root / sub).mkdir(parents=True)
        shutil.copy(ref / sub / "012314.npy", root / sub / "012314.npy")
    for name in ("Mean.npy", "Std.npy"):
        shutil.copy(ref / name, root / name)
    s = np.load(ref / "new_joint_vecs" / "012314.npy")
    clips = {
        "012314": s,
        "000001": s[:120],
        "000002": s[:30],  # too short
        "000003": np.concatenate([s, s[:30]]),  # 200 frames: dropped
        "000004": np.concatenate([s, s[:29]]),  # 199 frames: kept
        "000005": s[50:150] + 0.1,
        "000006": s[:60],  # no texts file
    }
    for clip_id, m in clips.items():
        np.save(root / "new_joint_vecs" / f"{clip_id}.npy", m)
    _write_texts(root, HML_TEXTS)
    _write_splits(root, {"train": TRAIN_IDS, "val": ["000004", "000001"], "test": ["012314"]})
    return clips


@pytest.fixture
def ref(shared) -> Path:
    return shared("reference", "humanml3d")


@pytest.fixture
def hml(tmp_path, ref) -> tuple[Path, dict[str, np.ndarray]]:
    root = tmp_path / "HumanML3D"
    return root, build_hml_root(root, ref)


def test_segments_are_cut_as_official(hml):
    root, clips = hml
    records, _, _ = load_official_split(root, "train")
    by_id = {r.id: r for r in records}
    s = clips["012314"]
    expected = {  # id -> (source clip, frames)
        "012314": ("012314", 0, 170),
        "012314#1.5-6#2": ("012314", 30, 120),
        "012314#0-3#5": ("012314", 0, 60),
        "012314#1.52-6.07#6": ("012314", 30, 121),
        "012314#5-12#7": ("012314", 100, 170),
        "000001": ("000001", 0, 120),
        "000001#0.5-2.5#2": ("000001", 10, 50),
        "000004": ("000004", 0, 199),
        "000005#0-3#0": ("000005", 0, 60),
    }
    assert [r.id for r in records] == list(expected)
    for rid, (clip, f0, f1) in expected.items():
        rec = by_id[rid]
        np.testing.assert_array_equal(rec.motion, clips[clip][f0:f1])
        assert rec.length == f1 - f0 and rec.meta["frames"] == (f0, f1) and rec.meta["clip_id"] == clip
    whole = by_id["012314"]
    assert whole.texts == ["a person walks forward and turns around.", "someone strolls ahead, then spins.",
                           "the person walks."]  # fmt: skip
    assert whole.meta["tokens"][0] == ["a/DET", "person/NOUN", "walk/VERB", "forward/ADV", "and/CCONJ",
                                       "turn/VERB", "around/ADV"]  # fmt: skip
    assert len(whole.meta["tokens"]) == len(whole.texts)
    assert whole.meta["joints_path"] == str(root / "new_joints" / "012314.npy")
    assert "joints_path" not in by_id["000001"].meta
    span = by_id["012314#1.5-6#2"]
    assert span.texts == ["a person steps forward."] and span.meta["seconds"] == (1.5, 6.0)
    assert span.meta["tokens"] == [["a/DET", "person/NOUN", "step/VERB", "forward/ADV"]]
    assert all(r.action == -1 for r in records)
    np.testing.assert_array_equal(by_id["012314#1.5-6#2"].motion, s[30:120])


def test_skips_are_counted_and_logged(hml, caplog):
    root, _ = hml
    with caplog.at_level(logging.WARNING, logger="motiondiff.data.sources.humanml3d"):
        records, _, _ = load_official_split(root, "train")
    ids = {r.meta["clip_id"] for r in records}
    # 000002 too short, 000003 has 200 frames, 000006 has no texts, 009999 no features
    assert ids == {"012314", "000001", "000004", "000005"}
    msgs = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert any("1 of 8" in m and "new_joint_vecs" in m and "009999" in m for m in msgs), msgs
    assert any("1 of 8" in m and "texts" in m and "000006" in m for m in msgs), msgs


def test_mean_std_and_official_split_order(hml, ref):
    root, _ = hml
    records, mean, std = load_official_split(root, "val")
    assert [r.id for r in records] == ["000004", "000001", "000001#0.5-2.5#2"]
    np.testing.assert_array_equal(mean, np.load(ref / "Mean.npy"))
    np.testing.assert_array_equal(std, np.load(ref / "Std.npy"))
    assert mean.dtype == np.float32 and mean.shape == (263,)


def test_datamodule_batches(hml):
    root, clips = hml
    dm = HumanML3DDataModule(root, batch_size=4, seed=1)
    assert (dm.feature_dim, dm.num_joints, dm.fps) == (263, 22, 20.0)
    with pytest.raises(RuntimeError, match="setup"):
        _ = dm.mean
    dm.setup("fit")
    seen = []
    for batch in dm.train_dataloader():
        b, n, d = batch["motion"].shape
        assert d == 263 and batch["motion"].dtype == torch.float32 and b <= 4
        assert batch["mask"].dtype == torch.bool and batch["mask"].shape == (b, n)
        assert torch.equal(batch["mask"].sum(1), batch["length"]) and int(batch["length"].max()) == n
        assert all(int(x) % 4 == 0 and int(x) <= 196 for x in batch["length"])
        assert torch.equal(batch["action"], torch.full((b,), -1, dtype=torch.long))
        assert all(isinstance(t, str) and t for t in batch["text"])
        seen += batch["id"]
    assert sorted(seen) == sorted(r.id for r in dm.datasets["train"].records)  # drop_last=False

    batch = next(iter(dm.val_dataloader()))  # val: first window, first caption, fixed order
    assert batch["id"] == ["000004", "000001", "000001#0.5-2.5#2"]
    assert batch["length"].tolist() == [196, 120, 40]
    assert batch["text"][0] == "someone strolls ahead, then spins."
    want = (clips["000004"][:196] - dm.mean) / dm.std
    np.testing.assert_allclose(batch["motion"][0].numpy(), want, rtol=1e-5, atol=1e-5)
    want = (clips["000001"][10:50] - dm.mean) / dm.std
    np.testing.assert_allclose(batch["motion"][2, :40].numpy(), want, rtol=1e-5, atol=1e-5)
    assert not batch["motion"][2, 40:].any() and not batch["mask"][2, 40:].any()
    assert dm.train_dataloader().persistent_workers is False  # only with worker processes
    workers = HumanML3DDataModule(root, batch_size=4, num_workers=2)
    workers.setup("validate")
    assert workers.val_dataloader().persistent_workers is True and "train" not in workers.datasets


def _build_kit_root(root: Path, rng: np.random.Generator) -> dict[str, np.ndarray]:
    (root / "new_joint_vecs").mkdir(parents=True)
    clips = {"00001": 100, "00002": 30, "00003": 20}
    clips = {k: rng.normal(size=(n, 251)).astype(np.float32) for k, n in clips.items()}
    for clip_id, m in clips.items():
        np.save(root / "new_joint_vecs" / f"{clip_id}.npy", m)
    np.save(root / "Mean.npy", rng.normal(size=251).astype(np.float32))
    np.save(root / "Std.npy", rng.uniform(0.5, 2.0, size=251).astype(np.float32))
    cap = "a man walks forward.#a/DET man/NOUN walk/VERB forward/ADV"
    _write_texts(root, {"00001": [f"{cap}#0.0#0.0", f"{cap}#1.5#3.0"], "00002": [f"{cap}#0.0#0.0"],
                        "00003": [f"{cap}#0.0#0.0"]})  # fmt: skip
    _write_splits(root, {"train": list(clips), "val": ["00002"], "test": ["00001"]})
    return clips


def test_kit_layout_and_x20_quirk(tmp_path):
    root = tmp_path / "KIT-ML"
    clips = _build_kit_root(root, np.random.default_rng(0))
    records, mean, std = load_official_split(root, "train", dataset="kit")
    by_id = {r.id: r for r in records}
    assert list(by_id) == ["00001", "00001#1.5-3#1", "00002"]  # 30 frames kept (min 24), 20 dropped
    # x20 even at 12.5 fps: 1.5-3.0 s -> frames 30:60 (x12.5 would give 18:37, 19 frames, dropped)
    np.testing.assert_array_equal(by_id["00001#1.5-3#1"].motion, clips["00001"][30:60])
    assert KIT.seconds_to_frames == 20.0 and KIT.fps == 12.5
    assert mean.shape == std.shape == (251,)

    dm = KITDataModule(root, batch_size=8)
    dm.setup("fit")
    assert (dm.feature_dim, dm.num_joints, dm.fps) == (251, 21, 12.5)
    batch = next(iter(dm.train_dataloader()))
    assert batch["motion"].shape[0] == 3 and batch["motion"].shape[2] == 251
    # a KIT root read as HumanML3D: the statistics' width gives it away, with a hint
    with pytest.raises(ValueError, match=r"Mean\.npy.*\(263,\).*dataset='kit'"):
        load_official_split(root, "train")


def _message(excinfo) -> str:
    return str(excinfo.value)


def test_missing_root(tmp_path):
    with pytest.raises(DatasetNotFoundError) as ei:
        load_official_split(tmp_path / "nope", "train")
    msg = _message(ei)
    assert isinstance(ei.value, FileNotFoundError) and str(tmp_path / "nope") in msg
    assert "new_joint_vecs/<id>.npy" in msg and "texts/<id>.txt" in msg and "Mean.npy" in msg
    assert "github.com/EricGuo5513/HumanML3D" in msg
    with pytest.raises(DatasetNotFoundError, match="KIT-ML.*(?s:.*)github.com/EricGuo5513/HumanML3D"):
        load_official_split(tmp_path / "nope", "train", dataset="kit")


@pytest.mark.parametrize("missing", ["Mean.npy", "Std.npy", "texts", "new_joint_vecs", "train.txt"])
def test_missing_required_path(hml, missing):
    root, _ = hml
    path = root / missing
    shutil.rmtree(path) if path.is_dir() else path.unlink()
    with pytest.raises(DatasetNotFoundError) as ei:
        load_official_split(root, "train")
    assert ei.value.path == path and str(path) in _message(ei) and "Expected layout" in _message(ei)


def test_no_feature_file_at_all(hml):
    root, _ = hml
    _write_splits(root, {"train": ["777777", "888888"]})
    with pytest.raises(DatasetNotFoundError, match="none of the 2 ids"):
        load_official_split(root, "train")


def test_wrong_feature_width(hml):
    root, _ = hml
    bad = root / "new_joint_vecs" / "000001.npy"
    np.save(bad, np.zeros((120, 251), np.float32))
    with pytest.raises(ValueError) as ei:
        load_official_split(root, "train")
    assert str(bad) in _message(ei) and "(N, 263)" in _message(ei) and "dataset='kit'" in _message(ei)


def test_wrong_stats_width(hml):
    root, _ = hml
    np.save(root / "Std.npy", np.ones(262, np.float32))
    with pytest.raises(ValueError, match=r"Std\.npy.*\(262,\).*\(263,\)"):
        load_official_split(root, "train")


def test_bad_inputs():
    with pytest.raises(ValueError, match="unknown official dataset"):
        load_official_split(".", "train", dataset="amass")
    with pytest.raises(ValueError, match="malformed caption line"):
        parse_caption_line("a caption without times#a/DET")
    cap = parse_caption_line("x#a/DET#nan#2.0\n")
    assert (cap.start, cap.end, cap.whole_motion, cap.frames(KIT)) == (0.0, 2.0, False, (0, 40))


def test_official_split_files_parse(ref):
    ids = {s: read_split_ids(ref / f"{s}.txt") for s in ("train", "val", "test")}
    assert {s: len(v) for s, v in ids.items()} == {"train": 23384, "val": 1460, "test": 4384}
    assert all(len(set(v)) == len(v) for v in ids.values())
    assert not (set(ids["train"]) & set(ids["val"]) or set(ids["train"]) & set(ids["test"]))
    assert not set(ids["val"]) & set(ids["test"])
    for v in ids.values():  # every clip comes with its mirrored copy "M<id>" in the same split
        assert sum(i.startswith("M") for i in v) * 2 == len(v)
    assert "012314" in ids["train"]


def test_official_layouts_refuse_representations_they_cannot_encode(tmp_path):
    """The official layouts ship features only: a rotation representation is one clear error naming the fix."""
    with pytest.raises(ValueError, match=r"representation=rp6jr.*stores hml263.*representation=hml263.*humanact12"):
        HumanML3DDataModule(tmp_path, representation="rp6jr")
    with pytest.raises(ValueError, match=r"stores kit251"):
        KITDataModule(tmp_path, representation="hml263")
    assert KITDataModule(tmp_path, representation="kit251").feature_dim == 251
