"""The ablation cells' stopping rule (docs/results/ablation_plan.md): best val FID not 5 % better over 3,000 steps,
checked from step 4,000; its history survives a checkpoint."""

from types import SimpleNamespace

import pytest
import torch

from motiondiff.eval.plateau import PlateauStop, plateaued


def curve(values, every=1000):
    return [(every * (i + 1), v) for i, v in enumerate(values)]


def test_a_falling_curve_goes_on_and_a_flat_one_stops_after_the_window():
    falling = curve([4.0, 3.0, 2.5, 2.0, 1.8, 1.6, 1.4, 1.3])
    assert not any(plateaued(falling[: i + 1], 0.05, 3000, 4000) for i in range(len(falling)))
    flat = curve([4.0, 3.0, 2.0, 1.5, 1.49, 1.48, 1.47])  # step 7,000: best 1.47 against 1.5 at 4,000 (2 %)
    assert [plateaued(flat[: i + 1], 0.05, 3000, 4000) for i in range(len(flat))] == [False] * 6 + [True]


def test_never_before_the_window_starts_at_start_and_a_gain_of_exactly_five_percent_is_enough():
    early = curve([2.0, 2.0, 2.0, 2.0, 2.0, 2.0])  # step 6,000: the window would start at 3,000 < 4,000
    assert not plateaued(early, 0.05, 3000, 4000)
    assert not plateaued(curve([4, 3, 2, 2.0, 2.0, 2.0, 1.9]), 0.05, 3000, 4000)  # 1.9 = 0.95 x 2.0
    assert plateaued(curve([4, 3, 2, 2.0, 2.0, 2.0, 1.91]), 0.05, 3000, 4000)


def test_a_worse_value_after_a_best_counts_as_no_gain_and_max_mode_mirrors_min():
    assert plateaued(curve([4, 3, 2, 1.0, 1.2, 1.1, 1.3]), 0.05, 3000, 4000)
    assert plateaued(curve([0.5, 0.6, 0.7, 0.80, 0.81, 0.82, 0.83]), 0.05, 3000, 4000, mode="max")
    assert not plateaued(curve([0.5, 0.6, 0.7, 0.80, 0.81, 0.82, 0.85]), 0.05, 3000, 4000, mode="max")
    with pytest.raises(ValueError, match="mode must be min or max"):
        plateaued(curve([1.0]), 0.05, 3000, 4000, mode="lowest")


def evaluate(callback, step, fid):
    trainer = SimpleNamespace(callback_metrics={"val/fid": torch.tensor(fid)}, global_step=step, sanity_checking=False,
                              should_stop=False)  # fmt: skip
    callback.on_validation_end(trainer, None)
    return trainer.should_stop


def test_the_callback_stops_the_trainer_and_a_resumed_one_stops_at_the_same_step():
    values = [4.0, 3.0, 2.0, 1.5, 1.49, 1.48, 1.47]
    whole = PlateauStop()
    stops = [evaluate(whole, 1000 * (i + 1), v) for i, v in enumerate(values)]
    assert stops == [False] * 6 + [True]

    first = PlateauStop()
    assert not any(evaluate(first, 1000 * (i + 1), v) for i, v in enumerate(values[:5]))
    resumed = PlateauStop()
    resumed.load_state_dict(first.state_dict())  # what a checkpoint carries to the next sitting
    assert not evaluate(resumed, 5000, 1.49)  # the same evaluation seen again after resuming is not counted twice
    assert [evaluate(resumed, 6000, 1.48), evaluate(resumed, 7000, 1.47)] == [False, True]
    assert resumed.history == whole.history


def test_sanity_checks_and_runs_without_the_metric_are_ignored():
    callback = PlateauStop()
    trainer = SimpleNamespace(callback_metrics={}, global_step=9000, sanity_checking=False, should_stop=False)
    callback.on_validation_end(trainer, None)
    trainer = SimpleNamespace(callback_metrics={"val/fid": torch.tensor(1.0)}, global_step=0, sanity_checking=True,
                              should_stop=False)  # fmt: skip
    callback.on_validation_end(trainer, None)
    assert callback.history == [] and not trainer.should_stop
