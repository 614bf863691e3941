"""Simultaneous-action data (data.simultaneous): a clip paired with itself is the prepared clip, a pair keeps the
locomotion clip's legs and path and the gesture's arms, captions are generated and joined, builds are reproducible."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.joint_map import JointMap
from motiondiff.data.prepared import load_split
from motiondiff.data.simultaneous import build, build_split, candidates, compose_pair, join_simultaneous, pairs_of
from motiondiff.skeleton import SMPL22


@pytest.fixture(scope="module")
def train():
    return load_split(embedded_data_root(), "train")


@pytest.fixture(scope="module")
def joint_map():
    return JointMap.load("bandai_to_smpl22")


def test_a_clip_paired_with_itself_is_its_prepared_clip(train, joint_map):
    lower, upper = candidates(train)
    for i in (lower[0], upper[0]):
        pair = compose_pair(train, joint_map, i, i)
        np.testing.assert_allclose(pair.joints, train.arrays["joints"][train.clip_slice(i)], atol=1e-5)


def test_candidates_are_locomotion_and_arm_gestures(train):
    lower, upper = candidates(train)
    assert {train.label("content", i).split("-")[0] for i in lower} <= {"walk", "run", "dash"}
    assert all(not train.label("content", i).startswith(("walk", "run", "dash", "bow", "punch")) for i in upper)
    assert len(lower) > 100 and len(upper) > 100


def test_pairs_keep_the_whole_gesture(train):
    pairs = pairs_of(train)
    n = train.arrays["lengths"]
    assert len(pairs) > 1000 and all(n[lo] >= n[up] for lo, up in pairs)


def test_a_pair_has_the_walks_legs_and_path_and_the_gestures_raised_arms(train, joint_map):
    lower, upper = candidates(train)
    walk = next(i for i in lower if train.label("content", i) == "walk")
    hands = next(i for i in upper if train.label("content", i) == "raise-up-both-hands")
    pair = compose_pair(train, joint_map, walk, hands)
    s, e = pair.lower_window
    ref = train.arrays["joints"][train.clip_slice(walk)][s:e]
    legs = list(SMPL22.parts["legs"])
    rel, ref_rel = pair.joints[:, legs] - pair.joints[:, :1], ref[:, legs] - ref[:, :1]
    # the legs keep their pose about the root up to the (new) facing of the canonical frame
    assert np.abs(np.linalg.norm(rel, axis=-1) - np.linalg.norm(ref_rel, axis=-1)).max() < 1e-4
    travel = np.linalg.norm(pair.joints[-1, 0, [0, 2]] - pair.joints[0, 0, [0, 2]])
    ref_travel = np.linalg.norm(ref[-1, 0, [0, 2]] - ref[0, 0, [0, 2]])
    assert travel == pytest.approx(ref_travel, abs=1e-3) and travel > 1.0
    head, wrists = SMPL22.parts["head"][-1], [SMPL22.parts["left_arm"][-1], SMPL22.parts["right_arm"][-1]]
    up = (pair.joints[:, wrists, 1] > pair.joints[:, [head], 1]).all(-1).mean()
    walk_up = (ref[:, wrists, 1] > ref[:, [head], 1]).all(-1).mean()
    assert up > 0.3 and walk_up == 0.0


def test_captions_join_two_generated_captions():
    assert (
        join_simultaneous("the person walks.", "a man raises both hands.") == "the person walks and raises both hands."
    )
    assert join_simultaneous("walks", "waves") == "walks and waves."


def test_build_is_reproducible_and_loads(train, joint_map, tmp_path):
    a = [p.captions[0] for p in build_split(train, joint_map, 4, seed=3, split_index=0)]
    b = [p.captions[0] for p in build_split(train, joint_map, 4, seed=3, split_index=0)]
    assert a == b
    out = tmp_path / "simul"
    build(embedded_data_root(), out, {"train": 3, "val": 2, "test": 2}, seed=0)
    data = load_split(out, "train")
    assert data.num_clips == 3 and data.captions_generated(0)
    assert "generated" in (out / "README.md").read_text().lower()
    np.testing.assert_array_equal(np.load(out / "Mean.npy"), np.load(embedded_data_root() / "Mean.npy"))
    with pytest.raises(Exception, match="already holds a prepared dataset"):
        build(embedded_data_root(), out, {"train": 3, "val": 2, "test": 2}, seed=0)
