"""The weight-control report's bookkeeping: which local action is guided, root travel, and the monotonicity verdicts."""

from __future__ import annotations

import json

import numpy as np

from motiondiff.studies.weight_control import guided_index, root_travel, summarise


def test_the_guided_action_is_the_first_that_moves_the_body():
    assert guided_index(["waves both hands", "walks forward", "runs"]) == 1
    assert guided_index(["bows", "waves"]) == 0


def test_root_travel_is_the_ground_distance_of_the_root():
    joints = np.zeros((10, 3, 3))
    joints[:, 0, 0] = np.linspace(0, 3, 10)  # 3 m along x
    joints[:, 0, 1] = np.linspace(0, 5, 10)  # height does not count
    joints[-1, 0, 2] = 4.0
    assert np.isclose(root_travel(joints), 5.0)


def _caption(distances, travel, text="walks forward", local_travel=3.0, motion=(2, 2, 1)):
    rows = [{"weight": w, "latent_distance": [d, d], "root_travel_m": [t, t], "motion_distance": [m, m + 1]}
            for w, d, t, m in zip((0, 1, 2), distances, travel, motion, strict=True)]  # fmt: skip
    return {"guided_text": text, "rows": rows, "guided_local_root_travel_m": local_travel}


def test_summary_reports_the_mean_curve_and_per_caption_monotonicity():
    results = [
        _caption([3, 2, 1], [1, 2, 3]),
        _caption([3, 3.5, 1], [1, 1, 1]),
        _caption([2, 1, 0.5], [0, 0, 0], "bows", motion=(1, 1, 3)),
    ]
    summary = summarise(results, [0, 1, 2])
    means = [c["latent_distance"][0] for c in summary["curve"]]
    assert np.allclose(means, [8 / 3, 6.5 / 3, 2.5 / 3])
    assert summary["mean_distance_decreases_monotonically"] and summary["captions_monotone"] == 2
    assert [c["walking_captions"] for c in summary["curve"]] == [2, 2, 2]  # "bows" has no root travel to report
    assert np.isclose(summary["curve"][2]["root_travel_m"][0], 2.0)
    # travel 1 -> 3 m reaches the local motion's 3 m; 1 -> 1 m does not move towards it
    assert summary["walking_captions_toward_local"] == 1 and summary["walking_captions"] == 2
    assert np.isclose(summary["guided_local_root_travel_m"][0], 3.0)
    assert summary["captions_decoded_closer"] == 2  # the decoded motion ends closer to the local one in 2 of 3
    assert np.allclose(
        [c["motion_distance"][0] for c in summary["curve"]], [13 / 6] * 3
    )  # per caption: mean of the samples, then over captions
    json.dumps(summary)  # plain Python numbers: the report is written as JSON
    rising = summarise([_caption([1, 2, 3], [0, 0, 0])], [0, 1, 2])
    assert not rising["mean_distance_decreases_monotonically"] and rising["captions_monotone"] == 0
