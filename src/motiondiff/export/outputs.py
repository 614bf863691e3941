"""What sample.py and edit.py write for each generated motion besides its arrays: videos, a BVH, an HTML viewer,
SMPL parameters.

One call per motion, `export_features`, from the de-normalised features of the model's representation (the BVH of
a rotation representation then carries the model's own rotations) or from joints that were changed after decoding
(smoothed: their BVH and SMPL files are solved by IK, so the files show what was saved).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motiondiff.data.formats.smpl_params import SmplBody
from motiondiff.data.representations import Representation
from motiondiff.export import export_motion
from motiondiff.export.blender import BLENDER_FORMATS, check_blender, convert_bvh
from motiondiff.export.body_render import MannequinBody, mannequin_mesh
from motiondiff.export.bvh_export import export_bvh, export_bvh_from_features
from motiondiff.export.mesh_render import render_mesh
from motiondiff.export.render import VIDEO_SIZE, Title, check_video_size
from motiondiff.export.rig_names import with_rig_names
from motiondiff.export.smpl_export import check_smpl_skeleton, export_smpl, export_smpl_from_features
from motiondiff.export.smpl_mesh import check_mesh_skeleton, smpl_vertices
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.errors import UsageError

OUTPUT_FORMATS = ("mp4", "gif", "bvh", "html", "smpl", *BLENDER_FORMATS)  # the arrays (.npy) are always written
ROTATION_FORMATS = ("bvh", "smpl")  # written from the features (a model's own rotations), or solved from changed joints
VIDEO_FORMATS = ("mp4", "gif")  # stick figures, or a shaded body: the mannequin (render=body) or SMPL (render=mesh)


def parse_formats(value: str | Sequence[str] | None) -> list[str]:
    """``export=`` of the CLIs: "none", one format, "mp4,bvh" or a list; checked before any sampling."""
    if value is None:
        return []
    items = [value] if isinstance(value, str) else list(value)
    formats = [f.strip().lower() for item in items for f in str(item).split(",") if f.strip()]
    formats = [f for f in formats if f != "none"]
    unknown = [f for f in formats if f not in OUTPUT_FORMATS]
    if unknown:
        raise ValueError(
            f"unknown export format(s) {', '.join(unknown)}; choose from {', '.join(OUTPUT_FORMATS)} (a list such "
            "as export=[mp4,bvh,html]) or export=none"
        )
    return list(dict.fromkeys(formats))


def check_formats_for(
    formats: Sequence[str],
    skeleton: Skeleton,
    rig_names: str | None = None,
    body: SmplBody | MannequinBody | None = None,
    video_size: int = VIDEO_SIZE,
) -> None:
    """Refuse, before anything is generated or written, formats the skeleton cannot be written in (smpl, and videos
    of a `body` model's mesh: SMPL-22 or SMPL-24 only) and a video size no video can have; one UsageError naming
    what is supported."""
    formats = parse_formats(formats)
    check_video_size(video_size, "video_size")
    if "smpl" in formats:
        check_smpl_skeleton(skeleton)
    if body is not None:
        render = "body" if isinstance(body, MannequinBody) else "mesh"  # the mannequin fits any skeleton
        if render == "mesh":
            check_mesh_skeleton(skeleton)
        if not any(f in VIDEO_FORMATS for f in formats):
            asked, what = ",".join(formats) or "none", "the mannequin" if render == "body" else "the SMPL body"
            raise UsageError(f"render={render} draws {what} in the mp4/gif videos, and export={asked} has none: "
                             f"add mp4 or gif to export= (or drop render={render})")  # fmt: skip
    check_blender(formats)  # fbx/glb: Blender must be there
    with_rig_names(skeleton, rig_names)  # a preset this skeleton has names for


def export_features(
    stem: str | Path,
    representation: Representation,
    features: np.ndarray,
    fps: float,
    formats: Sequence[str],
    title: Title = "",
    joints: np.ndarray | None = None,
    rig_names: str | None = None,
    body: SmplBody | MannequinBody | None = None,
    video_size: int = VIDEO_SIZE,
) -> dict:
    """Write ``{stem}.{format}`` for each format; returns {format: path} and, with a BVH, its fit error
    ("bvh_max_error_m", "bvh_mean_error_m": FK of the file against the joints it was made from; generated joints
    stretch their bones from frame to frame, which a BVH's fixed bone lengths cannot follow exactly); with smpl,
    ``{stem}_smpl.npz`` and the same three numbers ("smpl_max_error_m", ...). ``joints``: the motion to show when
    it is not simply the features decoded (e.g. smoothed or cleaned up). ``body``: an SMPL body model
    or the mannequin (`smpl_mesh.render_body`) whose mesh the mp4/gif videos show instead of stick figures; fbx/glb
    always carry the mannequin. ``video_size``: the videos' side in pixels."""
    formats = parse_formats(formats)
    check_formats_for(formats, representation.skeleton, rig_names, body, video_size)
    named = with_rig_names(representation.skeleton, rig_names)  # bone names of the bvh/fbx/glb files
    stem = Path(stem)
    written: dict = {}
    if "bvh" in formats:
        path = stem.parent / f"{stem.name}.bvh"
        if joints is None:
            report = export_bvh_from_features(path, representation, features, fps, names=rig_names)
        else:
            report = export_bvh(path, joints, named, fps)
        written.update(bvh=str(report.path), bvh_max_error_m=report.max_error, bvh_mean_error_m=report.mean_error,
                       bvh_method=report.method)  # fmt: skip
    if "smpl" in formats:
        path = stem.parent / f"{stem.name}_smpl.npz"
        if joints is None:
            report = export_smpl_from_features(path, representation, features, fps)
        else:
            report = export_smpl(path, joints, representation.skeleton, fps)
        written.update(smpl=str(report.path), smpl_max_error_m=report.max_error,
                       smpl_mean_error_m=report.mean_error, smpl_method=report.method)  # fmt: skip
    blender = [f for f in formats if f in BLENDER_FORMATS]
    if blender:  # Blender's own FBX/glTF writers, from this motion's BVH
        bvh = written.get("bvh")
        scratch = None if bvh else stem.parent / f".{stem.name}.for_blender.bvh"
        if scratch is not None:
            if joints is None:
                export_bvh_from_features(scratch, representation, features, fps, names=rig_names)
            else:
                export_bvh(scratch, joints, named, fps)
        try:
            for fmt in blender:
                path = convert_bvh(bvh or scratch, stem.parent / f"{stem.name}.{fmt}", fps, skeleton=named)
                written[fmt] = str(path)  # with the mannequin bound to the bones
        finally:
            if scratch is not None:
                scratch.unlink(missing_ok=True)
    others = [f for f in formats if f not in ROTATION_FORMATS and f not in BLENDER_FORMATS]
    if others:
        shown = representation.decode_numpy(np.asarray(features)) if joints is None else joints
        meshes = [f for f in others if f in VIDEO_FORMATS] if body is not None else []
        if meshes:  # the body's mesh (the mannequin or the SMPL model), posed by the joints shown (once for both)
            if isinstance(body, MannequinBody):
                vertices, faces = mannequin_mesh(shown, representation.skeleton)
            else:
                vertices, faces = smpl_vertices(shown, representation.skeleton, fps, body), body.faces
            for fmt in meshes:
                path = render_mesh(vertices, faces, stem.parent / f"{stem.name}.{fmt}", title, fps, joints=shown,
                                   skeleton=representation.skeleton, size=video_size)  # fmt: skip
                written[fmt] = str(path)
        rest = [f for f in others if f not in meshes]
        paths = {}
        if rest:
            paths = export_motion(stem, shown, representation.skeleton, fps, rest, title=title, video_size=video_size)
        written.update({fmt: str(p) for fmt, p in paths.items()})
    return written
