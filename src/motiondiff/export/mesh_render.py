"""Shaded body-mesh videos (MP4 or GIF): the mesh counterpart of render.py's stick figures, with the same camera
(it follows the root from the front-side of the travel), ground grid, root trail, titles and video writers.

matplotlib draws the mesh as one Poly3DCollection whose triangles and colours are replaced every frame (it sorts them
back to front itself). Each face is shaded by Lambert's law from its normal under a light above and beside the
camera, two-sided, so a mesh's winding does not matter. No OpenGL or GPU: it runs wherever the stick videos do, at
a fraction of a second per frame for an SMPL-sized mesh (`frame_step` draws every k-th frame).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motiondiff.export.render import (
    VIDEO_SIZE,
    Title,
    camera_azimuth,
    check_video_path,
    draw_ground,
    follow,
    follow_half,
    quiet_matplotlib,
    save_frames,
    title_at,
    to_axes,
    video_axes,
    wrap_title,
)
from motiondiff.geometry.skeleton import Skeleton

BODY_RGB = np.array([0.80, 0.80, 0.82])  # light gray, darker than the ground grid wherever it is lit
AMBIENT = 0.3  # the share of the light that faces turned away from it still get
LIGHT_ELEVATION = 50  # degrees above the ground
LIGHT_SIDE = -30  # degrees of azimuth off the camera's: the body's side towards the light is lit, the other shaded


def light_direction(azim: float) -> np.ndarray:
    """Unit vector (our x, y up, z) towards the light, for a camera at azimuth `azim` (degrees in our ground,
    `render.camera_azimuth`)."""
    e, a = np.radians(LIGHT_ELEVATION), np.radians(azim + LIGHT_SIDE)
    return np.array([np.cos(e) * np.cos(a), np.sin(e), np.cos(e) * np.sin(a)])


def shade(triangles: np.ndarray, light: np.ndarray) -> np.ndarray:
    """RGB (F, 3) of triangles (F, 3, 3): BODY_RGB x (AMBIENT + (1 - AMBIENT) |cos| of the normal to `light`);
    degenerate triangles get the ambient share."""
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    cosine = np.abs(normals @ light) / np.maximum(np.linalg.norm(normals, axis=-1), 1e-12)
    return BODY_RGB * (AMBIENT + (1 - AMBIENT) * cosine)[:, None]


def mesh_frames(
    vertices: np.ndarray,
    faces: np.ndarray,
    title: Title = "",
    size: int = VIDEO_SIZE,
    step: int = 1,
    *,
    joints: np.ndarray | None = None,
    skeleton: Skeleton | None = None,
):
    """(figure, draw(frame index), frame indices) for render.save_frames: meshes (N, V, 3) (metres, y up) with
    triangles `faces` (F, 3), every ``step``-th frame. The camera follows joint 0 of `joints` (N, J, 3) and looks as
    render.py's does for that `skeleton`; without joints it follows the mesh's centroid. The body is one
    Poly3DCollection whose triangles and colours each frame replaces; the ground lines are redrawn around the root."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    vertices, faces = _checked(vertices, faces)
    if joints is not None and (np.ndim(joints) != 3 or len(joints) != len(vertices)):
        raise ValueError(f"joints must be (frames, J, 3) for the {len(vertices)} meshes, got {np.shape(joints)}")
    followed = vertices.mean(axis=1, keepdims=True) if joints is None else np.asarray(joints, dtype=np.float64)
    trail = to_axes(followed[:, 0])[:, :2]
    half = follow_half(vertices)
    azim = camera_azimuth(followed, skeleton if joints is not None else None)
    light = light_direction(azim)
    fig, ax = video_axes(size)
    ax.computed_zorder = False  # the ground, then the trail, then the body: the floor never covers the feet
    body = Poly3DCollection(np.zeros((0, 3, 3)), linewidths=0.3, zorder=3)  # edges in the face colour: no seams
    ax.add_collection3d(body)
    label = ax.text2D(0.5, 0.97, "", transform=ax.transAxes, ha="center", va="top", fontsize=8, parse_math=False)
    ground: list = []

    def draw(i: int):
        for line in ground:
            line.remove()
        follow(ax, azim, trail[i], half)
        ground[:] = draw_ground(ax, trail, i, half, zorder=1)
        triangles = vertices[i][faces]
        colours = shade(triangles, light)
        body.set_verts(to_axes(triangles))
        body.set_facecolor(colours)
        body.set_edgecolor(colours)
        label.set_text(wrap_title(title_at(title, i)))
        return []

    return fig, draw, range(0, len(vertices), max(1, int(step)))


def render_mesh(
    vertices: np.ndarray,
    faces: np.ndarray,
    path: str | Path,
    title: Title = "",
    fps: float = 20.0,
    frame_step: int = 1,
    *,
    joints: np.ndarray | None = None,
    skeleton: Skeleton | None = None,
    size: int = VIDEO_SIZE,
) -> Path:
    """Animate meshes (N, V, 3) (metres, y up; triangles `faces` (F, 3)) to `path` (.mp4 or .gif): a shaded light
    gray body, ``size`` pixels square (render.video_axes), every ``frame_step``-th frame at the motion's own
    speed. ``joints``/``skeleton``: the motion, whose root the camera follows (`mesh_frames`)."""
    path = check_video_path(path)
    frame_step = max(1, int(frame_step))
    quiet_matplotlib()
    frames = mesh_frames(vertices, faces, title, size, frame_step, joints=joints, skeleton=skeleton)
    return save_frames(*frames, path, fps / frame_step)


def _checked(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = np.asarray(vertices, dtype=np.float64), np.asarray(faces)
    if vertices.ndim != 3 or vertices.shape[2] != 3 or len(vertices) == 0 or not np.isfinite(vertices).all():
        raise ValueError(f"vertices must be finite with shape (frames, V, 3), got {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu" or len(faces) == 0:
        raise ValueError(f"faces must be whole-number vertex indices with shape (F, 3), got {faces.shape}")
    if faces.min() < 0 or faces.max() >= vertices.shape[1]:
        raise ValueError(f"faces index vertices 0..{vertices.shape[1] - 1}, got {faces.min()}..{faces.max()}")
    return vertices, faces
