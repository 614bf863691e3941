"""MDM's geometric losses (MDM §3 eq. 3-5, used by vvMDM too), for any representation.

With x0 the clean motion, x̂0 the network's estimate of it (converted from ε or v when the network predicts those),
FK = the representation's decode to joint positions (metres) of the de-normalised features, frames i = 1..N:

    L_pos  = 1/N     Σ_i ‖FK(x0^i) − FK(x̂0^i)‖²                        (eq. 3)
    L_foot = 1/(N−1) Σ_i ‖(FK(x̂0^{i+1}) − FK(x̂0^i)) · f_i‖²            (eq. 4)  f_i ∈ {0,1}^J: ground-truth contacts
    L_vel  = 1/(N−1) Σ_i ‖(x0^{i+1} − x0^i) − (x̂0^{i+1} − x̂0^i)‖²      (eq. 5)  on the features the model predicts
    L = L_diffusion + λ_pos L_pos + λ_vel L_vel + λ_foot L_foot

`reduction="mean"` (the default and the paper presets, as MDM's released code, whose masked L2 divides by frames x
joints x coordinates): the mean over joints (or features) too, 1/J of eq. 3-4 and 1/D of eq. 5.
`reduction="equation"`: each norm runs over a whole frame (all joints and coordinates, or all features), the mean
over frames only, as the equations are written (docs/presets_audit.md has the difference).

f_i is the representation's own contact rule unless ``contact_threshold`` is set: then a foot joint is in contact
where its ground-truth displacement to the next frame is at most that many metres (MDM's code for its a2m data:
‖p_{i+1} − p_i‖ ≤ 0.01 m per frame; HumanML3D's rule is about 0.045 m). Only the feet carry contacts, so the
other joints' terms of eq. 4 are zero.

Means run over valid frames only (frame pairs for the two velocity terms); each sample counts once in the batch.
The geometric terms are not scaled by the diffusion loss weight w(t) (MDM adds them unweighted). `time_weighting=
"alpha_bar"` scales each sample's terms by ᾱ_t (vvMDM's ω(t) = SNR/(SNR+1)): an ε network's x̂0 = (x_t −
√(1−ᾱ) ε̂)/√ᾱ makes ‖x̂0 − x0‖² = (1−ᾱ)/ᾱ ‖ε̂ − ε‖², about 4e8 × at t = 999 of the cosine schedule, and the weight
bounds it (docs/results/eps_fix).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from motiondiff.diffusion.process import masked_mean_per_sample

REDUCTIONS = ("equation", "mean")
TIME_WEIGHTINGS = ("none", "alpha_bar")


@dataclass
class GeometricLoss:
    representation: object  # motiondiff.data.representations.Representation
    lambda_pos: float = 1.0
    lambda_vel: float = 1.0
    lambda_foot: float = 1.0
    contact_threshold: float | None = None  # metres per frame; None: the representation's rule
    reduction: str = "mean"  # "mean": MDM's released code | "equation": eq. 3-5 (sum over a frame, mean over frames)
    time_weighting: str = "none"  # "none": MDM's unweighted terms | "alpha_bar": each sample's terms times ᾱ_t

    def __post_init__(self):
        if self.reduction not in REDUCTIONS:
            raise ValueError(f"loss.reduction={self.reduction!r}: choose from {', '.join(REDUCTIONS)}")
        if self.time_weighting not in TIME_WEIGHTINGS:
            raise ValueError(f"loss.time_weighting={self.time_weighting!r}: choose from {', '.join(TIME_WEIGHTINGS)}")

    @property
    def active(self) -> bool:
        return any(w > 0 for w in (self.lambda_pos, self.lambda_vel, self.lambda_foot))

    def terms(
        self,
        x0_hat: torch.Tensor,
        x0: torch.Tensor,
        mask: torch.Tensor,
        mean: torch.Tensor,
        std: torch.Tensor,
    ) -> dict[str, torch.Tensor]:
        """Per-sample terms (B,) from normalised x̂0 and x0 (B, N, D) and the valid-frame mask (B, N)."""
        rep = self.representation
        out: dict[str, torch.Tensor] = {}
        pair_mask = mask[:, 1:] & mask[:, :-1]
        if self.lambda_vel > 0:
            dv = (x0[:, 1:] - x0[:, :-1]) - (x0_hat[:, 1:] - x0_hat[:, :-1])
            out["vel"] = masked_mean_per_sample(self._per_frame(dv**2), pair_mask)
        if self.lambda_pos > 0 or self.lambda_foot > 0:
            # FK in float32 even under bf16 autocast: positions integrate velocities over frames.
            with torch.autocast(device_type=x0.device.type, enabled=False):
                raw_hat = x0_hat.float() * std + mean
                pos_hat = rep.decode(raw_hat)
                raw = x0.float() * std + mean
                with torch.no_grad():
                    pos = rep.decode(raw)
                if self.lambda_pos > 0:
                    out["pos"] = masked_mean_per_sample(self._per_frame(((pos - pos_hat) ** 2).sum(-1)), mask)
                if self.lambda_foot > 0:
                    with torch.no_grad():
                        contacts = self.contacts(pos, raw)  # (B, N-1, F): contact at frame i
                    feet = pos_hat[:, :, list(rep.contact_joints)]
                    slide = ((feet[:, 1:] - feet[:, :-1]) ** 2).sum(-1) * contacts
                    out["foot"] = masked_mean_per_sample(self._per_frame(slide), pair_mask)
        return out

    def _per_frame(self, values: torch.Tensor) -> torch.Tensor:
        """(B, N, K) squared terms of each frame -> what is averaged over frames: their sum (the equations' norm
        over the whole frame) or, with reduction="mean", the values themselves (averaged over K too)."""
        return values.sum(-1) if self.reduction == "equation" else values

    def contacts(self, pos: torch.Tensor, raw: torch.Tensor) -> torch.Tensor:
        """(B, N-1, F) 0/1 ground-truth contacts of the contact joints at frames 0..N-2."""
        if self.contact_threshold is None:
            return self.representation.foot_contacts(raw)[:, :-1]
        feet = pos[:, :, list(self.representation.contact_joints)]
        step = (feet[:, 1:] - feet[:, :-1]).norm(dim=-1)
        return (step <= self.contact_threshold).to(pos.dtype)

    def __call__(
        self, x0_hat, x0, mask, mean, std, alpha_bar: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """(λ-weighted sum averaged over the batch, {term: batch mean}) for logging. ``alpha_bar`` (B,): each sample's
        ᾱ_t, read when ``time_weighting="alpha_bar"`` (then the terms are logged weighted, as they enter the loss)."""
        terms = self.terms(x0_hat, x0, mask, mean, std)
        if self.time_weighting == "alpha_bar":
            if alpha_bar is None:
                raise ValueError("time_weighting='alpha_bar' needs each sample's alpha_bar")
            terms = {k: v * alpha_bar.to(v.dtype) for k, v in terms.items()}
        weights = {"pos": self.lambda_pos, "vel": self.lambda_vel, "foot": self.lambda_foot}
        total = sum(weights[k] * v.mean() for k, v in terms.items())
        return total, {k: v.mean().detach() for k, v in terms.items()}
