"""Compositional multi-action data: joins of real clips, joined captions, and the committed
data/bandai_mini_compositional (bookkeeping, continuity, captions, split purity, reproducibility, loading)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.data.compositional.dataset import MAX_SEAM_RATIO, MIN_PART_FRAMES, RULES, allocate, build_split
from motiondiff.data.compositional.join import Part, join_captions, join_parts, place_canonically, split_subject
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.formats.prepared import SPLITS, load_split
from motiondiff.data.representations.hml_features import mean_std
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.skeleton import SMPL22, SMPL22_BONE_LENGTHS
from motiondiff.text.parse import parse_caption, parse_captions

SRC = embedded_data_root()
ROOT = SRC.parent / "bandai_mini_compositional"
FPS = 20.0
T = 8  # 0.4 s, the committed transition


@pytest.fixture(scope="module")
def source():
    return {s: load_split(SRC, s) for s in SPLITS}


@pytest.fixture(scope="module")
def committed():
    return {s: load_split(ROOT, s) for s in SPLITS}


def clip(data, content: str, k: int = 0) -> Part:
    i = [i for i in range(data.num_clips) if data.label("content", i) == content][k]
    a, s = data.arrays, data.clip_slice(i)
    return Part(a["joints"][s], a["native_rotations"][s], a["native_root"][s])


def facing(joints: np.ndarray) -> np.ndarray:
    """Unsmoothed yaw per frame from hips and shoulders (independent of the join's smoothed heading)."""
    across = (joints[:, 2] - joints[:, 1]) + (joints[:, 17] - joints[:, 16])
    forward = np.cross([0.0, 1.0, 0.0], across)
    return np.unwrap(np.arctan2(forward[:, 0], forward[:, 2]))


def fastest(joints: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(joints, axis=0), axis=-1).max(-1) * FPS


def root_steps(joints: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(joints[:, 0, [0, 2]], axis=0), axis=-1)


def rigid_error(src: np.ndarray, dst: np.ndarray) -> float:
    """Largest joint distance after the best rotation about +Y and translation taking src onto dst."""
    p, q = src.reshape(-1, 3) - src.reshape(-1, 3).mean(0), dst.reshape(-1, 3) - dst.reshape(-1, 3).mean(0)
    yaw = np.arctan2((p[:, 2] * q[:, 0] - p[:, 0] * q[:, 2]).sum(), (p[:, 0] * q[:, 0] + p[:, 2] * q[:, 2]).sum())
    c, s = np.cos(yaw), np.sin(yaw)
    moved = p @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]).T
    return float(np.linalg.norm(moved - q, axis=-1).max())


def acceleration(joints: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(joints, 2, axis=0), axis=-1).max(-1)


def assert_seam_continuous(joined: np.ndarray, a: np.ndarray, b: np.ndarray, start: int, max_jerk: float) -> None:
    """Root path, facing, joint speeds and accelerations across the transition that starts at `start`, against both
    clips. A hard cut instead of the cross-fade gives 2.1-5.3x the clips' largest acceleration on the pairs below."""
    w = slice(start - 1, start + T + 1)
    # + 3 cm a frame: between two stances the body shifts over the planted feet (measured up to 2.5 cm a frame);
    # a misplaced clip jumps by decimetres
    assert root_steps(joined)[w].max() <= 1.25 * max(root_steps(a).max(), root_steps(b).max()) + 0.03
    turn = np.abs(np.diff(facing(joined)))[w].max()
    assert turn <= max(np.abs(np.diff(facing(a))).max(), np.abs(np.diff(facing(b))).max()) + np.radians(2)
    peak = fastest(joined)[w].max()
    assert peak <= MAX_SEAM_RATIO * max(np.median(fastest(a)), np.median(fastest(b)))
    assert peak <= 3.5 * max(fastest(a).max(), fastest(b).max())
    jerk = acceleration(joined)[start - 2 : start + T + 1].max()
    assert jerk <= max_jerk * max(acceleration(a).max(), acceleration(b).max())


