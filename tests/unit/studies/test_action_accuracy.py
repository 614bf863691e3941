"""The action-accuracy metric and its per-action breakdown, on hand-made classifier outputs."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.eval import action_table
from motiondiff.eval.protocol import EvalClips, action_accuracy


class _Evaluators:  # only what action_accuracy reads
    pass


def test_action_accuracy_counts_labelled_clips_only():
    logits = np.eye(3)[[0, 1, 2, 2]]  # predicted 0, 1, 2, 2
    assert action_accuracy(_Evaluators(), {"action_logits": logits}, np.array([0, 1, 1, -1])) == pytest.approx(2 / 3)
    with pytest.raises(ValueError, match="action classifier"):
        action_accuracy(_Evaluators(), {"text_motion": logits}, np.array([0, 1, 1, 2]))
    with pytest.raises(ValueError, match="labels"):
        action_accuracy(_Evaluators(), {"action_logits": logits}, np.full(4, -1))


def test_label_captions_are_the_first_caption():
    clips = EvalClips(["a", "b"], [np.zeros((4, 263))] * 2, [["x walks.", "y"], []], np.array([3, -1]))
    assert clips.label_captions() == ["x walks.", ""] and clips.labelled


def test_per_action_rows_and_confusion():
    names = ["walk", "run", "bow"]
    asked = [0, 0, 1, 2]
    generated = [[0, 1, 1, 2], [0, 0, 0, 2]]  # two replications
    rows = action_table.per_action_rows(asked, generated, real=[0, 0, 1, 1], names=names)
    by = {r["action"]: r for r in rows}
    assert by["walk"] == {"action": "walk", "clips": 2, "generated": 0.75, "real": 1.0, "mistaken_for": "run"}
    assert by["run"]["generated"] == 0.5 and by["run"]["mistaken_for"] == "walk"
    assert by["bow"]["generated"] == 1.0 and by["bow"]["real"] == 0.0 and by["bow"]["mistaken_for"] == ""
    m = action_table.confusion([0, 0, 1, 2], [0, 1, 1, 2], 3)
    assert m.tolist() == [[1, 1, 0], [0, 1, 0], [0, 0, 1]]
    text = action_table.format_per_action(rows, "t")
    assert "| walk | 2 | 0.75 | 1.00 | run |" in text


def test_confusion_png(tmp_path):
    m = action_table.confusion([0, 1, 1], [0, 1, 0], 4)  # class 2 and 3 never appear: left out of the figure
    path = action_table.plot_confusion(m, ["a", "b", "c", "d"], tmp_path / "c.png", "t")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
