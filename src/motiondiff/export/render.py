"""Stick-figure animations (MP4 or GIF) of joint positions: left limbs blue and right limbs red with a legend saying
so, a ground grid, the root's trajectory trail, a camera that follows the root, and the prompt as the title.

A video is `size` pixels square (VIDEO_SIZE by default; video.size= in the commands). The figure is always
FIGURE_INCHES wide and its dots per inch follow the size, so lines and text, drawn in points, keep their share of
the frame at every size: a larger video is the same picture, sharper.

MP4 uses the ffmpeg binary bundled by the `imageio-ffmpeg` wheel (no system ffmpeg needed); GIF uses Pillow.
Files are written to a temporary name and renamed, so a failed render leaves nothing behind.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.errors import UsageError

# Left limbs blue, right limbs red, torso dark: the usual convention in motion papers.
_COLORS = {"left": "#1f77b4", "right": "#d62728", "torso": "#333333"}
VIDEO_SIZE = 720  # pixels, the side of a square video
MIN_VIDEO_SIZE, MAX_VIDEO_SIZE = 64, 2160  # below 64 nothing can be read; 2160 is 4K's height
FIGURE_INCHES = 4  # the figure's side; its dpi is size / FIGURE_INCHES


def _chain_color(chain: tuple[int, ...], skeleton: Skeleton) -> str:
    for side in ("left", "right"):
        limb = set(skeleton.parts.get(f"{side}_arm", ())) | set(skeleton.parts.get(f"{side}_leg", ()))
        if limb & set(chain[1:]):
            return _COLORS[side]
    return _COLORS["torso"]


Title = str | Sequence[tuple[int, str]]  # one title, or (first frame, title) per segment of a long motion


def stick_figure_animation(
    joints: np.ndarray, skeleton: Skeleton, title: Title = "", fps: float = 20.0, size: int = VIDEO_SIZE, step: int = 1
):
    """A matplotlib FuncAnimation of (N, J, 3) joints (metres, y up), ``size`` pixels square: every ``step``-th
    frame, ground grid, root trail, a head marker, a left/right colour legend. The camera follows the root at a fixed
    distance, so the body fills the frame however far it travels, and looks from the front-side of the travel
    direction (or of the facing when it stays in place), never along the line of motion. ``title``: one text, or
    (first frame, text) segments shown as they play. Show it in a notebook with
    ``IPython.display.HTML(anim.to_jshtml())``; its figure has its own canvas, outside pyplot (`video_axes`), so
    nothing needs closing and the notebook's own figures are untouched."""
    from matplotlib import animation

    fig, draw, frames = stick_frames(joints, skeleton, title, size, step)
    return animation.FuncAnimation(fig, draw, frames=frames, interval=1000 * max(1, int(step)) / fps)


def stick_frames(joints: np.ndarray, skeleton: Skeleton, title: Title = "", size: int = VIDEO_SIZE, step: int = 1):
    """(figure, draw(frame index), frame indices) of `stick_figure_animation`, for `save_frames`. The legend belongs
    to the figure, so clearing the axes each frame keeps it."""
    joints = np.asarray(joints, dtype=np.float64)
    if joints.ndim != 3 or joints.shape[1:] != (skeleton.num_joints, 3):
        raise ValueError(f"expected joints (frames, {skeleton.num_joints}, 3), got {joints.shape}")
    fig, ax = video_axes(size)
    side_legend(fig)
    trail = to_axes(joints[:, 0])[:, :2]
    half = follow_half(joints)
    azim = camera_azimuth(joints, skeleton)
    head = head_joint(skeleton)
    chains = [(c, _chain_color(c, skeleton)) for c in skeleton.kinematic_chains]

    def draw(i: int):
        ax.clear()
        follow(ax, azim, trail[i], half)
        text = title_at(title, i)
        if text:
            # a prompt is plain text: "$_$" is not mathtext
            ax.text2D(0.5, 0.97, wrap_title(text), transform=ax.transAxes, ha="center", va="top",
                      fontsize=TITLE_POINTS, parse_math=False)  # fmt: skip
        draw_ground(ax, trail, i, half)
        frame = to_axes(joints[i])
        for chain, color in chains:
            ax.plot(*frame[list(chain)].T, color=color, lw=LIMB_POINTS)
        if head is not None:
            ax.scatter(*frame[head], s=90, color=_COLORS["torso"], depthshade=False)
        return []

    return fig, draw, range(0, len(joints), max(1, int(step)))


