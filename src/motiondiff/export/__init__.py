"""Motion outputs people can use: `export_motion` writes one motion in any of FORMATS next to a common stem.

- npy: joints (N, J, 3) float32, metres, y up;
- mp4 / gif: stick-figure video (render.render_motion), `video_size` pixels square;
- bvh: animation file on the skeleton (bvh_export; fit error in its ExportReport);
- html: offline interactive 3D viewer (html_viewer).

SMPL parameters (.npz, AMASS layout) of SMPL-22/24 motions: `export_smpl` (smpl_export; export=smpl in the CLIs).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motiondiff.export.bvh_export import ExportReport, export_bvh, export_bvh_from_features
from motiondiff.export.html_viewer import export_html
from motiondiff.export.render import VIDEO_SIZE, Title, render_motion
from motiondiff.export.smpl_export import export_smpl, export_smpl_from_features, smpl_joints
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write

__all__ = ["FORMATS", "ExportReport", "export_bvh", "export_bvh_from_features", "export_html", "export_motion",
           "export_smpl", "export_smpl_from_features", "smpl_joints"]  # fmt: skip

FORMATS = ("npy", "mp4", "gif", "bvh", "html")


def export_motion(
    stem: str | Path,
    joints: np.ndarray,
    skeleton: Skeleton,
    fps: float,
    formats: list[str],
    title: Title = "",
    rotations: np.ndarray | None = None,
    root: np.ndarray | None = None,
    video_size: int = VIDEO_SIZE,
) -> dict[str, Path]:
    """Write `joints` (N, J, 3) as `{stem}.{format}` for each format; returns {format: path}. `rotations` and `root`
    (a rotation representation's local quaternions and root positions) go into the BVH as they are, else it is
    solved by IK. ``video_size``: the side of the mp4/gif in pixels. Unknown formats are refused before anything is
    written."""
    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise ValueError(f"unknown export format(s) {unknown}; choose from {', '.join(FORMATS)}")
    joints = np.asarray(joints)
    if joints.ndim != 3 or joints.shape[1:] != (skeleton.num_joints, 3) or not np.isfinite(joints).all():
        raise ValueError(
            f"export_motion: joints must be finite with shape (frames, {skeleton.num_joints}, 3) for skeleton "
            f"{skeleton.name!r}, got {joints.shape}{'' if np.isfinite(joints).all() else ' with NaN/Inf'}"
        )
    stem = Path(stem)
    paths = {}
    for fmt in dict.fromkeys(formats):  # each format once, in the order asked
        path = stem.parent / f"{stem.name}.{fmt}"  # not with_suffix: a stem may contain dots
        if fmt == "npy":
            array = np.asarray(joints, dtype=np.float32)
            paths[fmt] = atomic_write(path, lambda tmp, a=array: np.save(tmp, a), suffix=".npy")
        elif fmt in ("mp4", "gif"):
            paths[fmt] = render_motion(joints, skeleton, path, title=title, fps=fps, size=video_size)
        elif fmt == "bvh":
            paths[fmt] = export_bvh(path, joints, skeleton, fps, rotations=rotations, root=root).path
        else:
            paths[fmt] = export_html(path, joints, skeleton, fps, title=title)
    return paths
