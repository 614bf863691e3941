"""What an edit writes: the input and each edited motion as arrays and in the asked export formats, with one
results row per edit (how well it kept the input, its seams, what a clean-up did)."""

from __future__ import annotations

from pathlib import Path

from motiondiff.edit.measures import edit_numbers
from motiondiff.export.naming import slug
from motiondiff.export.outputs import export_features
from motiondiff.export.render import VIDEO_SIZE
from motiondiff.runtime.atomic import save_npy


def save_edits(out: Path, edited, formats, rig_names=None, video_size: int = VIDEO_SIZE) -> list[dict]:
    """The input and each edit of ``edited`` (a MotionOutput of an edit: its ``edit`` and ``source``) as arrays and
    the ``formats`` (export.outputs); one results row per edit. After ``edited.cleaned("feet")`` the saved joints are
    the foot-skate cleaned ones (kept frames and joints untouched; the model's joints go to *_joints_raw.npy) and the
    row reports the sliding before and after. ``video_size``: the side of the mp4/gif videos in pixels."""
    result, motion, rep, fps = edited.edit, edited.source, edited.representation, float(edited.fps)
    condition = edited.prompts[0] if edited.prompts else None
    title = f"{result.kind}: {condition or 'unconditioned'}"
    inputs = export_features(
        out / "input", rep, motion.features, fps, formats, title="input", rig_names=rig_names, video_size=video_size
    )
    save_npy(out / "keep_mask.npy", result.keep[0])
    cleaned = edited.info.get("cleanup")
    rows = []
    for k in range(len(result)):
        stem = out / f"{result.kind}_{slug(condition)}_{k:02d}"
        files = {"joints": f"{stem}_joints.npy", "features": f"{stem}_features.npy",
                 "input_joints": f"{stem}_input_joints.npy"}  # fmt: skip
        if cleaned:
            save_npy(f"{stem}_joints_raw.npy", result.joints[k])
        save_npy(files["joints"], edited.joints[k])
        save_npy(files["features"], result.features[k])
        save_npy(files["input_joints"], result.input_joints[k])
        exports = export_features(stem, rep, result.features[k], fps, formats, title=title,
                                  joints=edited.joints[k] if cleaned else None, rig_names=rig_names,
                                  video_size=video_size)  # fmt: skip
        rows.append({"index": k, **files, "video": exports.get("mp4", exports.get("gif")), "exports": exports,
                     "input_video": inputs.get("mp4", inputs.get("gif")), "input_exports": inputs,
                     **edit_numbers(result, k, fps), **(cleaned[k] if cleaned else {})})  # fmt: skip
    return rows
