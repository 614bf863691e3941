"""What an edit writes: the input and each edited motion as arrays and in the asked export formats, with one
results row per edit (how well it kept the input, its seams, what a clean-up did)."""

from __future__ import annotations

from pathlib import Path

from motiondiff.edit.api import EditResult
from motiondiff.edit.cleanups import apply_cleanups
from motiondiff.edit.inputs import InputMotion
from motiondiff.edit.measures import edit_numbers
from motiondiff.export.naming import slug
from motiondiff.export.outputs import export_features
from motiondiff.runtime.atomic import save_npy


def save_edits(
    out: Path, result: EditResult, motion: InputMotion, module, formats, condition, cleanup=(), rig_names=None
) -> list[dict]:
    """The input and each edit as arrays and the ``formats`` (export.outputs); one results row per edit. With
    ``cleanup=("feet",)`` the saved joints are foot-skate cleaned (kept frames and joints untouched; the model's joints
    go to *_joints_raw.npy) and the row reports the sliding before and after."""
    fps = float(module.hparams.fps)
    rep = module.representation
    title = f"{result.kind}: {condition or 'unconditioned'}"
    inputs = export_features(out / "input", rep, motion.features, fps, formats, title="input", rig_names=rig_names)
    save_npy(out / "keep_mask.npy", result.keep[0])
    rows = []
    for k in range(len(result)):
        stem = out / f"{result.kind}_{slug(condition)}_{k:02d}"
        files = {"joints": f"{stem}_joints.npy", "features": f"{stem}_features.npy",
                 "input_joints": f"{stem}_input_joints.npy"}  # fmt: skip
        joints, cleaned = result.joints[k], {}
        if cleanup:
            save_npy(f"{stem}_joints_raw.npy", joints)
            joints, cleaned = apply_cleanups(joints, rep.skeleton, fps, cleanup, keep=result.kept_points(k))
        save_npy(files["joints"], joints)
        save_npy(files["features"], result.features[k])
        save_npy(files["input_joints"], result.input_joints[k])
        exports = export_features(stem, rep, result.features[k], fps, formats, title=title,
                                  joints=joints if cleaned else None, rig_names=rig_names)  # fmt: skip
        rows.append({"index": k, **files, "video": exports.get("mp4", exports.get("gif")), "exports": exports,
                     "input_video": inputs.get("mp4", inputs.get("gif")), "input_exports": inputs,
                     **edit_numbers(result, k, fps), **cleaned})  # fmt: skip
    return rows
