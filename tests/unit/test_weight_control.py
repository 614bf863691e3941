"""The weight-control report's bookkeeping: which local action is guided, root travel, and the monotonicity verdicts."""

from __future__ import annotations

import numpy as np

from motiondiff.eval.weight_control import guided_index, root_travel, summarise


def test_the_guided_action_is_the_first_that_moves_the_body():
    assert guided_index(["waves both hands", "walks forward", "runs"]) == 1
    assert guided_index(["bows", "waves"]) == 0


def test_root_travel_is_the_ground_distance_of_the_root():
    joints = np.zeros((10, 3, 3))
    joints[:, 0, 0] = np.linspace(0, 3, 10)  # 3 m along x
    joints[:, 0, 1] = np.linspace(0, 5, 10)  # height does not count
    joints[-1, 0, 2] = 4.0
    assert np.isclose(root_travel(joints), 5.0)


def _caption(distances, travel, text="walks forward"):
    rows = [{"weight": w, "latent_distance": [d, d], "root_travel_m": [t, t]}
            for w, d, t in zip((0, 1, 2), distances, travel, strict=True)]  # fmt: skip
    return {"guided_text": text, "rows": rows}


def test_summary_reports_the_mean_curve_and_per_caption_monotonicity():
    results = [
        _caption([3, 2, 1], [1, 2, 3]),
        _caption([3, 3.5, 1], [1, 1, 1]),
        _caption([2, 1, 0.5], [0, 0, 0], "bows"),
    ]
    summary = summarise(results, [0, 1, 2])
    means = [c["latent_distance"][0] for c in summary["curve"]]
    assert np.allclose(means, [8 / 3, 6.5 / 3, 2.5 / 3])
    assert summary["mean_distance_decreases_monotonically"] and summary["captions_monotone"] == 2
    assert [c["walking_captions"] for c in summary["curve"]] == [2, 2, 2]  # "bows" has no root travel to report
    assert np.isclose(summary["curve"][2]["root_travel_m"][0], 2.0)
    rising = summarise([_caption([1, 2, 3], [0, 0, 0])], [0, 1, 2])
    assert not rising["mean_distance_decreases_monotonically"] and rising["captions_monotone"] == 0
