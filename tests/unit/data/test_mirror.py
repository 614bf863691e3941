"""Left-right mirroring (issue 39): on a real clip of the embedded Bandai data the mirrored features decode to the
reflected joints, agree with features extracted from the reflected joints, and mirror back to the original;
captions and action labels swap sides; a datamodule with mirror=true trains on both and evaluates on the real clips."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.mirror import mirror_hml_features, mirrored_labels, swap_left_right
from motiondiff.data.representations.hml_features import (
    feature_slices,
    features_from_canonical,
    joints_from_features,
)
from motiondiff.geometry.skeleton import KIT21, SMPL22

REFLECT_X = np.array([-1.0, 1.0, 1.0])


@pytest.fixture(scope="module")
def walk_turn():
    """A real clip that turns and swings its arms: every feature block is non-trivial."""
    data = load_split(embedded_data_root(), "train")
    index = next(i for i, r in enumerate(data.records()) if "walk-turn-left" in r.id)
    return data.arrays["features"][data.feature_slice(index)].astype(np.float64)


def test_mirrored_features_decode_to_the_reflected_joints(walk_turn):
    joints = joints_from_features(walk_turn)
    reflected = joints[:, list(SMPL22.mirror_permutation)] * REFLECT_X
    mirrored = joints_from_features(mirror_hml_features(walk_turn))
    assert np.abs(mirrored - reflected).max() < 1e-5  # metres
    assert np.abs(mirrored - joints).max() > 0.1  # a real change: the turn goes the other way


def test_mirroring_twice_is_the_identity(walk_turn):
    assert np.array_equal(mirror_hml_features(mirror_hml_features(walk_turn)), walk_turn)
    kit = np.random.default_rng(0).normal(size=(5, 251))
    assert np.array_equal(mirror_hml_features(mirror_hml_features(kit)), kit)


def test_every_block_matches_features_extracted_from_the_reflected_joints(walk_turn):
    """Rotations, velocities and contacts too, not only what decoding reads. The extractor's own round trip
    (features -> joints -> features of the same clip) differs by about 2e-3 in the 6D block: that is the bar."""
    joints = joints_from_features(walk_turn).astype(np.float64)
    round_trip = np.abs(features_from_canonical(joints) - walk_turn[:-1]).max()
    reflected = joints[:, list(SMPL22.mirror_permutation)] * REFLECT_X
    extracted = features_from_canonical(reflected)
    mirrored = mirror_hml_features(walk_turn)[:-1]
    for name, block in feature_slices(22).items():
        assert np.abs(extracted[:, block] - mirrored[:, block]).max() <= round_trip + 1e-6, name


def test_the_mirror_needs_a_symmetric_rest_pose():
    assert len(set(KIT21.mirror_permutation)) == 21  # every joint has one partner


def test_captions_swap_left_and_right_keeping_case():
    assert swap_left_right("a person waves the left hand.") == "a person waves the right hand."
    assert swap_left_right("Left, then RIGHT: turns right") == "Right, then LEFT: turns left"
    assert swap_left_right("wave-left-hand, walk_right") == "wave-right-hand, walk_left"
    assert swap_left_right("a leftover bright light") == "a leftover bright light"  # words, not letters


def test_action_labels_map_to_their_mirror_images():
    names = ["walk", "walk-left", "walk-right", "wave-left-hand", "wave-right-hand", "raise-up-left-hand"]
    assert mirrored_labels(names) == [0, 2, 1, 4, 3, 5]  # no raise-up-right-hand here: kept


def test_a_mirrored_datamodule_doubles_train_only():
    plain = PreparedDataModule(embedded_data_root(), max_frames=80)
    mirrored = PreparedDataModule(embedded_data_root(), max_frames=80, mirror=True)
    train, plain_train = mirrored.dataset("train").records, plain.dataset("train").records
    assert len(train) == 2 * len(plain_train)
    assert [r.id for r in mirrored.dataset("val").records] == [r.id for r in plain.dataset("val").records]
    by_id = {r.id: r for r in train}
    names = mirrored.action_names
    for rec in plain_train:
        image = by_id["M" + rec.id]
        assert image.texts == [swap_left_right(t) for t in rec.texts]
        assert names[image.action] == swap_left_right(names[rec.action])
        assert np.array_equal(image.motion, mirror_hml_features(rec.motion))
    assert any("left" in t for r in plain_train for t in r.texts)  # the swap is exercised
    # statistics of the doubled split: no net sideways drift or turn
    blocks = feature_slices(22)
    assert abs(mirrored.mean[blocks["root_rot_vel"]][0]) < 1e-6
    assert abs(mirrored.mean[blocks["root_lin_vel"]][0]) < 1e-6


def test_mirror_refuses_representations_it_cannot_reflect():
    with pytest.raises(ValueError, match="representation=hml263"):
        PreparedDataModule(embedded_data_root(), representation="rp6jr", mirror=True)
