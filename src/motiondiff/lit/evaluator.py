"""LightningModules that train the evaluators on any dataset of ours (`python -m motiondiff.cli.train_evaluator`).

- `TextMotionEvaluatorModule`: captions and motions embedded contrastively. The loss is a symmetric InfoNCE over
  negative Euclidean distances (the distance R-precision ranks by), with a learned scale; other clips of the batch
  that carry the very same caption are not counted as negatives (generated captions such as "someone stays in
  place." are shared by many clips).
- `ActionClassifierModule`: the HumanAct12-protocol GRU classifier with cross-entropy on the dataset's labels.

Both keep the weights of their best validation epoch (R-precision top-3 / accuracy), which is what gets released.
"""

from __future__ import annotations

import copy

import lightning as L
import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from motiondiff.data.mirror import mirrored_labels
from motiondiff.data.representations.hml_features import evaluator_std, skeleton_for_dim
from motiondiff.metrics import r_precision
from motiondiff.models.evaluators.networks import ActionClassifierGRU, TextMotionEvaluator, motion_input


class _BestWeights(L.LightningModule):
    """Keeps a copy of the evaluator's weights at the best validation score. Ties go to the later epoch: on small
    validation splits the score saturates early, and the longer-trained weights separate motions better."""

    best_score: float = -np.inf
    best_state: dict | None = None

    def _keep_if_best(self, score: float, model: torch.nn.Module) -> None:
        if score >= self.best_score:
            self.best_score = score
            self.best_state = copy.deepcopy(model.state_dict())
            self.best_epoch = self.current_epoch

    def configure_optimizers(self):
        return torch.optim.AdamW(
            [p for p in self.parameters() if p.requires_grad], lr=self.hparams.lr, weight_decay=self.hparams.wd
        )


class MovementDecoder(nn.Module):
    """Training-only inverse of the movement encoder (codes at 1/4 rate -> features), for its pre-training."""

    def __init__(self, movement_size: int, hidden_size: int, output_size: int):
        super().__init__()
        self.main = nn.Sequential(
            nn.ConvTranspose1d(movement_size, hidden_size, 4, 2, 1),
            nn.LeakyReLU(0.2),
            nn.ConvTranspose1d(hidden_size, output_size, 4, 2, 1),
            nn.LeakyReLU(0.2),
        )
        self.out_net = nn.Linear(output_size, output_size)

    def forward(self, codes: torch.Tensor) -> torch.Tensor:
        return self.out_net(self.main(codes.transpose(1, 2)).transpose(1, 2))


class MovementAutoencoderModule(_BestWeights):
    """Stage 1 of the official recipe: the movement encoder learns to compress short windows of motion (L1
    reconstruction through `MovementDecoder`, plus a small penalty on code changes over time), so its codes keep
    the dynamics (velocities, direction of travel) that captions alone would not ask for. Stage 2 freezes it."""

    def __init__(self, evaluator: TextMotionEvaluator, mean: np.ndarray, std: np.ndarray, lr: float = 1e-3,
                 wd: float = 1e-4, smooth_weight: float = 1e-3):  # fmt: skip
        super().__init__()
        self.save_hyperparameters(ignore=["evaluator", "mean", "std"])
        self.evaluator = evaluator
        evaluator.set_normalisation(mean, evaluator_std(std))  # the T2M evaluator convention (feat_bias 5)
        enc = evaluator.movement_encoder
        self.decoder = MovementDecoder(enc.out_net.out_features, enc.main[0].out_channels, enc.main[0].in_channels)
        self.register_buffer("data_mean", torch.as_tensor(mean, dtype=torch.float32))
        self.register_buffer("data_std", torch.as_tensor(std, dtype=torch.float32))
        self._val_err: list[float] = []

    def _errors(self, batch: dict) -> tuple[torch.Tensor, torch.Tensor]:
        raw = batch["motion"] * self.data_std + self.data_mean
        x = self.evaluator.normalised_input(raw, batch["length"])
        codes = self.evaluator.movement_encoder(x)
        recon = self.decoder(codes)[:, : x.shape[1]]
        valid = torch.arange(x.shape[1], device=x.device)[None] < batch["length"].to(x.device)[:, None]
        rec = ((recon - x[:, : recon.shape[1]]).abs().mean(-1) * valid[:, : recon.shape[1]]).sum() / valid.sum()
        smooth = (codes[:, 1:] - codes[:, :-1]).abs().mean()
        return rec, smooth

    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        rec, smooth = self._errors(batch)
        loss = rec + self.hparams.smooth_weight * smooth
        self.log("train/recon", rec, prog_bar=True, batch_size=len(batch["length"]))
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        self._val_err.append(float(self._errors(batch)[0]))

    def on_validation_epoch_end(self) -> None:
        err = float(np.mean(self._val_err))
        self._val_err.clear()
        self.log("val/recon", err, prog_bar=True)
        self._keep_if_best(-err, self.evaluator.movement_encoder)


