"""Stick-figure animations (MP4 or GIF) of joint positions, with a ground grid and the root's trajectory trail.

MP4 uses the ffmpeg binary bundled by the `imageio-ffmpeg` wheel (no system ffmpeg needed); GIF uses Pillow.
Files are written to a temporary name and renamed, so a failed render leaves nothing behind.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motiondiff.atomic import atomic_write
from motiondiff.skeleton import Skeleton

# Left limbs blue, right limbs red, torso dark: the usual convention in motion papers.
_COLORS = {"left": "#1f77b4", "right": "#d62728", "torso": "#333333"}


def _chain_color(chain: tuple[int, ...], skeleton: Skeleton) -> str:
    for side in ("left", "right"):
        limb = set(skeleton.parts.get(f"{side}_arm", ())) | set(skeleton.parts.get(f"{side}_leg", ()))
        if limb & set(chain[1:]):
            return _COLORS[side]
    return _COLORS["torso"]


def stick_figure_animation(
    joints: np.ndarray, skeleton: Skeleton, title: str = "", fps: float = 20.0, dpi: int = 80, step: int = 1
):
    """A matplotlib FuncAnimation of (N, J, 3) joints (metres, y up): every ``step``-th frame, ground grid, root
    trail. Show it in a notebook with ``IPython.display.HTML(anim.to_jshtml())``; close its figure when done
    (``plt.close(anim._fig)``)."""
    import matplotlib.pyplot as plt
    from matplotlib import animation

    joints = np.asarray(joints, dtype=np.float64)
    if joints.ndim != 3 or joints.shape[1:] != (skeleton.num_joints, 3):
        raise ValueError(f"expected joints (frames, {skeleton.num_joints}, 3), got {joints.shape}")
    fig = plt.figure(figsize=(4, 4), dpi=dpi)
    ax = fig.add_subplot(projection="3d")
    trail = joints[:, 0, [0, 2]]
    lo, hi = joints.reshape(-1, 3).min(0), joints.reshape(-1, 3).max(0)
    centre = (lo + hi) / 2
    radius = max(1.0, float((hi - lo)[[0, 2]].max()) / 2 + 0.3)
    chains = [(c, _chain_color(c, skeleton)) for c in skeleton.kinematic_chains]

    def draw(i: int):
        ax.clear()
        ax.set_title(_wrap(title), fontsize=8)
        ax.set_xlim(centre[0] - radius, centre[0] + radius)
        ax.set_ylim(centre[2] - radius, centre[2] + radius)
        ax.set_zlim(0, max(2.0, hi[1] + 0.1))
        ax.set_axis_off()
        ax.view_init(elev=20, azim=-60)
        grid = np.arange(np.floor(centre[0] - radius), np.ceil(centre[0] + radius) + 0.5, 0.5)
        grid_z = np.arange(np.floor(centre[2] - radius), np.ceil(centre[2] + radius) + 0.5, 0.5)
        for g in grid:  # ground grid (matplotlib's y is our z: the ground is its x-y plane)
            ax.plot([g, g], [grid_z[0], grid_z[-1]], [0, 0], color="#dddddd", lw=0.5)
        for g in grid_z:
            ax.plot([grid[0], grid[-1]], [g, g], [0, 0], color="#dddddd", lw=0.5)
        ax.plot(trail[: i + 1, 0], trail[: i + 1, 1], np.zeros(i + 1), color="#ff9900", lw=1.5)
        frame = joints[i]
        for chain, color in chains:
            ax.plot(frame[list(chain), 0], frame[list(chain), 2], frame[list(chain), 1], color=color, lw=2.5)
        return []

    frames = range(0, len(joints), max(1, int(step)))
    return animation.FuncAnimation(fig, draw, frames=frames, interval=1000 * max(1, int(step)) / fps)


def render_motion(
    joints: np.ndarray,
    skeleton: Skeleton,
    path: str | Path,
    title: str = "",
    fps: float = 20.0,
    dpi: int = 80,
    frame_step: int = 1,
) -> Path:
    """Animate (N, J, 3) joints (metres, y up) to `path` (.mp4 or .gif): a 4-inch square figure of ``4 * dpi``
    pixels, every ``frame_step``-th frame (played at the motion's own speed)."""
    import logging

    import matplotlib

    matplotlib.use("Agg")
    logging.getLogger("matplotlib.animation").setLevel(logging.WARNING)  # it logs every save at INFO
    import matplotlib.pyplot as plt

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".mp4", ".gif"):
        raise ValueError(f"cannot render to {path.name}: use a .mp4 or .gif file name")
    if not path.parent.is_dir():
        raise NotADirectoryError(f"cannot write {path}: the folder {path.parent} does not exist")
    frame_step = max(1, int(frame_step))
    anim = stick_figure_animation(joints, skeleton, title, fps, dpi, frame_step)
    writer = _writer(suffix, fps / frame_step)
    try:
        atomic_write(path, lambda tmp: anim.save(tmp, writer=writer, dpi=dpi), suffix=suffix)
    finally:
        plt.close(anim._fig)
    return path


def _writer(suffix: str, fps: float):
    from matplotlib import animation, rcParams

    if suffix == ".gif":
        return animation.PillowWriter(fps=fps)
    import imageio_ffmpeg

    rcParams["animation.ffmpeg_path"] = imageio_ffmpeg.get_ffmpeg_exe()
    return animation.FFMpegWriter(fps=fps, codec="libx264", extra_args=["-pix_fmt", "yuv420p"])


def _wrap(text: str, width: int = 48) -> str:
    words, lines, line = text.split(), [], ""
    for w in words:
        if len(line) + len(w) + 1 > width and line:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}".strip()
    return "\n".join(lines + [line] if line else lines)
