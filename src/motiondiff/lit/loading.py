"""Load a trained motion model from a file: a training checkpoint (.ckpt, read without running pickled code) or a
release (.safetensors weights + .json config). A file that is not one, or holds NaN weights, is one UsageError."""

from __future__ import annotations

from pathlib import Path

from motiondiff.checked_loading import check_finite_state, reading
from motiondiff.lit.diffusion import MotionDiffusionModule
from motiondiff.paths import RELEASE_SUFFIXES
from motiondiff.release import load_release


def load_model(path: str | Path, device: str = "cpu") -> MotionDiffusionModule:
    """The model in `path`, in eval mode on `device`."""
    if Path(path).suffix in RELEASE_SUFFIXES:
        return load_release(path, device)
    with reading(path, "checkpoint"):
        module = MotionDiffusionModule.load_from_checkpoint(path, map_location=device, weights_only=True)
    check_finite_state(module.state_dict(), f"checkpoint {path}")
    return module.eval()
