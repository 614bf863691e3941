"""Load a trained motion model from a file: a training checkpoint (.ckpt, read without running pickled code) or a
release (.safetensors weights + .json config). A file that is not one, or holds NaN weights, is one UsageError."""

from __future__ import annotations

from pathlib import Path

from motiondiff.lit.motion_diffusion import MotionDiffusion
from motiondiff.model_files.file_checks import checkpoint_state
from motiondiff.model_files.release import load_latent_release, load_release
from motiondiff.model_files.resolve import RELEASE_SUFFIXES
from motiondiff.runtime.checked_loading import CKPT_FIX, check_finite_state, check_same_shapes, reading
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.file_kinds import file_problem


def load_model(path: str | Path, device: str = "cpu") -> MotionDiffusion:
    """The model in `path`, in eval mode on `device`: built from the checkpoint's hyper-parameters and weights as a
    plain `MotionDiffusion` (generation needs no Lightning; `MotionDiffusionModule.load_from_checkpoint` trains on)."""
    if Path(path).suffix in RELEASE_SUFFIXES:
        return load_release(path, device)
    state = checkpoint_state(path)
    weights = state["state_dict"]
    with reading(path, "checkpoint"):
        module = MotionDiffusion(**state["hyper_parameters"])
    check_same_shapes(
        weights, module.state_dict(), f"checkpoint {path}", CKPT_FIX, "the model its hyper_parameters describe"
    )
    module.load_state_dict(weights, strict=True)
    return module.to(device).eval()


VAE_FIX = "pass the best-mpjpe checkpoint train_vae.py wrote"


def load_vae(path: str | Path, what: str = "VAE checkpoint", fix: str = VAE_FIX):
    """A motion VAE of train_vae.py in eval mode on CPU, and its checkpoint's step: built from the checkpoint's
    hyper-parameters (read without running pickled code). A missing file, or one that is not a VAE checkpoint or
    holds NaN weights, is one UsageError naming `what` and `fix`."""
    from motiondiff.lit.vae import MotionVAEModule  # Lightning: only where a VAE loads

    path = Path(path)
    problem = file_problem(path)
    if problem is not None:
        raise UsageError(f"{what} {path} {problem}; {fix}")
    state = checkpoint_state(path, what, fix)
    with reading(path, what, fix):
        module = MotionVAEModule(**state["hyper_parameters"])
        check_same_shapes(
            state["state_dict"], module.state_dict(), f"{what} {path}", fix, "the VAE its hparams describe"
        )
        module.load_state_dict(state["state_dict"], strict=True)
    return module.eval(), int(state.get("global_step", 0))


LATENT_FIX = "give the .ckpt that train_latent.py wrote or a GuidedMotion release (.safetensors)"


def load_latent_model(path: str | Path, device: str = "cpu"):
    """GuidedMotion's latent model (with its three VAEs) in eval mode: a train_latent.py checkpoint (read without
    running pickled code) or a release. A file that is neither, or holds NaN weights, is one UsageError."""
    from motiondiff.lit.latent import HierarchicalLatentModule  # Lightning: only where a latent model loads

    path = Path(path)
    if not path.is_file():
        raise UsageError(f"no latent model at {path}: {LATENT_FIX}")
    if path.suffix in RELEASE_SUFFIXES:
        return load_latent_release(path, device)
    with reading(path, "latent checkpoint", LATENT_FIX):
        module = HierarchicalLatentModule.load_from_checkpoint(path, map_location=device, weights_only=True)
    check_finite_state(module.state_dict(), f"latent checkpoint {path}", LATENT_FIX)
    return module.eval()
