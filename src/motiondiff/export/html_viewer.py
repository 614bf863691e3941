"""A self-contained interactive 3D viewer (one HTML file, plotly.js inline, works offline) of joint positions:
bones per kinematic chain (left blue, right red, torso dark, as in the videos), a ground grid, the root's
trajectory trail on the floor with the current root marked, Play/Pause and a frame slider. Axis ranges are fixed
over the motion so the camera never jumps, and y (up) is drawn vertical. Opening `viewer.html#frame=K` shows
frame K (deep links, and what tests screenshot).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from motiondiff.export.render import Title, _chain_color, camera_azimuth, head_joint, title_at
from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write

__all__ = ["export_html"]

_GRID_STEP = 0.5  # metres between ground grid lines, as in the videos
_GRID_COLOR, _TRAIL_COLOR, _HEAD_COLOR = "#bbbbbb", "#ff9900", "#333333"

# Runs after the plot and its frames exist: jump to the frame in the URL hash ('#frame=K'), now and on changes.
_DEEP_LINK_JS = """
var gd = document.getElementById('{plot_id}');
function frameFromHash() {
  var m = /frame=(\\d+)/.exec(window.location.hash);
  return m ? Math.min(parseInt(m[1], 10), LAST_FRAME) : null;
}
function showFrame(k) {
  if (k === null) return;
  Plotly.animate(gd, [String(k)], {mode: 'immediate', frame: {duration: 0, redraw: true}, transition: {duration: 0}})
    .then(function () { return Plotly.relayout(gd, {'sliders[0].active': k}); });
}
showFrame(frameFromHash());
window.addEventListener('hashchange', function () { showFrame(frameFromHash()); });
"""


def export_html(
    path: str | os.PathLike,
    joints: np.ndarray,
    skeleton: Skeleton,
    fps: float,
    title: Title = "",
    *,
    trail: bool = True,
) -> Path:
    """Write an interactive viewer of joints (N, J, 3) (metres, y up) to `path` (.html), atomically. The camera
    starts front-side of the travel direction (as the videos); ``title``: one text, or (first frame, text)
    segments shown as the motion plays."""
    import plotly.io as pio

    path = Path(path)
    joints = check_motion(joints, skeleton, fps, "export_html")
    if not path.parent.is_dir():
        raise NotADirectoryError(f"cannot write {path}: the folder {path.parent} does not exist")

    chains = [(list(c), _chain_color(c, skeleton)) for c in skeleton.kinematic_chains]
    ranges, aspect = _fixed_ranges(joints)
    shown = np.round(joints, 4)  # 0.1 mm is plenty on screen and keeps the file small
    on_ground = shown[:, 0] * np.array([1.0, 0.0, 1.0])  # the root's path, drawn on the floor
    # The whole trail is one static trace (a growing trail would store O(N^2) points); each frame marks the root
    # on it, so the file grows linearly with the motion's length.
    static = [_grid(ranges)] + ([_trace(on_ground, "lines", _TRAIL_COLOR, 3, "trail")] if trail else [])

    head = [j for j in [head_joint(skeleton)] if j is not None]

    def moving_traces(i: int) -> list[dict]:
        bones = [_trace(shown[i, chain], "lines", color, 6, f"chain {k}") for k, (chain, color) in enumerate(chains)]
        return [*bones, _trace(on_ground[i : i + 1], "markers", _TRAIL_COLOR, 4, "root"),
                _trace(shown[i, head], "markers", _HEAD_COLOR, 9, "head")]  # fmt: skip

    def frame(i: int) -> dict:
        shown_frame = {"name": str(i), "data": moving_traces(i), "traces": moving}
        if not isinstance(title, str):  # a long motion: the title follows the segment playing
            shown_frame["layout"] = {"title": {"text": title_at(title, i), "x": 0.5}}
        return shown_frame

    moving = list(range(len(static), len(static) + len(chains) + 2))  # frames update these traces only
    azim = np.radians(camera_azimuth(joints, skeleton))  # matplotlib's azimuth: its x-y plane is our x-z ground
    figure = {
        "data": [*static, *moving_traces(0)],
        "frames": [frame(i) for i in range(len(joints))],
        "layout": {
            "title": {"text": title_at(title, 0), "x": 0.5},
            "showlegend": False,
            "margin": {"l": 0, "r": 0, "t": 40 if title else 10, "b": 0},
            "paper_bgcolor": "white",
            "scene": {
                **{f"{axis}axis": _axis(axis, r) for axis, r in zip("xyz", ranges, strict=True)},
                "aspectmode": "manual",
                "aspectratio": dict(zip("xyz", aspect, strict=True)),
                "camera": {
                    "up": {"x": 0, "y": 1, "z": 0},
                    "eye": {"x": 2.0 * np.cos(azim), "y": 0.7, "z": 2.0 * np.sin(azim)},
                },
            },
            "uirevision": "keep",  # animating must not reset a camera the user has turned
            "updatemenus": [_play_pause(fps)],
            "sliders": [_slider(len(joints), fps)],
        },
    }
    html = pio.to_html(
        figure,
        validate=False,  # plain dicts of known-good keys: plotly's per-frame validation is most of the time
        include_plotlyjs=True,  # inline, so the file works offline and alone
        full_html=True,
        auto_play=False,
        post_script=_DEEP_LINK_JS.replace("LAST_FRAME", str(len(joints) - 1)),
        config={"displaylogo": False, "responsive": True},
    )
    return atomic_write(path, lambda tmp: Path(tmp).write_text(html, encoding="utf-8"), suffix=".html")


def _trace(points: np.ndarray, mode: str, color: str, size: float, name: str) -> dict:
    """A scatter3d trace of points (K, 3): a polyline (mode 'lines', size = width) or dots ('markers')."""
    style = {"line": {"color": color, "width": size}} if mode == "lines" else {"marker": {"color": color, "size": size}}
    return {"type": "scatter3d", "x": points[:, 0], "y": points[:, 1], "z": points[:, 2], "mode": mode,
            "name": name, "hoverinfo": "skip", **style}  # fmt: skip


def _axis(name: str, value_range: tuple[float, float]) -> dict:
    """A fixed axis without plotly's grey walls (the ground grid is drawn instead), ticks kept for scale."""
    return {"range": list(value_range), "autorange": False, "title": name, "showbackground": False,
            "showgrid": False, "zeroline": False, "showspikes": False}  # fmt: skip