LIMB_POINTS = 2.5  # limb line width: 6 pixels at 720, 2.8 at 320
TITLE_POINTS = 8.5  # the title's text: 21 pixels high at 720 (48 characters a line fit the frame)
LEGEND_POINTS = 8
GRID_COLOR, GRID_POINTS = "#dddddd", 0.8  # the ground grid: light, 2 pixels wide at 720
ELEVATION = 15  # degrees above the ground: low enough to read heights, high enough to see the ground trail
ZOOM = 1.35  # matplotlib's 3D box leaves wide margins at zoom 1
SIDE_ANGLE = 55  # degrees between the travel (or facing) direction and the camera: front-side, never edge-on


def to_axes(points: np.ndarray) -> np.ndarray:
    """Points (..., 3) in our frame (x, y up, z) as matplotlib's 3D axes take them: (x, -z, y), its x-y plane our
    ground and its z our up. z is negated because a plain swap (x, z, y) is a reflection: it drew every body mirrored,
    the left hand where the right one is (the camera in front of a body facing +z showed its left side on the left)."""
    points = np.asarray(points, dtype=np.float64)
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


def camera_azimuth(joints: np.ndarray, skeleton: Skeleton | None) -> float:
    """Azimuth (degrees in our x-z ground, from +x towards +z: the camera stands at (cos, sin) of it around the
    body; `follow` turns it into matplotlib's) of a camera SIDE_ANGLE off the direction the root (joint 0) travels, or, for motion that stays in place (< 0.5 m), off the direction the body faces in frame
    0 (+z when the skeleton is None or has no facing joints)."""
    travel = joints[-1, 0, [0, 2]] - joints[0, 0, [0, 2]]
    if np.linalg.norm(travel) >= 0.5:
        forward = travel
    elif skeleton is not None and skeleton.face_joints is not None:
        r_hip, l_hip, r_sho, l_sho = skeleton.face_joints
        across = joints[0, r_hip] - joints[0, l_hip] + joints[0, r_sho] - joints[0, l_sho]
        forward = np.cross([0.0, 1.0, 0.0], across)[[0, 2]]  # up x (right - left) = forward
    else:
        forward = np.array([0.0, 1.0])  # +z, the canonical facing
    return float(np.degrees(np.arctan2(forward[1], forward[0]))) + SIDE_ANGLE


def head_joint(skeleton: Skeleton) -> int | None:
    """The joint drawn as the head: the leaf that ends in a head, else the last joint of the head part."""
    roles = skeleton.leaf_roles or {}
    heads = [j for j, role in roles.items() if role == "head"] or list(skeleton.parts.get("head", ()))[-1:]
    return heads[0] if heads else None


def video_axes(size: int = VIDEO_SIZE):
    """A figure of ``size`` x ``size`` pixels (FIGURE_INCHES at size / FIGURE_INCHES dpi) filled by one 3D axes
    (matplotlib's x-y plane is our x-z ground, its z our y up). The figure has its own Agg canvas, outside pyplot:
    rendering never changes the caller's backend (a notebook's inline figures keep showing) and needs no display."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    size = check_video_size(size)
    fig = Figure(figsize=(FIGURE_INCHES, FIGURE_INCHES), dpi=size / FIGURE_INCHES)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=1)
    ax = fig.add_subplot(projection="3d")
    ax.set_box_aspect((1, 1, 1), zoom=ZOOM)
    return fig, ax


def side_legend(fig) -> None:
    """The key to the limb colours in the figure's lower left corner: a blue "left" line over a red "right" one."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=_COLORS[side], lw=LIMB_POINTS, label=side) for side in ("left", "right")]
    fig.legend(handles=handles, loc="lower left", fontsize=LEGEND_POINTS, handlelength=1.6, framealpha=0.85,
               edgecolor="#cccccc")  # fmt: skip


def check_video_size(size, name: str = "size") -> int:
    """``size`` as the side of a square video in pixels, else one UsageError naming the fix: a whole number from
    MIN_VIDEO_SIZE to MAX_VIDEO_SIZE, even (H.264 video needs even sides). ``name``: the setting as the user wrote it
    (video.size in the commands, video_size in the Python API)."""
    if (isinstance(size, bool) or not isinstance(size, numbers.Integral) or not MIN_VIDEO_SIZE <= size <= MAX_VIDEO_SIZE
            or size % 2):  # fmt: skip
        raise UsageError(f"{name}={size!r}: the video's side in pixels must be an even whole number from "
                         f"{MIN_VIDEO_SIZE} to {MAX_VIDEO_SIZE}; fix it with e.g. {name}={VIDEO_SIZE}")  # fmt: skip
    return int(size)


def follow_half(points: np.ndarray) -> float:
    """Half the side of the cube the camera follows, for points (N, P, 3) (joints or a mesh's vertices, y up):
    the body's tallest extent above the ground (or its lowest point) fills it."""
    height = float((points[..., 1].max(axis=1) - np.minimum(points[..., 1].min(axis=1), 0)).max())
    return max(0.6, 0.55 * height)


