"""Long motions by prefix in-painting: windows planned within max_frames, the stitched length, the overlap frames the
same motion in joint space on both sides of each seam, and the boundary report (tiny untrained models)."""

from __future__ import annotations

from itertools import pairwise
from types import SimpleNamespace

import numpy as np
import pytest
import torch
from fixtures.tiny_models import tiny_datamodule
from fixtures.tiny_models import tiny_module as build_tiny

from motiondiff.edit.canonical import placement, turn_points
from motiondiff.edit.long_motion import WindowPlan, boundary_report, generate_long, plan_windows

MAX_FRAMES = 40  # 2 s at 20 fps
TOL = 1e-5  # metres


def tiny_module(representation: str):
    return build_tiny(tiny_datamodule(MAX_FRAMES, representation)).eval()


@pytest.fixture(scope="module", params=[("hml263", 0.0), ("jp", 0.0), ("rp6jr", 0.0), ("hml263", 0.25), ("jp", 0.25)],
                ids=["hml263", "jp", "rp6jr", "hml263-blend", "jp-blend"])  # fmt: skip
def long(request):
    """3 segments (1.5 s, 2.5 s, 1 s = 100 frames, 2.5x max_frames), 0.5 s overlap (of which `blend` cross-faded),
    2 motions at once."""
    representation, blend = request.param
    module = tiny_module(representation)
    motion = generate_long(module, [(None, 1.5), (None, 2.5), (None, 1.0)], overlap_s=0.5, blend_s=blend,
                           num_samples=2, sampler="ddim", steps=2, generator=torch.Generator().manual_seed(0),
                           labels=["a", "b", "c"])  # fmt: skip
    return module, motion


def placed_joints(module, window) -> np.ndarray:
    """A window's own (canonical) decoding, moved to where it stands in the long motion."""
    return turn_points(module.representation.decode_numpy(window.features), window.yaw, window.offset)


def test_plan_keeps_every_window_within_max_frames():
    plans = plan_windows([30, 50, 20], overlap=10, max_frames=40)
    assert plans == [WindowPlan(0, 0, 30, 0), WindowPlan(1, 30, 55, 10), WindowPlan(1, 55, 80, 10),
                     WindowPlan(2, 80, 100, 10)]  # fmt: skip
    assert all(p.length <= 40 for p in plans)
    long_first = plan_windows([100], overlap=10, max_frames=40)  # 4 windows of 25 new frames
    assert [p.end - p.start for p in long_first] == [25] * 4 and [p.overlap for p in long_first] == [0, 10, 10, 10]
    assert plan_windows([3, 4], overlap=10, max_frames=40)[1] == WindowPlan(1, 3, 7, 3)  # overlap ≤ what exists
    with pytest.raises(ValueError, match="overlap must be 1 to 39"):
        plan_windows([30], overlap=40, max_frames=40)
    blended = plan_windows([30, 50], overlap=10, max_frames=40, blend=4)
    assert [(p.overlap, p.blend, p.held) for p in blended] == [(0, 0, 0), (10, 4, 6), (10, 4, 6)]
    assert plan_windows([2, 5], overlap=10, max_frames=40, blend=4)[1].blend == 1  # one frame stays held
    with pytest.raises(ValueError, match="blend must be 0 to 9"):
        plan_windows([30], overlap=10, max_frames=40, blend=10)


def test_stitched_length_and_segment_ranges(long):
    module, motion = long
    d, j = module.hparams.feature_dim, module.representation.skeleton.num_joints
    assert motion.features.shape == (2, 100, d) and motion.joints.shape == (2, 100, j, 3)
    assert motion.num_frames > module.hparams.max_frames and np.isfinite(motion.joints).all()
    assert [(s["label"], s["start"], s["end"]) for s in motion.segments] == [("a", 0, 30), ("b", 30, 80),
                                                                             ("c", 80, 100)]  # fmt: skip
    plans = [w.plan for w in motion.windows]
    assert plans == plan_windows([30, 50, 20], overlap=10, max_frames=MAX_FRAMES, blend=plans[1].blend)
    assert {p.blend for p in plans[1:]} == ({5} if plans[1].blend else {0})  # 0.25 s at 20 fps
    assert all(w.features.shape == (2, w.plan.length, d) for w in motion.windows)


