"""vvMDM Fig. 2 and the evaluation filter per representation: smoothness on a representation's own features, and
the Gaussian filter on jp features (positions) equal to filtering the joints."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.edit.smoothing import smooth_features, smooth_joints
from motiondiff.studies.representation_smoothness import ORDER, representation_smoothness


def test_every_representation_is_scored_on_its_own_features():
    names = ("jp", "rpmjr", "hml263")  # one of each kind: positions, rotations, HumanML3D features
    results = representation_smoothness(embedded_data_root(), "val", names=names)
    assert list(results) == list(names) and set(names) <= set(ORDER)
    dims = {name: r["dims"] for name, r in results.items()}
    assert dims["jp"] == 3 * 21 and dims["hml263"] == 263 and dims["rpmjr"] == 3 + 9 * 21  # the rig's 21 joints
    assert all(0 < r["mean"] <= 1 and r["clips"] > 10 for r in results.values())


def test_jp_filter_is_the_joint_filter_and_rotations_are_refused():
    rng = np.random.default_rng(0)
    joints = rng.normal(size=(30, 21, 3)).cumsum(0)
    feats = joints.reshape(30, 63).astype(np.float32)
    np.testing.assert_allclose(
        smooth_features(feats, 2.0, "jp").reshape(30, 21, 3), smooth_joints(joints, 2.0), atol=1e-5
    )
    with pytest.raises(ValueError, match="rp6jr"):
        smooth_features(rng.normal(size=(30, 129)), 2.0, "rp6jr")
    assert np.array_equal(smooth_features(feats, 0, "rp6jr"), feats)  # off: nothing to refuse


def test_the_study_shows_progress_on_stderr(capsys):
    representation_smoothness(embedded_data_root(), "val", names=("jp",))
    err = capsys.readouterr().err
    assert "representations" in err and "1/1" in err  # tqdm's bar over the representations, finished
