"""`repr(MotionOutput)` is one short line (counts, lengths, skeleton, prompts), never the arrays (issue 40)."""

from __future__ import annotations

import numpy as np

from motiondiff.data.representations import get_representation
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.pipelines.output import MotionOutput


def test_repr_is_one_short_line_without_arrays():
    rep = get_representation("hml263", SMPL22)
    joints = [np.zeros((80, 22, 3)), np.zeros((40, 22, 3)), np.zeros((80, 22, 3))]
    prompts = ["a person walks forward", "a person bows", "a person walks forward"]
    out = MotionOutput(joints, [np.zeros((79, 263))] * 3, prompts, 20.0, SMPL22, rep, {"seed": 0})
    text = repr(out)
    assert "\n" not in text and len(text) < 300 and "array" not in text and "0." not in text
    assert text.startswith("MotionOutput(3 motion(s) of 2 s, 4 s at 20 fps on smpl22 (22 joints)")
    assert "'a person walks forward', 'a person bows'" in text