# ---- the join itself, on real clips ---------------------------------------------------------------------------------
def test_each_clip_is_kept_rigidly_outside_transitions(source):
    parts = [clip(source["test"], c) for c in ("walk", "wave-both-hands", "bow")]
    joined = join_parts(parts, T)
    n = [len(p.joints) for p in parts]
    assert joined.frames == [(0, n[0]), (n[0] - T, n[0] + n[1] - T), (n[0] + n[1] - 2 * T, sum(n) - 2 * T)]
    assert len(joined.joints) == sum(n) - 2 * T
    np.testing.assert_allclose(joined.joints[: n[0] - T], parts[0].joints[: n[0] - T], atol=1e-5)  # not moved
    for k in (1, 2):
        s, e = joined.frames[k]
        keep = slice(T, n[k] - T if k < 2 else n[k])
        assert rigid_error(parts[k].joints[keep], joined.joints[s:e][keep]) < 1e-5
    # the second clip really was turned and moved: the walk ends elsewhere than it started, facing elsewhere
    assert rigid_error(parts[1].joints[T:-T], joined.joints[n[0] : n[0] + n[1] - 2 * T]) < 1e-5
    assert np.abs(joined.joints[n[0], 0] - parts[1].joints[T, 0]).max() > 0.5


@pytest.mark.parametrize(
    "contents",
    [("walk", "bow"), ("bow", "walk"), ("run", "wave-both-hands"), ("dash", "walk"),
     ("walk-back", "raise-up-right-hand"), ("walk-turn-left", "byebye"), ("raise-up-both-hands", "walk")],
)  # fmt: skip
def test_seams_are_continuous(source, contents):
    parts = [clip(source["train"], c) for c in contents]
    joined = join_parts(parts, T)
    assert_seam_continuous(joined.joints, parts[0].joints, parts[1].joints, joined.frames[1][0], max_jerk=2.0)
    # cross-fading bone directions keeps every bone at its length (lerped positions would shorten crossing limbs)
    parents = np.array(SMPL22.parents)
    bones = np.linalg.norm(joined.joints[:, 1:] - joined.joints[:, parents[1:]], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(SMPL22_BONE_LENGTHS[1:], bones.shape), atol=2e-4)


def test_native_rig_moves_with_the_joints(source):
    data = source["train"]
    parts = [clip(data, c) for c in ("walk-turn-right", "wave-left-hand", "run")]
    rig = data.rig()
    placed = place_canonically(join_parts(parts, T), rig.offsets, rig)
    translations = np.broadcast_to(rig.offsets, placed.rotations.shape[:-1] + (3,)).copy()
    translations[:, 0] = placed.root
    hips = forward_kinematics(placed.rotations, translations, rig.parents)[0][:, 0]
    assert placed.joints[..., 1].min() == pytest.approx(0.0, abs=1e-9)  # floor
    for k, part in enumerate(parts):
        s, e = placed.frames[k]
        keep = slice(T if k else 0, len(part.joints) - T if k < 2 else None)
        # the rig's hips keep their offset from the SMPL pelvis frame by frame, as in the source clip
        own = np.linalg.norm(part.root - part.joints[:, 0], axis=-1)[keep]
        np.testing.assert_allclose(np.linalg.norm(hips[s:e] - placed.joints[s:e, 0], axis=-1)[keep], own, atol=2e-3)


def test_allocate_shortens_the_longest_first():
    sizes = allocate([80, 80, 40], target=150, transition=T)
    assert sum(sizes) - 2 * T == 150 and sizes[2] == 40 and abs(sizes[0] - sizes[1]) <= 1
    assert allocate([40, 50], target=150, transition=T) == [40, 50]  # too short: whole clips
    assert min(allocate([80, 80, 80], target=60, transition=T)) == MIN_PART_FRAMES  # never below the minimum


