"""The behaviour checks used to judge a trained model (walks travel, raised hands), on synthetic motion."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.synthetic_motion import glide as _walk
from fixtures.synthetic_motion import rest_pose as _rest_pose

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.edit.measures import mean_joint_acceleration, mean_joint_speed
from motiondiff.studies.behaviour import Behaviour, real_clips


def test_walk_and_raise_are_told_apart():
    walk = _walk(0, 3.0, frames=80)
    raise_both = np.repeat(_rest_pose()[None], 50, axis=0)
    raise_both[10:40, [20, 21], 1] = raise_both[0, 15, 1] + 0.25  # both wrists above the head for 1.5 s
    b = Behaviour.of([walk, raise_both], fps=20)
    assert b.walk_success().tolist() == [True, False]
    assert b.in_place().tolist() == [False, True]
    assert b.both_wrists_up.tolist() == [False, True]
    # the rest pose glides 3 m in 79 frames: every joint moves 3/79 m per frame
    assert abs(mean_joint_speed(walk, 20) - 3.0 / 79 * 20) < 1e-9 and b.speed[0] == mean_joint_speed(walk, 20)
    assert b.accel[0] < 1e-6  # a constant glide has no acceleration


def test_jitter_shows_in_the_acceleration_not_in_the_travel():
    walk = _walk(0, 3.0, frames=80)
    jittery = walk.copy()
    jittery[1::2, 10, 1] += 0.1  # the left foot flips 10 cm up and down every frame
    b = Behaviour.of([walk, jittery], fps=20)
    smooth, noisy = b.accel
    assert smooth < 1e-6
    assert b.travel[1] == b.travel[0]  # the root path is untouched: travel cannot see the jitter
    # one joint of 22 moves +-0.1 m between frames: second differences of 0.2 m, so 0.2 * 400 / 22 m/s^2 on average
    assert abs(noisy - 0.2 * 400 / 22) < 1e-3
    assert abs(mean_joint_acceleration(jittery, 20) - noisy) < 1e-9


def test_real_reference_clips_from_the_embedded_data():
    walks = real_clips(embedded_data_root(), "walk", 80)
    raises = real_clips(embedded_data_root(), "raise-up-both-hands", 50)
    assert len(walks) >= 20 and len(raises) >= 10
    assert Behaviour.of(walks, 20).walk_success().mean() > 0.9
    assert Behaviour.of(raises, 20).in_place().all()


def test_report_samples_as_sample_py_does():
    """The behaviour report's sampler is sample.py's default (conf/sample.yaml), not a sampler of its own."""
    from hydra import compose, initialize_config_dir

    from motiondiff.studies.behaviour import CONF_DIR, DEFAULT_PROMPTS, default_sampler

    with initialize_config_dir(str(CONF_DIR), version_base=None):
        cfg = compose("sample")  # what sample.py runs with when given nothing
    assert default_sampler() == {"sampler": cfg.sampler.name, "steps": cfg.sampler.steps}
    asked = {label for _, _, label in DEFAULT_PROMPTS}
    assert {"walk", "run", "raise-up-both-hands", "wave-right-hand", "kick", "bow", "walk-back"} <= asked


def test_an_action_model_is_asked_with_the_prompts_labels():
    """The behaviour report of the released action-conditioned model: each prompt's label is the condition, and
    the rows are the labels the model knows."""
    import torch

    from motiondiff.model_files.release import load_release
    from motiondiff.model_files.resolve import SHIPPED_MODELS
    from motiondiff.studies.behaviour import DEFAULT_PROMPTS, report

    module = load_release(SHIPPED_MODELS["action"])
    assert module.condition_kind == "action"
    torch.manual_seed(0)
    rows = report(module, embedded_data_root(), n=2, steps=2, prompts=DEFAULT_PROMPTS[:2])
    assert list(rows) == ["walk", "run"]
    assert all(r["label"] == name and len(r["generated"].travel) == 2 for name, r in rows.items())


def test_net_speed_is_ground_distance_per_second_and_ignores_jitter():
    from motiondiff.studies.behaviour import net_speed

    frames = 41  # 2 s at 20 fps
    joints = np.zeros((frames, 22, 3))
    joints[:, 0, 2] = np.linspace(0, 2.0, frames)  # 2 m forward along z in 2 s
    joints[:, 0, 1] = 0.9 + 0.05 * np.sin(np.arange(frames))  # bobbing height does not count
    joints[1:-1:2, 0, 0] += 0.1  # sideways jitter between the end frames does not count
    assert net_speed(joints, 20.0) == pytest.approx(1.0)


def test_the_speed_table_measures_each_length_against_the_real_clips():
    import torch

    from motiondiff.model_files.release import load_release
    from motiondiff.model_files.resolve import SHIPPED_MODELS
    from motiondiff.pipelines import MotionPipeline
    from motiondiff.studies.behaviour import SPEED_PROMPTS, speed_table

    torch.manual_seed(0)
    for kind in ("text", "action"):  # an action model is asked with the label (the text is no action name)
        pipe = MotionPipeline(load_release(SHIPPED_MODELS[kind]))
        rows = speed_table(pipe, embedded_data_root(), n=2, seed=0, sampler="ddim", steps=2)
        assert [(r["label"], r["seconds"]) for r in rows] == [(lb, s) for _, lb in SPEED_PROMPTS for s in (2, 4, 6)]
        assert all(r["real"] > 0.5 and r["ratio"] == pytest.approx(r["speed"] / r["real"]) for r in rows)
