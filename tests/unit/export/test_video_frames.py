"""Default videos (issue 42): 720 pixels square unless a size is asked (video.size= in the commands, video_size= in
the API), and every frame shows the left/right colour legend and the ground grid. Sizes are read back from the
written files (imageio-ffmpeg's reader, Pillow for GIFs); the legend and grid from the figure and from its pixels."""

from __future__ import annotations

import imageio_ffmpeg
import numpy as np
import pytest
from fixtures.synthetic_motion import glide
from matplotlib.colors import to_rgb
from omegaconf import OmegaConf
from PIL import Image

from motiondiff.cli.outputs import video_size
from motiondiff.data.representations import get_representation
from motiondiff.export import export_motion
from motiondiff.export import render as render_module
from motiondiff.export.render import _COLORS, GRID_COLOR, VIDEO_SIZE, render_motion, stick_frames
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import CONF_DIR


def mp4_frames(path) -> tuple[tuple[int, int], list[np.ndarray]]:
    """(width, height) and the RGB frames of an MP4, decoded by the ffmpeg that wrote it."""
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in reader]
    return (width, height), frames


def strongly(image: np.ndarray, side: str) -> np.ndarray:
    """Pixels of an RGB image (0..255) clearly of the limb colour of `side`: red well above green and blue (right),
    blue well above red (left). H.264's 4:2:0 colour rounding moves thin strokes' colours too far for a match."""
    r, g, b = np.moveaxis(image[..., :3].astype(int), -1, 0)
    return r - np.maximum(g, b) > 80 if side == "right" else b - r > 80


def legend_corner(image: np.ndarray) -> np.ndarray:
    """The lower left corner (a quarter of the width, a sixth of the height), where the legend is drawn."""
    h, w = image.shape[:2]
    return image[h - h // 6 :, : w // 4]


def test_a_default_mp4_is_720_pixels_square_in_every_frame(tmp_path):
    path = render_motion(glide(0, 1.0, frames=3), SMPL22, tmp_path / "m.mp4", title="a person walks")
    size, frames = mp4_frames(path)
    assert VIDEO_SIZE == 720 and size == (720, 720)
    assert len(frames) == 3 and all(f.shape == (720, 720, 3) for f in frames)


def test_the_size_switch_sets_the_side_of_mp4_and_gif(tmp_path):
    joints = glide(0, 1.0, frames=3)
    assert mp4_frames(render_motion(joints, SMPL22, tmp_path / "m.mp4", size=320))[0] == (320, 320)
    gif = Image.open(render_motion(joints, SMPL22, tmp_path / "m.gif", size=160))
    assert gif.size == (160, 160) and gif.n_frames == 3
    paths = export_motion(tmp_path / "e", joints, SMPL22, 20, ["mp4"], video_size=240)  # the API's keyword
    assert mp4_frames(paths["mp4"])[0] == (240, 240)


@pytest.mark.parametrize("size", [63, 2162, 721, 720.0, True, "720"])
def test_a_size_no_video_can_have_is_refused_before_drawing(tmp_path, size):
    with pytest.raises(UsageError, match=r"size=.*even whole number from 64 to 2160; fix it with e.g. size=720"):
        render_motion(glide(0, 1.0, frames=3), SMPL22, tmp_path / "m.mp4", size=size)
    assert list(tmp_path.iterdir()) == []


def test_the_commands_video_size_defaults_to_720_and_is_checked_before_sampling():
    for command in ("sample", "edit"):  # the switch every command that writes videos has
        assert OmegaConf.load(CONF_DIR / f"{command}.yaml").video.size == VIDEO_SIZE
    assert video_size(OmegaConf.create({"video": {"size": 320}})) == 320
    assert video_size(OmegaConf.create({})) == VIDEO_SIZE  # a config written before the switch
    with pytest.raises(UsageError, match=r"^video\.size=721: .* fix it with e\.g\. video\.size=720$"):
        video_size(OmegaConf.create({"video": {"size": 721}}))


def test_motion_output_save_takes_the_size_and_refuses_a_bad_one_before_writing(tmp_path):
    joints = glide(0, 1.0, frames=3).astype(np.float32)
    rep = get_representation("hml263", SMPL22)
    out = MotionOutput(
        [joints], [np.zeros((3, rep.dim))], ["a person walks"], 20.0, SMPL22, rep, {"joints_changed": True}
    )
    (row,) = out.save(tmp_path / "small", formats=["mp4"], video_size=160)
    assert mp4_frames(row["video"])[0] == (160, 160)
    with pytest.raises(UsageError, match="video_size=100.5"):
        out.save(tmp_path / "bad", formats=["mp4"], video_size=100.5)
    assert not (tmp_path / "bad").exists()


def test_every_frame_has_the_left_right_legend_in_the_limb_colours():
    fig, draw, frames = stick_frames(glide(0, 1.0, frames=4), SMPL22, "a person walks", size=320)
    for i in frames:
        draw(i)  # the axes are cleared each frame: the legend is the figure's
        (legend,) = fig.legends
        assert [t.get_text() for t in legend.get_texts()] == ["left", "right"]
        assert [line.get_color() for line in legend.get_lines()] == [_COLORS["left"], _COLORS["right"]]


def test_the_written_mp4_shows_the_legend_colours_in_its_corner(tmp_path):
    path = render_motion(glide(0, 1.0, frames=2), SMPL22, tmp_path / "m.mp4", title="a person walks")
    for frame in mp4_frames(path)[1]:
        corner = legend_corner(frame)
        for side in ("left", "right"):  # the legend's two strokes (about 200 pixels each)
            assert strongly(corner, side).sum() > 100, side


def grid_pixels() -> int:
    """Light grey pixels (the grid's grey, or it on white) of a rendered 320-pixel frame, outside the legend."""
    fig, draw, _ = stick_frames(glide(0, 2.0, frames=10), SMPL22, "", size=320)
    draw(5)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    legend_corner(image)[:] = 255
    grey, chroma = image.mean(-1), image.max(-1) - image.min(-1)
    darkest = 255 * to_rgb(GRID_COLOR)[0]
    return int(((chroma < 6) & (grey > darkest - 30) & (grey < 248)).sum())


def test_the_ground_grid_is_drawn_around_the_root(monkeypatch):
    fig, draw, _ = stick_frames(glide(0, 2.0, frames=10), SMPL22, "", size=320)
    draw(5)
    (ax,) = fig.axes
    grid = [line for line in ax.get_lines() if line.get_color() == GRID_COLOR]
    assert len(grid) >= 6  # lines every half metre both ways across the followed cube
    assert all(np.allclose(line.get_data_3d()[2], 0) for line in grid)  # on the ground
    with_grid = grid_pixels()
    monkeypatch.setattr(render_module, "draw_ground", lambda *args, **kwargs: [])
    assert with_grid > 1000 and grid_pixels() < with_grid / 10  # the grey pixels are the grid's