def follow(ax, azim: float, centre: np.ndarray, half: float) -> None:
    """Point the camera (ELEVATION, our azimuth `azim`) at the cube of half side `half` around the ground point
    `centre` in the axes' x-y plane (`to_axes`; matplotlib's azimuth runs towards its y, our -z, hence -azim)."""
    ax.set_axis_off()
    ax.view_init(elev=ELEVATION, azim=-azim)
    cx, cz = centre
    ax.set_xlim(cx - half, cx + half)
    ax.set_ylim(cz - half, cz + half)
    ax.set_zlim(0, 2 * half)


def draw_ground(ax, trail: np.ndarray, i: int, half: float, zorder: float | None = None) -> list:
    """The world-fixed ground grid around frame `i`'s root and the root's trail (N, 2) so far; returns the lines."""
    cx, cz = trail[i]
    extra = {} if zorder is None else {"zorder": zorder}
    lines = []
    for g in np.arange(np.floor(cx - half), np.ceil(cx + half) + 0.25, 0.5):
        lines += ax.plot([g, g], [cz - half, cz + half], [0, 0], color=GRID_COLOR, lw=GRID_POINTS, **extra)
    for g in np.arange(np.floor(cz - half), np.ceil(cz + half) + 0.25, 0.5):
        lines += ax.plot([cx - half, cx + half], [g, g], [0, 0], color=GRID_COLOR, lw=GRID_POINTS, **extra)
    lines += ax.plot(trail[: i + 1, 0], trail[: i + 1, 1], np.zeros(i + 1), color="#ff9900", lw=1.5, **extra)
    return lines


def title_at(title: Title, frame: int) -> str:
    if isinstance(title, str):
        return title
    current = ""
    for start, text in title:
        if frame >= start:
            current = text
    return current


def render_motion(
    joints: np.ndarray,
    skeleton: Skeleton,
    path: str | Path,
    title: Title = "",
    fps: float = 20.0,
    size: int = VIDEO_SIZE,
    frame_step: int = 1,
) -> Path:
    """Animate (N, J, 3) joints (metres, y up) to `path` (.mp4 or .gif), ``size`` pixels square, every
    ``frame_step``-th frame (played at the motion's own speed)."""
    path = check_video_path(path)
    size = check_video_size(size)
    frame_step = max(1, int(frame_step))
    quiet_matplotlib()
    return save_frames(*stick_frames(joints, skeleton, title, size, frame_step), path, fps / frame_step)


def check_video_path(path: str | Path) -> Path:
    """`path` as a Path when it names a .mp4 or .gif file in an existing folder; ValueError (or NotADirectoryError)
    before anything is drawn otherwise."""
    path = Path(path)
    if path.suffix.lower() not in (".mp4", ".gif"):
        raise ValueError(f"cannot render to {path.name}: use a .mp4 or .gif file name")
    if not path.parent.is_dir():
        raise NotADirectoryError(f"cannot write {path}: the folder {path.parent} does not exist")
    return path


def quiet_matplotlib() -> None:
    """No INFO line for every saved animation (the figures have their own Agg canvas: `video_axes`)."""
    import logging

    logging.getLogger("matplotlib.animation").setLevel(logging.WARNING)


def save_frames(fig, draw, frames, path: Path, fps: float) -> Path:
    """Write the figure after `draw(i)` for each of `frames` to `path` (.mp4 or .gif) at `fps` frames per second and
    at the figure's own pixel size (`video_axes`), atomically, and close the figure. Each frame is drawn once
    (FuncAnimation.save draws each twice)."""
    import matplotlib

    writer = _writer(path.suffix.lower(), fps)

    def write(tmp):
        with matplotlib.rc_context({"savefig.bbox": None}), writer.saving(fig, tmp, fig.dpi):
            for i in frames:
                draw(i)
                writer.grab_frame()

    try:
        atomic_write(path, write, suffix=path.suffix.lower())
    finally:
        fig.clear()  # the figure is no pyplot figure: nothing else holds it once its artists go
    return path


def _writer(suffix: str, fps: float):
    from matplotlib import animation, rcParams

    if suffix == ".gif":
        return animation.PillowWriter(fps=fps)
    import imageio_ffmpeg

    rcParams["animation.ffmpeg_path"] = imageio_ffmpeg.get_ffmpeg_exe()
    return animation.FFMpegWriter(fps=fps, codec="libx264", extra_args=["-pix_fmt", "yuv420p"])


def wrap_title(text: str, width: int = 48) -> str:
    """The title in lines of at most `width` characters (words kept whole)."""
    words, lines, line = text.split(), [], ""
    for w in words:
        if len(line) + len(w) + 1 > width and line:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}".strip()
    return "\n".join(lines + [line] if line else lines)
