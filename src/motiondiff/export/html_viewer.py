"""A self-contained interactive 3D viewer of joint positions: one small HTML file that works offline and alone
(e-mailed, or shown in a notebook or the demo's iframe). The mannequin body of the videos' render=body
(`geometry.mannequin`), or bones per kinematic chain (left blue, right red, torso dark, as in the videos) with a
head marker, a Body/Bones button to switch; a ground grid, the root's trajectory trail on the floor with the current
root marked, Play/Pause and a frame slider. The camera frames the whole motion's fixed box, so it never jumps, with y (up)
drawn vertical; drag turns it, the wheel zooms. Opening `viewer.html#frame=K` shows frame K (deep links, and what
tests screenshot).

Why a hand-written viewer (motiondiff/assets/motion_viewer.js, inlined) and not plotly: plotly.js inline is megabytes
in every file, and plotly's one-script-per-folder option still writes frames over 300 KB per motion and leaves a file
copied alone blank (measured in docs/usage.md, "The HTML viewer").

The body costs no bytes per frame: the file carries each mannequin piece's shape (its two end points as joints plus
a reach along a bone, and the radius at each end, read off `Mannequin` as built for the videos), and the script
places the pieces on each frame's joints as `Mannequin.at` does, drawing each capsule as its projected outline.
"""

from __future__ import annotations

import base64
import html
import json
import os
from importlib import resources
from pathlib import Path

import numpy as np

from motiondiff.export.render import Title, _chain_color, camera_azimuth, head_joint
from motiondiff.geometry.inverse_kinematics import fit_rest_offsets
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write

__all__ = ["export_html"]

_STYLE = {  # colours as in the videos; sizes in metres, so they scale with the zoom
    "grid": "#bbbbbb", "grid_step": 0.5, "trail": "#ff9900", "head": "#333333", "bone_width": 0.03,
    "head_radius": 0.09, "root_radius": 0.035,
    # the body: limbs tinted in their side's colour, the trunk and head light gray as the videos' body
    "body": {"left": "#8fb8df", "right": "#e59c9c", "torso": "#c8c8cc"},
}  # fmt: skip
_ELEVATION = 20.0  # degrees above the ground the camera starts at
_STEP_M = 0.001  # positions are stored in 1 mm steps (`_quantize`)

_PAGE = """<!DOCTYPE html>
<html><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
html:has(> body > .motion-viewer), body:has(> .motion-viewer) {{ height: 100%; margin: 0; }}  /* the page, not a host */
.motion-viewer {{ display: flex; flex-direction: column; height: 100%; min-height: min(420px, 100vh);
  font: 14px sans-serif; background: white; color: #222; }}
.mv-title {{ text-align: center; padding: 8px 12px 0; font-size: 16px; }}
.mv-stage {{ flex: 1; min-height: 0; position: relative; }}
.mv-canvas {{ position: absolute; width: 100%; height: 100%; cursor: grab; touch-action: none; }}
.mv-bar {{ display: flex; align-items: center; gap: 10px; padding: 6px 12px 10px; }}
.mv-slider {{ flex: 1; }}
.mv-label {{ min-width: 170px; font-variant-numeric: tabular-nums; }}
</style></head>
<body><div class="motion-viewer">
<script type="application/json" class="motion-data">{data}</script>
<script>{script}</script>
</div></body></html>
"""