# ---- captions --------------------------------------------------------------------------------------------------------
def test_joined_captions_and_their_action_nodes():
    parts = ["a person walks forward.", "someone waves both hands.", "a man bows."]
    text, spans = join_captions(parts)
    assert text == "a person walks forward, then waves both hands, and then bows."
    assert [text[s:e] for s, e in spans] == ["a person walks forward", "waves both hands", "bows"]
    assert join_captions(parts[:2])[0] == "a person walks forward, then waves both hands."
    assert split_subject("The person runs.") == ("The person", "runs")
    graph = parse_caption(text)
    assert len(graph.action_ids()) == 3 and graph.action_texts() == ["walks forward", "waves both hands", "bows"]


# ---- the committed dataset -----------------------------------------------------------------------------------------
def test_committed_files_license_and_meta(source):
    for name in ("train.npz", "val.npz", "test.npz", "Mean.npy", "Std.npy", "meta.json", "report.json", "LICENSE",
                 "README.md"):  # fmt: skip
        assert (ROOT / name).is_file(), name
    assert sum(p.stat().st_size for p in ROOT.iterdir()) <= 13 * 2**20
    assert (ROOT / "LICENSE").read_text() == (SRC / "LICENSE").read_text()
    readme = (ROOT / "README.md").read_text()
    assert "Bandai Namco Research Inc., CC BY-NC 4.0" in readme and "**generated**" in readme
    meta = json.loads((ROOT / "meta.json").read_text())
    assert meta["labels"] == source["train"].meta["labels"] and "generated" in meta["captions"]
    assert meta["compositional"]["command"] in readme


def test_committed_segments_are_the_source_windows(committed, source):
    for split in SPLITS:
        a, src = committed[split].arrays, source[split]
        t = int(a["transition_frames"])
        assert t == T and bool(a["captions_generated"]) is True
        ids = list(src.arrays["ids"])
        for i in range(committed[split].num_clips):
            seg = range(a["segment_offsets"][i], a["segment_offsets"][i + 1])
            frames, windows = a["segment_frames"][seg], a["segment_source_frames"][seg]
            assert 2 <= len(seg) <= 3 and frames[0, 0] == 0 and frames[-1, 1] == a["lengths"][i]
            assert (frames[1:, 0] == frames[:-1, 1] - t).all()  # neighbours overlap by the transition
            assert ((frames[:, 1] - frames[:, 0]) == (windows[:, 1] - windows[:, 0])).all()
            joints = a["joints"][committed[split].clip_slice(i)]
            for k, j in enumerate(seg):
                c = ids.index(str(a["segment_source_ids"][j]))
                assert a["segment_content"][j] == src.arrays["content"][c]
                assert 0 <= windows[k, 0] < windows[k, 1] <= src.arrays["lengths"][c]
                window = src.arrays["joints"][src.clip_slice(c)][windows[k, 0] : windows[k, 1]]
                keep = slice(t if k else 0, len(window) - t if k < len(seg) - 1 else None)
                own = joints[frames[k, 0] : frames[k, 1]]
                assert rigid_error(window[keep], own[keep]) < 1e-4, (split, i, k)


def test_committed_seams_are_continuous(committed, source):
    for split in SPLITS:
        a, src = committed[split].arrays, source[split]
        ids = list(src.arrays["ids"])
        for i in range(committed[split].num_clips):
            joints = a["joints"][committed[split].clip_slice(i)]
            seg = range(a["segment_offsets"][i], a["segment_offsets"][i + 1])
            windows = []
            for j in seg:
                c, (s, e) = ids.index(str(a["segment_source_ids"][j])), a["segment_source_frames"][j]
                windows.append(src.arrays["joints"][src.clip_slice(c)][s:e])
            for k in range(1, len(seg)):
                # max_jerk: 8 of the 251 committed seams exceed 2 (both hands up -> a wave), the largest 4.2
                start = int(a["segment_frames"][seg[k], 0])
                assert_seam_continuous(joints, windows[k - 1], windows[k], start, max_jerk=4.5)