SUMMARY_DIMS = slice(0, 67)  # root (4) + root-relative joint positions (63) of the HumanML3D layout (SMPL-22)


def motion_summary(x: torch.Tensor, lengths: torch.Tensor, dims: slice = SUMMARY_DIMS) -> torch.Tensor:
    """Mean of the root and pose features over the first and the last quarter of each clip: (B, 2 * dims).
    The motion embedding is asked to predict it, so it describes how a motion starts and ends, not only what its
    caption names (generated captions name a few labels)."""
    n = torch.arange(x.shape[1], device=x.device)[None]
    quarter = (lengths.to(x.device) // 4).clamp(min=1)[:, None]
    first = (n < quarter).float()
    last = ((n >= lengths.to(x.device)[:, None] - quarter) & (n < lengths.to(x.device)[:, None])).float()
    feats = x[..., dims]
    return torch.cat([(feats * w[..., None]).sum(1) / w.sum(1, keepdim=True) for w in (first, last)], dim=-1)


class TextMotionEvaluatorModule(_BestWeights):
    """Stage 2: text and motion encoders trained contrastively; with `freeze_movement` the (pre-trained) movement
    encoder is kept fixed, as in the official recipe. `summary_weight` > 0 adds a linear read-out of
    `motion_summary` from the motion embedding (training only; the released evaluator is unchanged)."""

    def __init__(self, evaluator: TextMotionEvaluator, mean: np.ndarray, std: np.ndarray, lr: float = 1e-3,
                 wd: float = 1e-4, freeze_movement: bool = False, summary_weight: float = 0.0):  # fmt: skip
        super().__init__()
        self.save_hyperparameters(ignore=["evaluator", "mean", "std"])
        self.evaluator = evaluator
        evaluator.set_normalisation(mean, evaluator_std(std))  # the T2M evaluator convention (feat_bias 5)
        out = evaluator.motion_encoder.output_net[-1].out_features
        self.summary_head = nn.Linear(out, 2 * len(range(*SUMMARY_DIMS.indices(mean.shape[0]))))
        if freeze_movement:
            evaluator.movement_encoder.requires_grad_(False)
        self.register_buffer("data_mean", torch.as_tensor(mean, dtype=torch.float32))
        self.register_buffer("data_std", torch.as_tensor(std, dtype=torch.float32))
        self.log_scale = torch.nn.Parameter(torch.zeros(()))
        self._val: list[tuple[torch.Tensor, torch.Tensor]] = []

    def on_train_epoch_start(self) -> None:
        if self.hparams.freeze_movement:
            self.evaluator.movement_encoder.eval()  # no dropout in a frozen encoder

    def _embed(self, batch: dict) -> tuple[torch.Tensor, torch.Tensor]:
        raw = batch["motion"] * self.data_std + self.data_mean  # the evaluator reads de-normalised features
        return self.evaluator.encode_text(batch["text"]), self.evaluator.encode_motion(raw, batch["length"])

    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        text, motion = self._embed(batch)
        if self.hparams.summary_weight > 0:
            target = motion_summary(batch["motion"], batch["length"])  # dataset-normalised: dims weigh alike
            summary = F.mse_loss(self.summary_head(motion), target)
            self.log("train/summary", summary, batch_size=len(target))
        logits = -torch.cdist(motion, text) * self.log_scale.exp()
        same = torch.tensor([[a == b for b in batch["text"]] for a in batch["text"]], device=logits.device)
        logits = logits.masked_fill(same & ~torch.eye(len(same), dtype=torch.bool, device=logits.device), -1e4)
        target = torch.arange(len(logits), device=logits.device)
        loss = 0.5 * (F.cross_entropy(logits, target) + F.cross_entropy(logits.T, target))
        self.log("train/loss", loss, prog_bar=True, batch_size=len(target))
        if self.hparams.summary_weight > 0:
            loss = loss + self.hparams.summary_weight * summary
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        self._val.append(tuple(e.detach().cpu() for e in self._embed(batch)))

    def on_validation_epoch_end(self) -> None:
        text = torch.cat([t for t, _ in self._val])
        motion = torch.cat([m for _, m in self._val])
        self._val.clear()
        top3 = r_precision(text.double(), motion.double(), top_k=3, pool_size=32)["top3"]
        self.log("val/r_precision_top3", top3, prog_bar=True)
        self._keep_if_best(top3, self.evaluator)


class ActionClassifierModule(_BestWeights):
    """Two augmentations for small datasets: `crop_min` < 1 trains on random windows of at least that fraction of
    each clip (its label holds for most windows); `mirror` flips half the clips left/right and swaps labels that
    name a side ("wave-left-hand" <-> "wave-right-hand"), so every left/right class sees both sides' examples.
    `select_by` picks the kept weights: "accuracy" over all val clips, or "balanced_accuracy" (the mean of the
    per-class recalls over the classes present in val), which counts a class of 2 clips as much as one of 40."""

    SELECT_BY = ("accuracy", "balanced_accuracy")

    def __init__(self, classifier: ActionClassifierGRU, mean: np.ndarray, std: np.ndarray, num_joints: int,
                 lr: float = 1e-3, wd: float = 1e-4, crop_min: float = 1.0, mirror: bool = False,
                 action_names: list[str] | None = None, select_by: str = "accuracy"):  # fmt: skip
        super().__init__()
        if select_by not in self.SELECT_BY:
            raise ValueError(f"select_by must be one of {self.SELECT_BY}, got {select_by!r}")
        self.save_hyperparameters(ignore=["classifier", "mean", "std"])
        if mirror:
            if not action_names:
                raise ValueError("mirror augmentation needs the action names to swap left/right labels")
            self.register_buffer("mirror_label", torch.tensor(mirrored_labels(action_names)))
            self.register_buffer("mirror_joints", torch.tensor(skeleton_for_dim(mean.shape[0]).mirror_permutation))
        self.classifier = classifier
        self.register_buffer("data_mean", torch.as_tensor(mean, dtype=torch.float32))
        self.register_buffer("data_std", torch.as_tensor(std, dtype=torch.float32))
        self._correct = np.zeros(classifier.linear2.out_features)
        self._total = np.zeros(classifier.linear2.out_features)

    def _logits(self, batch: dict, flip: torch.Tensor | None = None) -> torch.Tensor:
        raw = batch["motion"] * self.data_std + self.data_mean
        x = motion_input(self.classifier, raw, self.hparams.num_joints)  # (B, J, 3, T), x = the body's side axis
        if flip is not None:
            mirrored = x[:, self.mirror_joints] * torch.tensor([-1.0, 1.0, 1.0], device=x.device)[:, None]
            x = torch.where(flip[:, None, None, None], mirrored, x)
        return self.classifier(x, batch["length"])[0]

    def _random_windows(self, batch: dict) -> dict:
        lengths = batch["length"]
        keep = torch.rand(len(lengths)) * (1 - self.hparams.crop_min) + self.hparams.crop_min
        new_len = (lengths * keep).long().clamp(min=min(8, int(lengths.min())))
        start = (torch.rand(len(lengths)) * (lengths - new_len + 1)).long()
        motion = torch.zeros_like(batch["motion"][:, : int(new_len.max())])
        for i, (s, n) in enumerate(zip(start.tolist(), new_len.tolist(), strict=True)):
            motion[i, :n] = batch["motion"][i, s : s + n]
        return {**batch, "motion": motion, "length": new_len}

    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        if self.hparams.crop_min < 1.0:
            batch = self._random_windows(batch)
        target, flip = batch["action"], None
        if self.hparams.mirror:
            flip = torch.rand(len(target), device=target.device) < 0.5
            target = torch.where(flip, self.mirror_label[target], target)
        loss = F.cross_entropy(self._logits(batch, flip), target)
        self.log("train/loss", loss, prog_bar=True, batch_size=len(batch["action"]))
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        pred = self._logits(batch).argmax(-1).cpu().numpy()
        target = batch["action"].cpu().numpy()
        np.add.at(self._total, target, 1)
        np.add.at(self._correct, target, pred == target)

    def on_validation_epoch_end(self) -> None:
        present = self._total > 0
        scores = {"accuracy": self._correct.sum() / max(1, self._total.sum()),
                  "balanced_accuracy": float((self._correct[present] / self._total[present]).mean()) if present.any() else 0.0}  # fmt: skip
        self._correct[:] = 0
        self._total[:] = 0
        for name, value in scores.items():
            self.log(f"val/{name}", float(value), prog_bar=True)
        self.val_scores = {k: float(v) for k, v in scores.items()}
        self._keep_if_best(float(scores[self.hparams.select_by]), self.classifier)
        if self.best_epoch == self.current_epoch:
            self.best_scores = dict(self.val_scores)
