"""The action classifier's kept weights: overall val accuracy, or balanced accuracy (mean per-class recall), which
counts a class of 2 val clips as much as one of 40."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.lit.evaluator import ActionClassifierModule
from motiondiff.models.evaluators.networks import ActionClassifierGRU


class _Module(ActionClassifierModule):
    """Validation outside a Trainer: the epoch is set by the test, logging goes nowhere."""

    epoch = 0

    @property
    def current_epoch(self) -> int:
        return self.epoch

    def log(self, *args, **kwargs) -> None:
        pass


def _module(select_by: str) -> ActionClassifierModule:
    classifier = ActionClassifierGRU(66, 8, 1, 3, 4, input_kind="joints")
    return _Module(classifier, np.zeros(263), np.ones(263), 22, select_by=select_by)


def _validate(module: ActionClassifierModule, targets: list[int], predictions: list[int], epoch: int) -> None:
    module._logits = lambda batch: torch.nn.functional.one_hot(torch.tensor(predictions), 3).float()  # noqa: ARG005
    module.epoch = epoch
    module.validation_step({"action": torch.tensor(targets)}, 0)
    module.on_validation_epoch_end()


@pytest.mark.parametrize("select_by, kept_epoch", [("accuracy", 2), ("balanced_accuracy", 1)])
def test_the_selection_score_decides_which_epoch_is_kept(select_by, kept_epoch):
    targets = [0] * 8 + [1, 2]  # one big class, two of one clip each
    module = _module(select_by)
    _validate(module, targets, [0] * 10, epoch=0)  # accuracy 0.8, balanced (1 + 0 + 0) / 3 = 0.33
    assert module.val_scores == pytest.approx({"accuracy": 0.8, "balanced_accuracy": 1 / 3})
    _validate(module, targets, [0] * 6 + [1, 1, 1, 2], epoch=1)  # accuracy 0.8, balanced (0.75 + 1 + 1) / 3
    assert module.val_scores == pytest.approx({"accuracy": 0.8, "balanced_accuracy": 0.75 / 3 + 2 / 3})
    _validate(module, targets, [0] * 7 + [2, 0, 2], epoch=2)  # accuracy 0.8 again (ties go to the later), balanced 0.63
    assert module.best_epoch == kept_epoch
    assert module.best_scores["accuracy"] == pytest.approx(0.8)


def test_an_unknown_selection_score_is_refused():
    with pytest.raises(ValueError, match="select_by must be one of"):
        _module("f1")
