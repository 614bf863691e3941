"""Generated captions from measured motion, joint maps, stratified splits."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.synthetic_motion import glide as _walk
from fixtures.synthetic_motion import rest_pose as _rest_pose

from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.preparing.captions import CONTENT_PHRASES, STYLE_PHRASES, generate_captions, measure
from motiondiff.data.preparing.splits import stratified_split, stratified_subset
from motiondiff.geometry.skeleton import SMPL22


@pytest.mark.parametrize(
    "deg, expected",
    [(0, "forward"), (180, "backward"), (90, "to the left"), (-90, "to the right"), (40, "forward and to the left")],
)
def test_travel_direction_and_distance(deg, expected):
    facts = measure(_walk(deg, 4.0))
    assert facts.direction == expected
    assert facts.distance == pytest.approx(4.0, rel=1e-6)
    assert facts.speed == pytest.approx(4.0 / (79 / 20), rel=1e-6)
    assert abs(facts.turn_degrees) < 1e-6


def test_standing_still_and_turning():
    pose = _rest_pose()
    frames = []
    for angle in np.linspace(0, np.pi / 2, 40):  # turn 90 degrees to the left about the root
        c, s = np.cos(angle), np.sin(angle)
        rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        frames.append((pose - pose[0] * [1, 0, 1]) @ rot.T)
    facts = measure(np.stack(frames))
    assert facts.direction is None and facts.distance < 1e-9
    assert facts.turn_degrees == pytest.approx(90.0, abs=1e-6)


def test_raised_hand_detected():
    joints = np.repeat(_rest_pose()[None], 40, axis=0)
    joints[10:30, 21, 1] = joints[0, 15, 1] + 0.2  # right wrist above the head for 1 s
    facts = measure(joints)
    assert facts.hands_above_head == ("right",) and facts.hands_above_shoulders == ("right",)
    caps = generate_captions("raise-up-right-hand", "tired", facts, np.random.default_rng(0))
    assert len(caps) == 3
    assert all("raises the right hand" in c for c in caps[:2]) and "wearily" in caps[0]
    assert "with the right hand above the head" in caps[1] and "stays in place" in caps[2]


def test_walk_captions_mention_measured_distance():
    caps = generate_captions("walk", "normal", measure(_walk(0, 4.0)), np.random.default_rng(1))
    assert caps[0].endswith("walks.") and "moving forward about 4.0 meters" in caps[1]
    assert "travels forward 4.0 meters at 1.0 m/s" in caps[2]


def test_every_bandai_label_has_a_phrase():
    contents = ["walk", "run", "dash", "walk-back", "walk-left", "walk-right", "bow", "bye", "byebye", "guide",
                "respond", "call", "punch", "kick", "slash", "dance-short", "dance-long", "walk-turn-left",
                "walk-turn-right", "wave-both-hands", "wave-left-hand", "wave-right-hand", "raise-up-both-hands",
                "raise-up-left-hand", "raise-up-right-hand"]  # fmt: skip
    styles = ["normal", "happy", "sad", "angry", "proud", "not-confident", "masculinity", "feminine", "childish",
              "old", "tired", "active", "musical", "giant", "chimpira", "elderly", "exhausted", "masculine",
              "youthful"]  # fmt: skip
    assert set(contents) <= set(CONTENT_PHRASES) and set(styles) <= set(STYLE_PHRASES)


def test_joint_map_is_data_and_averages():
    jm = JointMap.load("bandai_to_smpl22")
    names = ["Hips", "Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",
             "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R", "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L",
             "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"]  # fmt: skip
    pos = np.random.default_rng(0).normal(size=(5, len(names), 3)) * 100
    out = jm.apply(pos, names)
    assert out.shape == (5, 22, 3)
    spine2 = SMPL22.index("spine2")
    expected = (pos[:, 1] + pos[:, 2]) / 2 * 0.01
    np.testing.assert_allclose(out[:, spine2], expected)
    np.testing.assert_allclose(out[:, SMPL22.index("r_wrist")], pos[:, names.index("Hand_R")] * 0.01)
    with pytest.raises(ValueError, match="needs source joint 'Toes_R'"):
        jm.apply(pos[:, :-1], names[:-1])
    with pytest.raises(FileNotFoundError, match="shipped maps"):
        JointMap.load("nope_to_smpl22")


def test_stratified_split_is_stratified_and_deterministic():
    names = [f"clip{i:03d}" for i in range(300)]
    groups = [i % 3 for i in range(300)]  # three groups of 100
    split = stratified_split(names, groups, seed=0)
    for g in range(3):
        members = [s for s, gg in zip(split, groups, strict=True) if gg == g]
        assert members.count("train") == 80 and members.count("val") == 10 and members.count("test") == 10
    # Order of reading does not matter; the seed does.
    order = np.random.default_rng(0).permutation(300)
    again = stratified_split([names[i] for i in order], [groups[i] for i in order], seed=0)
    assert [again[list(order).index(i)] for i in range(300)] == split
    assert stratified_split(names, groups, seed=1) != split


def test_small_groups_reach_every_split():
    names = [f"c{i}" for i in range(40)]
    split = stratified_split(names, names, seed=0)  # 40 groups of one clip each
    assert split.count("train") == 32 and split.count("val") == 4 and split.count("test") == 4


def test_stratified_subset():
    names = [f"c{i}" for i in range(30)]
    groups = ["a"] * 20 + ["b"] * 9 + ["c"]
    keep = stratified_subset(names, groups, per_group=2, seed=0)
    assert sorted(groups[i] for i in keep) == ["a", "a", "b", "b", "c"]
    assert keep == stratified_subset(names, groups, per_group=2, seed=0)
