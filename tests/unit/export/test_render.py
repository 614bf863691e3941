"""The stick-figure videos frame the body: it fills most of the frame however far it travels, the camera looks
from the front-side of the travel (never along it), the head is marked, and a long motion's title follows the
segment playing."""

from __future__ import annotations

import io

import matplotlib
import numpy as np
import pytest
from fixtures.synthetic_motion import glide, rest_pose

from motiondiff.export.render import (
    SIDE_ANGLE,
    camera_azimuth,
    head_joint,
    render_motion,
    stick_figure_animation,
    title_at,
)
from motiondiff.geometry.skeleton import SMPL22

matplotlib.use("Agg")
LIMB_COLOURS = ((0x1F, 0x77, 0xB4), (0xD6, 0x27, 0x28), (0x33, 0x33, 0x33))


def limb_pixels(joints: np.ndarray, frame: int) -> dict[tuple, np.ndarray]:
    """Per limb colour, the mask of its pixels in one rendered frame (the legend's corner, in the limb colours too,
    left out)."""
    import matplotlib.pyplot as plt

    anim = stick_figure_animation(joints, SMPL22, size=320)
    anim._func(frame)
    buf = io.BytesIO()
    anim._fig.savefig(buf, format="png", dpi=anim._fig.dpi)
    legend = anim._fig.legends[0].get_window_extent()  # pixels from the lower left
    plt.close(anim._fig)
    buf.seek(0)
    image = plt.imread(buf)[..., :3].copy()
    image[image.shape[0] - int(np.ceil(legend.y1)) :, : int(np.ceil(legend.x1))] = 1.0
    return {colour: np.abs(image - np.array(colour) / 255).max(-1) < 0.12 for colour in LIMB_COLOURS}


def body_fill(joints: np.ndarray, frame: int) -> float:
    """Height of the box around the limb-coloured pixels of one rendered frame / the frame's height."""
    mask = np.any(list(limb_pixels(joints, frame).values()), axis=0)
    rows = np.where(mask.any(1))[0]
    return (rows[-1] - rows[0] + 1) / mask.shape[0]


def test_the_picture_is_not_mirrored():
    """A body facing +z with its left arm (blue) held out sideways, seen from its front side: the left arm is on
    the picture's right, as a camera (not a mirror) shows it. A plain (x, z, y) axis swap drew it on the left."""
    pose = rest_pose()
    shoulder = pose[16]
    pose[18], pose[20] = shoulder + [0.3, 0.0, 0.0], shoulder + [0.55, 0.0, 0.0]  # l_elbow, l_wrist out along +x
    left, right = (limb_pixels(np.repeat(pose[None], 3, axis=0), 0)[c] for c in LIMB_COLOURS[:2])
    columns = np.arange(left.shape[1])
    assert (left.sum(0) @ columns) / left.sum() > (right.sum(0) @ columns) / right.sum() + 20


@pytest.mark.parametrize("metres", [0.0, 4.0])
def test_the_body_fills_most_of_the_frame_at_the_start_and_the_end(metres):
    joints = glide(0, metres, frames=40)
    assert min(body_fill(joints, 0), body_fill(joints, 39)) > 0.6  # a fixed camera on a 4 m walk gave about 0.3


@pytest.mark.parametrize("direction", [0, 90, 200])
def test_the_camera_is_front_side_of_the_travel_and_of_the_facing(direction):
    walk = glide(direction, 3.0)
    travel = np.degrees(np.arctan2(*(walk[-1, 0, [2, 0]] - walk[0, 0, [2, 0]])))  # matplotlib's x-y = our x-z
    assert (camera_azimuth(walk, SMPL22) - travel) % 360 == pytest.approx(SIDE_ANGLE)
    standing = np.repeat(rest_pose()[None], 10, axis=0)  # faces +z: matplotlib's 90 degrees
    assert camera_azimuth(standing, SMPL22) % 360 == pytest.approx(90 + SIDE_ANGLE)


def test_the_head_is_marked():
    import matplotlib.pyplot as plt
    from matplotlib.collections import PathCollection

    assert SMPL22.joint_names[head_joint(SMPL22)] == "head"
    anim = stick_figure_animation(glide(0, 1.0, frames=5), SMPL22)
    anim._func(2)
    markers = [c for c in anim._fig.axes[0].collections if isinstance(c, PathCollection)]
    plt.close(anim._fig)
    assert len(markers) == 1


def test_a_long_motion_title_follows_the_segment(tmp_path):
    segments = [(0, "a person walks"), (20, "a person waves")]
    assert [title_at(segments, i) for i in (0, 19, 20, 39)] == ["a person walks"] * 2 + ["a person waves"] * 2
    assert title_at("one prompt", 7) == "one prompt"
    path = render_motion(glide(0, 1.0, frames=40), SMPL22, tmp_path / "long.gif", title=segments, fps=20, size=120)
    from PIL import Image

    assert Image.open(path).n_frames == 40