def test_committed_split_purity(committed, source):
    owner = {str(x): s for s in SPLITS for x in source[s].arrays["ids"]}
    assert len(owner) == sum(source[s].num_clips for s in SPLITS)  # no clip id in two source splits
    for split in SPLITS:
        used = {owner[str(x)] for x in committed[split].arrays["segment_source_ids"]}
        assert used == {split}


def test_committed_captions_parse_to_an_action_per_clip(committed):
    for split in SPLITS:
        data, a = committed[split], committed[split].arrays
        firsts = [data.captions(i)[0] for i in range(data.num_clips)]
        for i, graph in enumerate(parse_captions(firsts)):
            seg = range(a["segment_offsets"][i], a["segment_offsets"][i + 1])
            # each clip's caption (its subject dropped after the first) appears in order in the joined one
            pieces = [split_subject(str(a["segment_captions"][j]))[1] for j in seg]
            starts, at = [], 0
            for piece in pieces:
                at = firsts[i].index(piece, at)
                starts.append(at)
            ends = starts[1:] + [len(firsts[i])]
            offsets = np.cumsum([0] + [len(w) + len(s) for w, s in zip(graph.words, graph.whitespace, strict=True)])
            heads = [offsets[graph.nodes[n].head] for n in graph.action_ids()]
            per_clip = [sum(s <= h < e for h in heads) for s, e in zip(starts, ends, strict=True)]
            assert min(per_clip) >= 1, (firsts[i], per_clip)
            if split == "test":  # GuidedMotion's complex-motion subset
                assert len(graph.action_ids()) >= 3 and 150 <= a["lengths"][i] <= 196
        assert all(r.meta["captions_generated"] for r in data.records())


def test_committed_statistics_cover_both_train_sets(committed, source):
    mean, std = mean_std(np.concatenate([source["train"].arrays["features"], committed["train"].arrays["features"]]))
    np.testing.assert_allclose(committed["train"].mean, mean, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(committed["train"].std, std, rtol=1e-5, atol=1e-6)


def test_build_is_deterministic_and_reproduces_the_committed_test_split(committed, source):
    def build(seed):
        return build_split(source["test"], 3, RULES["test"], T, 196, seed, SPLITS.index("test"))[0]

    first, again, other = build(0), build(0), build(1)
    stored = committed["test"]
    for k, seq in enumerate(first):
        np.testing.assert_array_equal(seq.joints, again[k].joints)
        assert seq.captions == again[k].captions == stored.captions(k)
        np.testing.assert_allclose(seq.joints, stored.arrays["joints"][stored.clip_slice(k)], atol=1e-5)
    assert [s.indices for s in other] != [s.indices for s in first]


def test_datamodule_and_config_load_the_committed_dataset(source):
    register_resolvers()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=["dataset=bandai_mini_compositional"])
    dm_cfg = cfg.dataset.datamodule
    assert dm_cfg.max_frames == 196 and [str(p) for p in dm_cfg.extra_train] == [str(SRC)]
    assert str(dm_cfg.root) == str(ROOT)
    dm = PreparedDataModule(ROOT, batch_size=8, max_frames=196, extra_train=[SRC], seed=0)
    dm.setup("fit")
    singles = int((source["train"].arrays["lengths"] - 1 >= dm.min_frames).sum())
    assert len(dm.dataset("train")) == 64 + singles and len(dm.dataset("val")) == 16
    batch = next(iter(dm.train_dataloader()))
    assert batch["motion"].shape[2] == dm.feature_dim == 263 and int(batch["length"].max()) <= 196
    test = dm.dataset("test")
    assert len(test) == 64 and min(r.length for r in test.records) >= 149  # features: one row fewer than frames
    assert all(", then " in test[i]["text"] for i in range(len(test)))
    assert len(PreparedDataModule(ROOT, max_frames=196).dataset("train")) == 64  # without extra_train
