"""What the generation commands (sample.py, edit.py, sample.py method=guidedmotion) share about their outputs: the
output options of a config (export formats, render body, video size, clean-ups, temporal smoothing), checked before any
sampling. Writing the samples is `MotionOutput.save`, the same for the commands and the Python API."""

from __future__ import annotations

from typing import TYPE_CHECKING

from omegaconf import DictConfig, ListConfig, OmegaConf

from motiondiff.edit.cleanups import parse_cleanup
from motiondiff.export.outputs import parse_formats
from motiondiff.export.render import VIDEO_SIZE, check_video_size
from motiondiff.export.smpl_mesh import render_body
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


def video_size(cfg: DictConfig) -> int:
    """``video.size=``: the side of the mp4/gif videos in pixels (a config without the key: VIDEO_SIZE), checked
    before any sampling (``export.render.check_video_size``)."""
    return check_video_size(OmegaConf.select(cfg, "video.size", default=VIDEO_SIZE), "video.size")


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
