"""Stop a training run when its validation metric has plateaued: the stopping rule of issue 43's ablation cells
(docs/results/ablation_plan.md), written before any cell trained.

At each evaluation at step s, the best value so far is compared with the best value up to step s - `window`: the
run has plateaued when the newer best is not at least `min_gain` (relative) better, checked only once s - `window`
reaches `start`. Lightning's EarlyStopping counts evaluations and takes an absolute min_delta; the rule here is
written in steps and as a relative gain, and its history is saved in checkpoints so a run resumed in a later
sitting stops where an uninterrupted one would.
"""

from __future__ import annotations

import logging

import lightning as L

log = logging.getLogger(__name__)


def plateaued(history: list[tuple[int, float]], min_gain: float, window: int, start: int, mode: str = "min") -> bool:
    """Whether the last entry of `history` ((step, value) in step order) ends a plateau (see the module docstring)."""
    if mode not in ("min", "max"):
        raise ValueError(f"mode must be min or max, got {mode!r}")
    if not history:
        return False
    step = history[-1][0]
    if step - window < start:
        return False
    before = [v for s, v in history if s <= step - window]
    if not before:
        return False
    best = min if mode == "min" else max
    old, new = best(before), best(v for _, v in history)
    return new > old * (1 - min_gain) if mode == "min" else new < old * (1 + min_gain)


class PlateauStop(L.Callback):
    """Sets `trainer.should_stop` when `monitor` has plateaued (`plateaued`); place it after the callback that logs
    `monitor`. Its history of (step, value) is kept in the checkpoint."""

    def __init__(self, monitor: str = "val/fid", mode: str = "min", min_gain: float = 0.05, window: int = 3000,
                 start: int = 4000) -> None:  # fmt: skip
        super().__init__()
        self.monitor, self.mode, self.min_gain, self.window, self.start = monitor, mode, min_gain, window, start
        self.history: list[tuple[int, float]] = []

    def on_validation_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        value = trainer.callback_metrics.get(self.monitor)
        if trainer.sanity_checking or value is None:
            return
        step = int(trainer.global_step)
        if self.history and self.history[-1][0] == step:  # the same evaluation seen twice (resumed mid-epoch)
            return
        self.history.append((step, float(value)))
        if plateaued(self.history, self.min_gain, self.window, self.start, self.mode):
            log.info("%s has not improved by %.0f%% over the last %d steps at step %d: stopping", self.monitor,
                     100 * self.min_gain, self.window, step)  # fmt: skip
            trainer.should_stop = True

    def state_dict(self) -> dict:
        return {"history": [list(h) for h in self.history]}

    def load_state_dict(self, state_dict: dict) -> None:
        self.history = [(int(s), float(v)) for s, v in state_dict.get("history", [])]