def test_overlap_frames_are_the_same_motion_on_both_sides_of_each_seam(long):
    """The held overlap frames of window k+1 are window k's last frames and the stitched ones, exactly; everything
    a window contributes (its blended and new frames) is in the stitched motion as it decodes on its own."""
    module, motion = long
    for before, after in pairwise(motion.windows):
        p = after.plan
        mine, previous = placed_joints(module, after), placed_joints(module, before)
        end = previous.shape[1] - p.blend  # window k's frames before the ones blended over
        assert np.abs(mine[:, : p.held] - previous[:, end - p.held : end]).max() <= TOL
        assert np.abs(mine[:, : p.held] - motion.joints[:, p.start - p.overlap : p.start - p.blend]).max() <= TOL
    for w, following in zip(motion.windows, [*motion.windows[1:], None], strict=True):
        p, cut = w.plan, following.plan.blend if following else 0  # the next window blends over the last frames
        mine = placed_joints(module, w)
        stitched = motion.joints[:, p.start - p.blend : p.end - cut]
        assert np.abs(mine[:, p.held : mine.shape[1] - cut] - stitched).max() <= TOL


def test_windows_are_generated_in_canonical_placement(long):
    """Each window starts where the training clips start: root at the x,z origin, facing +Z."""
    module, motion = long
    rep = module.representation
    for w in motion.windows[1:]:
        yaw, offset = placement(rep, w.features, 0)
        assert np.abs(np.angle(np.exp(1j * yaw))).max() < 1e-6 and np.abs(offset).max() < 1e-6


def test_boundary_report_names_every_seam(long):
    _, motion = long
    assert len(motion.boundaries) == 2  # one report per motion
    blend = motion.windows[1].plan.blend
    speeds = np.linalg.norm(np.diff(motion.joints, axis=1), axis=-1).mean(-1) * motion.fps
    for rows, speed in zip(motion.boundaries, speeds, strict=True):
        assert [r["frame"] for r in rows] == [30, 55, 80]
        assert [(r["before"], r["after"]) for r in rows] == [("a", "b"), ("b", "b"), ("b", "c")]
        # the fastest step the stitch touched, over the motion's median step
        assert [r["speed"] for r in rows] == [pytest.approx(speed[s - 1 - blend : s].max()) for s in (30, 55, 80)]
        assert all(r["ratio"] == pytest.approx(r["speed"] / np.median(speed)) for r in rows)


def test_boundary_report_by_hand():
    """A point moving 1 cm per frame, with a 5 cm jump into frame 3: step speeds 0.2 (x4) and 1.0 m/s at 20 fps."""
    x = np.array([0.0, 0.01, 0.02, 0.07, 0.08, 0.09])
    joints = np.stack([x, 0 * x, 0 * x], -1)[:, None, :]
    (row,) = boundary_report(joints, [3], fps=20)
    assert row["speed"] == pytest.approx(1.0) and row["median_speed"] == pytest.approx(0.2)
    assert row["ratio"] == pytest.approx(5.0) and row["seconds"] == pytest.approx(0.15)
    (blended,) = boundary_report(joints, [5], fps=20, blends=[2])  # steps 2→3, 3→4, 4→5: the jump is the fastest
    assert blended["speed"] == pytest.approx(1.0) and blended["frame"] == 5


def test_bad_requests_are_named():
    module = SimpleNamespace(
        hparams=SimpleNamespace(fps=20.0, max_frames=MAX_FRAMES),  # refused before sampling
        diffusion=SimpleNamespace(num_steps=1000),
    )
    with pytest.raises(ValueError, match="overlap must be positive"):
        generate_long(module, [(None, 1.0)], overlap_s=0)
    with pytest.raises(ValueError, match="segment 2 lasts -1"):
        generate_long(module, [(None, 1.0), (None, -1)])
    with pytest.raises(ValueError, match="overwrite, repaint"):
        generate_long(module, [(None, 1.0)], mode="paste")
