"""Feature normalisation as the official datasets do it: the dataset's Std is the plain block-averaged std
(HumanML3D's Std.npy); the ÷5 of the root and contact blocks belongs to the T2M evaluator's input only."""

from __future__ import annotations

import numpy as np

from motiondiff.data.representations.hml_features import EVALUATOR_STD_BIAS, evaluator_std, feature_slices, mean_std

ROOT_AND_CONTACTS = ("root_rot_vel", "root_lin_vel", "root_y", "contacts")
# A 0/1 contact channel has std <= 0.5, so one divided by 5 is <= 0.1.
BIASED_CONTACT_STD = 0.5 / EVALUATOR_STD_BIAS


def test_official_std_is_block_averaged_and_not_reweighted(shared):
    ref = shared("reference", "humanml3d")
    official = np.load(ref / "Std.npy")
    for name, sl in feature_slices(22).items():
        assert np.ptp(official[sl]) == 0, f"official Std.npy is not constant within the {name} block"
    assert official[feature_slices(22)["contacts"]][0] > BIASED_CONTACT_STD  # 0.356: no ÷5


def test_mean_std_has_the_official_structure(shared):
    feats = np.load(shared("reference", "humanml3d") / "new_joint_vecs" / "012314.npy")
    mean, std = mean_std(feats)
    np.testing.assert_allclose(mean, feats.mean(0), rtol=1e-5, atol=1e-6)
    raw = feats.astype(np.float64).std(0)
    for name, sl in feature_slices(22).items():
        assert np.ptp(std[sl]) == 0, name
        np.testing.assert_allclose(std[sl][0], raw[sl].mean(), rtol=1e-5, err_msg=name)  # the plain block mean
    contact = std[feature_slices(22)["contacts"]][0]
    assert BIASED_CONTACT_STD < contact <= 0.5


def test_evaluator_std_divides_root_and_contacts_by_five(shared):
    official = np.load(shared("reference", "humanml3d") / "Std.npy")
    ratio = evaluator_std(official) / official
    for name, sl in feature_slices(22).items():
        want = 1 / EVALUATOR_STD_BIAS if name in ROOT_AND_CONTACTS else 1.0
        np.testing.assert_allclose(ratio[sl], want, rtol=1e-6, err_msg=name)
    assert np.array_equal(official, np.load(shared("reference", "humanml3d") / "Std.npy"))  # input left alone
    kit = np.ones(251, dtype=np.float32)  # KIT: 21 joints, found from the width
    assert (evaluator_std(kit) < 1).sum() == 4 + 4


def test_embedded_data_std_is_plain():
    """The committed embedded dataset's Std.npy is the plain block-averaged std of its train features."""
    from motiondiff.data.datamodules import embedded_data_root
    from motiondiff.data.formats.prepared import load_split

    train = load_split(embedded_data_root(), "train")
    _, std = mean_std(train.arrays["features"])
    np.testing.assert_allclose(train.std, std, rtol=1e-5)
