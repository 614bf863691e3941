"""Load a trained motion model from a file: a training checkpoint (.ckpt, read without running pickled code) or a
release (.safetensors weights + .json config)."""

from __future__ import annotations

from pathlib import Path

from motiondiff.lit.diffusion import MotionDiffusionModule
from motiondiff.paths import RELEASE_SUFFIXES
from motiondiff.release import load_release


def load_model(path: str | Path, device: str = "cpu") -> MotionDiffusionModule:
    """The model in `path`, in eval mode on `device`."""
    if Path(path).suffix in RELEASE_SUFFIXES:
        return load_release(path, device)
    module = MotionDiffusionModule.load_from_checkpoint(path, map_location=device, weights_only=True)
    return module.eval()
