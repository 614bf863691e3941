"""The LightningModule of GuidedMotion's motion VAEs (paper §3.3): one `MotionVAE` with Q latent tokens per level.

Like `MotionDiffusionModule`, the module owns what a checkpoint needs to encode and decode without the dataset:
the VAE sizes (with Q resolved), the feature Mean/Std, the representation spec (features -> joints), fps and
max_frames. It logs the reconstruction loss, the KL and, on validation, the MPJPE in metres of the reconstruction
from the posterior mean (the quantity the best checkpoint is chosen by).
"""

from __future__ import annotations

from dataclasses import fields

import lightning as L
import torch

from motiondiff.data.representations.spec import representation_from_spec
from motiondiff.lit.diffusion import MotionDiffusionModule
from motiondiff.models.backbones.encoder_layer import TransformerSize
from motiondiff.models.vae import MotionVAE, vae_loss

VAE_SIZE_KEYS = ("latent_dim", *(f.name for f in fields(TransformerSize)))  # what MotionVAE reads of `vae`


def mpjpe(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, root_aligned: bool = False) -> torch.Tensor:
    """Mean per-joint position error of each clip (B,), in the joints' units, over its valid frames.
    pred/target: (B, N, J, 3); mask: (B, N). `root_aligned`: both skeletons moved to their root (joint 0) per frame
    first (MLD's VAE protocol), so a drifting root trajectory does not count."""
    if root_aligned:
        pred, target = pred - pred[..., :1, :], target - target[..., :1, :]
    per_frame = (pred - target).norm(dim=-1).mean(-1)
    mask = mask.to(per_frame.dtype)
    return (per_frame * mask).sum(-1) / mask.sum(-1).clamp(min=1)


class MotionVAEModule(L.LightningModule):
    def __init__(
        self,
        feature_dim: int,
        vae: dict,
        optim: dict,
        mean: list[float],
        std: list[float],
        max_frames: int,
        fps: float,
        num_joints: int,
        kl_weight: float = 1e-4,
        level: str | None = None,
        dataset: str = "",
        representation: dict | None = None,
    ):
        super().__init__()
        self.save_hyperparameters()
        if not vae.get("tokens"):
            raise ValueError("vae['tokens'] (Q) must be set: resolve it from the level before building the module")
        self.vae = MotionVAE(
            feature_dim, latent_tokens=int(vae["tokens"]), max_frames=max_frames,
            **{k: vae[k] for k in VAE_SIZE_KEYS if k in vae},
        )  # fmt: skip
        self.kl_weight = float(kl_weight)
        self.representation = representation_from_spec(representation, feature_dim)
        self.register_buffer("mean", torch.tensor(mean, dtype=torch.float32))
        self.register_buffer("std", torch.tensor(std, dtype=torch.float32))

    # The same optimiser/schedule, de-normalisation and joint decoding as the diffusion module (they only read
    # hparams.optim, the trainer's max_steps, mean/std and the representation, which this module has too).
    configure_optimizers = MotionDiffusionModule.configure_optimizers
    normalise = MotionDiffusionModule.normalise
    denormalise = MotionDiffusionModule.denormalise
    joints = MotionDiffusionModule.joints

    @property
    def tokens(self) -> int:
        return self.vae.latent_tokens

    # ---- encode / decode on normalised features -------------------------------------------------------------------
    def encode(self, features: torch.Tensor, mask: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Normalised features (B, N, D), mask (B, N) -> posterior (mean, log-variance), each (B, Q, D')."""
        return self.vae.encode(features, mask)

    def decode(self, z: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Latent (B, Q, D') -> normalised features (B, N, D) for N = mask.shape[1]; padded frames are zero."""
        return self.vae.decode(z, mask)

    def reconstruct(self, features: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Decode of the posterior mean: the VAE's deterministic reconstruction."""
        return self.decode(self.encode(features, mask)[0], mask)

    # ---- training -------------------------------------------------------------------------------------------------
    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        x, mask = batch["motion"], batch["mask"]
        recon, mean, log_var = self.vae(x, mask)
        loss, rec, kl = vae_loss(recon, x, mask, mean, log_var, self.kl_weight)
        b = x.shape[0]
        self.log("train/loss", loss, prog_bar=True, batch_size=b)
        self.log_dict({"train/recon": rec.detach(), "train/kl": kl.detach()}, batch_size=b)
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        # The posterior mean (no sampling): the validation numbers are deterministic and comparable between epochs.
        x, mask = batch["motion"], batch["mask"]
        mean, log_var = self.encode(x, mask)
        recon = self.decode(mean, mask)
        loss, rec, kl = vae_loss(recon, x, mask, mean, log_var, self.kl_weight)
        error = mpjpe(self.joints(self.denormalise(recon)), self.joints(self.denormalise(x)), mask)
        b = x.shape[0]
        self.log("val/mpjpe", error.mean(), prog_bar=True, batch_size=b, sync_dist=True)
        self.log_dict({"val/loss": loss, "val/recon": rec, "val/kl": kl}, batch_size=b, sync_dist=True)
