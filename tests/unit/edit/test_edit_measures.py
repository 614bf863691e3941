"""The editing report's boundary measures, on hand-made motions whose numbers are known."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.edit.measures import boundary_jumps, step_speeds, velocity_changes

FPS = 20.0


def _line(velocities: list[float]) -> np.ndarray:
    """One joint moving along x with the given per-step velocities (m/s), shape (N, 1, 3)."""
    x = np.concatenate([[0.0], np.cumsum(np.asarray(velocities) / FPS)])
    return np.stack([x, np.zeros_like(x), np.zeros_like(x)], -1)[:, None]


def test_speeds_and_velocity_changes():
    joints = _line([1.0, 1.0, 3.0, -1.0])
    np.testing.assert_allclose(step_speeds(joints, FPS), [1.0, 1.0, 3.0, 1.0])
    np.testing.assert_allclose(velocity_changes(joints, FPS), [0.0, 2.0, 4.0])  # a reversal counts in full


def test_a_motion_that_keeps_its_velocity_has_no_change_however_fast_its_boundary_step():
    """A kick that starts at a boundary: a fast step there (ratio 4) but a seamless one (change ratio 0)."""
    kept = np.array([True] * 4 + [False] * 6 + [True] * 4)
    steps = [0.5, 0.5, 0.5, 0.5] + [0.5] * 5 + [2.0] * 4  # the middle moves at 0.5 m/s, the end part at 2 m/s
    out = boundary_jumps(_line(steps), kept, FPS)
    start, end = out["boundaries"]
    assert out["median_generated_speed"] == pytest.approx(0.5)
    assert start["side"] == "start" and start["ratio"] == pytest.approx(1.0)
    assert start["change_ratio"] == pytest.approx(0.0, abs=1e-9)
    # step 9 crosses into the kept end at 2 m/s: the velocity changed by 1.5 m/s entering it
    assert end["side"] == "end" and end["ratio"] == pytest.approx(4.0) and end["change_ratio"] == pytest.approx(3.0)


def test_a_jump_is_a_change_on_both_sides():
    """A one-frame teleport at a boundary: the velocity jumps into the step and back out of it."""
    kept = np.array([True] * 4 + [False] * 6)
    steps = [0.2, 0.2, 0.2, 5.0, 0.2, 0.2, 0.2, 0.2, 0.2]
    (b,) = boundary_jumps(_line(steps), kept, FPS, floor=0.1)["boundaries"]
    assert b["ratio"] == pytest.approx(25.0) and b["change_ratio"] == pytest.approx(4.8 / 0.2)
