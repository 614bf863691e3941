"""What the generation commands (sample.py, edit.py, sample.py method=guidedmotion) share about their outputs: the
output options of a config (export formats, render body, clean-ups, temporal smoothing), checked before any
sampling, and writing each sample's joints, features, exports and measured facts."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from omegaconf import DictConfig, ListConfig

from motiondiff.data.preparing.captions import measure
from motiondiff.data.representations.spec import bridge_from_spec
from motiondiff.edit.cleanups import apply_cleanups, parse_cleanup
from motiondiff.edit.measures import mean_joint_speed
from motiondiff.edit.smoothing import smooth_joints, smoothness_of_joints
from motiondiff.export.naming import slug
from motiondiff.export.outputs import export_features, parse_formats
from motiondiff.export.smpl_mesh import render_body
from motiondiff.runtime.atomic import save_npy
from motiondiff.runtime.errors import UsageError

if TYPE_CHECKING:
    from motiondiff.lit.motion_diffusion import MotionDiffusion


def export_formats(cfg: DictConfig) -> list[str]:
    """The ``export=`` formats (mp4, gif, bvh, html, smpl; none), checked before anything is sampled."""
    try:
        return parse_formats(cfg.export if not isinstance(cfg.export, ListConfig) else list(cfg.export))
    except ValueError as err:
        raise UsageError(str(err)) from None


def render_option(cfg: DictConfig):
    """``render=`` and ``smpl_model=``: the SMPL body the videos show (None: stick figures), loaded and checked
    before the model loads (``export.smpl_mesh.render_body``)."""
    return render_body(cfg.get("render"), cfg.get("smpl_model"))


def cleanup_option(cfg: DictConfig) -> tuple[str, ...]:
    """``cleanup=``: the clean-ups of the saved joints (bones, feet; ``edit.cleanups``), checked before sampling."""
    return parse_cleanup(cfg.get("cleanup"))


def smoothing_sigma(cfg: DictConfig, module: MotionDiffusion | None = None) -> float | None:
    """smooth_sigma= in frames; 0: off; null: the model's default (``default_smooth_sigma``, off for most)."""
    sigma = cfg.get("smooth_sigma")
    if sigma is None:
        return module.default_smooth_sigma if module is not None else None
    if sigma == 0:
        return None
    if isinstance(sigma, bool) or not isinstance(sigma, int | float) or not sigma > 0:
        raise UsageError(
            f"smooth_sigma is a Gaussian's width in frames (> 0; 0: off, null: the model's default), got {sigma!r}"
        )
    return float(sigma)


def save_samples(
    out: Path,
    prompt: str | None,
    feats: np.ndarray,
    module,
    formats,
    sigma: float | None = None,
    stem=None,
    cleanup: tuple[str, ...] = (),
    title=None,
    rig_names: str | None = None,
    body=None,
) -> list[dict]:
    """Joints, features and the ``formats`` (export.outputs) per sample; with ``sigma`` the saved joints are the
    smoothed ones (the raw ones go to *_joints_raw.npy) and the row reports the smoothness metric before and after;
    ``cleanup`` (``edit.cleanups``: bones, feet) then runs on them and the row holds each clean-up's report.
    ``title``: what the videos and viewer show (default the prompt; a long motion's (first frame, prompt) segments);
    ``rig_names``: bone names of the bvh/fbx/glb files (export.rig_names: smpl, mixamo); ``body``: the SMPL body
    model whose mesh the mp4/gif videos show (render=mesh; None: stick figures)."""
    rep = module.representation
    bridge = bridge_from_spec(module.hparams.get("representation"), module.hparams.feature_dim)
    fps = module.hparams.fps
    rows = []
    for k, f in enumerate(feats):
        joints = rep.decode_numpy(f).astype(np.float32)  # the representation's skeleton (a rig keeps its joints)
        stem_k = out / f"{stem or slug(prompt)}_{k:02d}"
        feature_joints = joints if bridge.identity else bridge.joints(f)  # SMPL-22/KIT-21, what `measure` reads
        smoothing = None
        if sigma is not None:
            save_npy(f"{stem_k}_joints_raw.npy", joints)
            before = smoothness_of_joints(feature_joints, bridge.feature_skeleton)
            joints, feature_joints = smooth_joints(joints, sigma), smooth_joints(feature_joints, sigma)
            after = smoothness_of_joints(feature_joints, bridge.feature_skeleton)
            smoothing = {"sigma_frames": sigma, "smoothness_before": before, "smoothness_after": after,
                         "measured_on": "HumanML3D features of the joints, as evaluate.py"}  # fmt: skip
        cleaned = {}
        if cleanup:
            if sigma is None:
                save_npy(f"{stem_k}_joints_raw.npy", joints)
            joints, cleaned = apply_cleanups(joints, rep.skeleton, fps, cleanup)
            if not bridge.identity:  # the measured joints get the same clean-ups on their own skeleton
                feature_joints = apply_cleanups(feature_joints, bridge.feature_skeleton, fps, cleanup)[0]
        save_npy(f"{stem_k}_joints.npy", joints)
        save_npy(f"{stem_k}_features.npy", f.astype(np.float32))
        changed = sigma is not None or bool(cleanup)
        exports = export_features(stem_k, rep, f, fps, formats, title=title or prompt or "unconditioned",
                                  joints=joints if changed else None, rig_names=rig_names, body=body)  # fmt: skip
        facts = measure(feature_joints, fps)
        speed = mean_joint_speed(feature_joints, fps)
        rows.append(
            {
                "prompt": prompt,
                "index": k,
                "joints": f"{stem_k}_joints.npy",
                "video": exports.get("mp4", exports.get("gif")),
                "exports": exports,
                "mean_joint_speed": speed,
                **asdict(facts),
                **({"smoothing": smoothing} if smoothing else {}),
                **cleaned,
            }  # fmt: skip
        )
    return rows
