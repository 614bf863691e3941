"""The LightningModule of MDM / vvMDM: `lit.motion_diffusion.MotionDiffusion` with its training and validation steps
and its optimiser. Checkpoints store its constructor's arguments (``save_hyperparameters``) to rebuild it.
"""

from __future__ import annotations

import math

import lightning as L
import torch

from motiondiff.lit.motion_diffusion import MotionDiffusion


class MotionDiffusionModule(MotionDiffusion, L.LightningModule):
    def __init__(self, **hparams):
        """The arguments of `MotionDiffusion` (by name: checkpoints store them and rebuild the module from them)."""
        super().__init__(**hparams)
        self.save_hyperparameters()

    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        loss, parts = self._loss(batch, self.cond_drop_prob)
        b = batch["motion"].shape[0]
        self.log("train/loss", loss, prog_bar=True, batch_size=b)
        if len(parts) > 1:
            self.log_dict({f"train/loss_{k}": v for k, v in parts.items()}, batch_size=b)
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        # A fixed generator per batch makes the validation loss comparable between evaluations.
        state = torch.get_rng_state()
        torch.manual_seed(batch_idx)
        loss, _ = self._loss(batch, 0.0, perturb=False)
        torch.set_rng_state(state)
        self.log("val/loss", loss, prog_bar=True, batch_size=batch["motion"].shape[0], sync_dist=True)

    def configure_optimizers(self):
        o = self.hparams.optim
        opt = torch.optim.AdamW(self.parameters(), lr=o["lr"], weight_decay=o.get("weight_decay", 0.0))
        if o.get("schedule", "constant") == "constant":  # MDM: constant lr
            return opt
        if o["schedule"] != "cosine":
            raise ValueError(f"unknown optim.schedule {o['schedule']!r}; choose constant or cosine")
        total, warmup = int(self.trainer.max_steps), int(o.get("warmup_steps", 0))
        if total <= 0:
            raise ValueError("optim.schedule=cosine needs trainer.max_steps > 0")

        def factor(step: int) -> float:  # linear warm-up, then cosine decay to 0 at max_steps
            if step < warmup:
                return (step + 1) / warmup
            progress = min(1.0, (step - warmup) / max(1, total - warmup))
            return 0.5 * (1.0 + math.cos(math.pi * progress))

        sched = torch.optim.lr_scheduler.LambdaLR(opt, factor)
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "step"}}