def _fixed_ranges(joints: np.ndarray) -> tuple[list[tuple[float, float]], list[float]]:
    """x/z ranges: a square around the whole motion (at least 2 m wide); y: from the floor (or the lowest joint)
    to above the highest. The aspect ratio follows the ranges so a metre is a metre on every axis."""
    lo, hi = joints.reshape(-1, 3).min(0), joints.reshape(-1, 3).max(0)
    centre = (lo + hi) / 2
    radius = max(1.0, float((hi - lo)[[0, 2]].max()) / 2 + 0.3)
    y_range = (min(0.0, float(lo[1])) - 0.05, max(2.0, float(hi[1]) + 0.1))
    ranges = [(centre[0] - radius, centre[0] + radius), y_range, (centre[2] - radius, centre[2] + radius)]
    spans = np.array([r[1] - r[0] for r in ranges])
    return [(float(a), float(b)) for a, b in ranges], list(spans / spans.max())


def _grid(ranges) -> dict:
    """Ground grid lines (y = 0) every _GRID_STEP metres, one trace (None breaks the lines)."""
    (x0, x1), _, (z0, z1) = ranges
    xs = np.arange(np.ceil(x0 / _GRID_STEP), np.floor(x1 / _GRID_STEP) + 1) * _GRID_STEP
    zs = np.arange(np.ceil(z0 / _GRID_STEP), np.floor(z1 / _GRID_STEP) + 1) * _GRID_STEP
    segments = [((x, z0), (x, z1)) for x in xs] + [((x0, z), (x1, z)) for z in zs]
    x, y, z = [], [], []
    for (ax, az), (bx, bz) in segments:
        x += [ax, bx, None]
        y += [0.0, 0.0, None]
        z += [az, bz, None]
    return {"type": "scatter3d", "x": x, "y": y, "z": z, "mode": "lines", "name": "ground", "hoverinfo": "skip",
            "line": {"color": _GRID_COLOR, "width": 2}}  # fmt: skip


def _animate_args(duration: float) -> dict:
    return {"mode": "immediate", "frame": {"duration": duration, "redraw": True}, "transition": {"duration": 0}}


def _play_pause(fps: float) -> dict:
    play = {**_animate_args(1000.0 / fps), "fromcurrent": True}
    return {
        "type": "buttons",
        "direction": "left",
        "x": 0.0,
        "y": 0.0,
        "xanchor": "left",
        "yanchor": "top",
        "pad": {"t": 45, "r": 10},
        "buttons": [
            {"label": "Play", "method": "animate", "args": [None, play]},
            {"label": "Pause", "method": "animate", "args": [[None], _animate_args(0)]},
        ],
    }


def _slider(frames: int, fps: float) -> dict:
    return {
        "active": 0,
        "x": 0.15,
        "len": 0.85,
        "y": 0.0,
        "yanchor": "top",
        "pad": {"t": 30},
        "currentvalue": {"prefix": "frame ", "font": {"size": 12}},
        "ticklen": 0,
        "minorticklen": 0,
        "font": {"color": "rgba(0, 0, 0, 0)"},  # one label per frame would overlap: the current value says it
        "steps": [
            {"label": f"{i} ({i / fps:.2f} s)", "method": "animate", "args": [[str(i)], _animate_args(0)]}
            for i in range(frames)
        ],
    }