def export_html(
    path: str | os.PathLike,
    joints: np.ndarray,
    skeleton: Skeleton,
    fps: float,
    title: Title = "",
    *,
    trail: bool = True,
    body: bool = True,
) -> Path:
    """Write an interactive viewer of joints (N, J, 3) (metres, y up) to `path` (.html), atomically. The camera
    starts front-side of the travel direction (as the videos); ``title``: one text, or (first frame, text)
    segments shown as the motion plays. ``body``: open on the mannequin body, with a button to the bones (False:
    bones only, and no button)."""
    path = Path(path)
    joints = check_motion(joints, skeleton, fps, "export_html")
    if not path.parent.is_dir():
        raise NotADirectoryError(f"cannot write {path}: the folder {path.parent} does not exist")
    page = _PAGE.format(
        title=html.escape(title if isinstance(title, str) else " / ".join(text for _, text in title)),
        data=_script_safe(
            json.dumps(_payload(joints, skeleton, fps, title, trail, body), separators=(",", ":"), ensure_ascii=False)
        ),
        script=_viewer_script(),
    )
    return atomic_write(path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"), suffix=".html")


def _payload(joints: np.ndarray, skeleton: Skeleton, fps: float, title: Title, trail: bool, body: bool) -> dict:
    """What motion_viewer.js draws: the positions, 16-bit steps from the motion's lowest corner (`_quantize`) in
    base64, and what is fixed over the motion (bones, the body's pieces, camera, style)."""
    origin, step, steps = _quantize(joints)
    return {
        "fps": float(fps),
        "frames": int(joints.shape[0]),
        "joints": int(joints.shape[1]),
        "origin": origin,
        "step": step,
        "positions": base64.b64encode(steps.tobytes()).decode("ascii"),
        "chains": [
            {"joints": list(map(int, c)), "color": _chain_color(c, skeleton)} for c in skeleton.kinematic_chains
        ],
        "head": head_joint(skeleton),
        "trail": bool(trail),
        "titles": [[0, title]] if isinstance(title, str) else [[int(start), str(text)] for start, text in title],
        "ranges": _fixed_ranges(joints),
        # camera_azimuth's angle in our ground plane, so the camera starts where the videos' does
        "camera": {
            "azimuth": float(np.radians(camera_azimuth(joints, skeleton))),
            "elevation": float(np.radians(_ELEVATION)),
        },
        "body": _body_pieces(joints, skeleton) if body else None,
        "style": _STYLE,
    }


def _body_pieces(joints: np.ndarray, skeleton: Skeleton) -> list[list] | None:
    """Each piece of the mannequin of `joints` (sized as render=body sizes it: on the motion's own bone lengths) as
    [joint, toward, reach, radius] for its end A, the same for B, and its tint ('left', 'right' or 'torso').
    An end point is ``joint + reach * unit(joint - toward)`` (toward -1: the joint itself), as in `Mannequin`; the
    radii are the distances of the pieces' vertices from their end points (a piece's half-sphere at each end).
    None (the viewer shows the bones) for a motion whose bones all have zero length: it has no body to build."""
    with np.errstate(invalid="ignore", divide="ignore"):
        try:
            mannequin = build_mannequin(skeleton, fit_rest_offsets(joints, skeleton))
        except ValueError:
            return None
    radius = np.zeros((len(mannequin.joint), 2))
    radius[mannequin.piece, mannequin.t.astype(int)] = np.hypot(mannequin.along, np.linalg.norm(mannequin.ring, axis=1))
    if not (np.isfinite(radius).all() and np.isfinite(mannequin.reach).all()):
        return None
    sides = {side: set(skeleton.parts.get(f"{side}_arm", ())) | set(skeleton.parts.get(f"{side}_leg", ()))
             for side in ("left", "right")}  # fmt: skip
    pieces = []
    for p, ends in enumerate(mannequin.joint.tolist()):
        touched = [side for side, limb in sides.items() if limb & set(ends)]
        shape = [v for e in (0, 1) for v in (ends[e], int(mannequin.toward[p, e]), round(float(mannequin.reach[p, e]), 4),
                                             round(float(radius[p, e]), 4))]  # fmt: skip
        pieces.append([*shape, touched[0] if len(touched) == 1 else "torso"])
    return pieces


def _quantize(joints: np.ndarray) -> tuple[list[float], float, np.ndarray]:
    """(origin, step, little-endian uint16 steps): joints = origin + step * steps, to within step / 2. The step is
    1 mm (finer than a pixel) unless the motion spans over 65 m; half the bytes of float32, so a file holds twice
    the frames under its size budget."""
    flat = joints.reshape(-1, 3).astype(np.float64)
    origin = flat.min(0)
    step = max(_STEP_M, float((flat.max(0) - origin).max()) / np.iinfo(np.uint16).max)
    steps = np.clip(np.round((joints - origin) / step), 0, np.iinfo(np.uint16).max).astype("<u2")
    return [float(v) for v in origin], step, steps


def _viewer_script() -> str:
    script = (resources.files("motiondiff") / "assets" / "motion_viewer.js").read_text(encoding="utf-8")
    if "</script" in script.lower():
        raise RuntimeError("motion_viewer.js must not contain '</script': it is inlined in a <script> element")
    return script


def _script_safe(text: str) -> str:
    """JSON that cannot end its <script> element early: '<' (only ever inside strings) becomes its \\u escape."""
    return text.replace("<", "\\u003c")


def _fixed_ranges(joints: np.ndarray) -> list[list[float]]:
    """x/z ranges: a square around the whole motion (at least 2 m wide); y: from the floor (or the lowest joint)
    to above the highest. The camera frames this box for the whole motion."""
    lo, hi = joints.reshape(-1, 3).min(0), joints.reshape(-1, 3).max(0)
    centre = (lo + hi) / 2
    radius = max(1.0, float((hi - lo)[[0, 2]].max()) / 2 + 0.3)
    y_range = (min(0.0, float(lo[1])) - 0.05, max(2.0, float(hi[1]) + 0.1))
    ranges = [(centre[0] - radius, centre[0] + radius), y_range, (centre[2] - radius, centre[2] + radius)]
    return [[round(float(a), 4), round(float(b), 4)] for a, b in ranges]
