"""The Gaussian forward process q(x_t | x_0) = N(√ᾱ_t x_0, (1 − ᾱ_t) I) and everything derived from it.

Knows nothing about motion or networks: tensors are (B, ...) with t a long tensor (B,) of step indices 0..T−1;
every per-step coefficient is looked up at t and broadcast over the trailing dims. Tables are float64 on the CPU and
cast once per (device, dtype) at first use, so float32/bf16 training never loses the schedule's precision at build time.

Conversions take (value, x_t, t), with a = √ᾱ_t, b = √(1 − ᾱ_t), x_t = a x0 + b ε and v = a ε − b x0:
x0 = (x_t − b ε)/a, ε = (x_t − a x0)/b, x0 = a x_t − b v, ε = b x_t + a v.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch

from motiondiff.diffusion.schedules import make_betas

PREDICTIONS = ("x0", "eps", "v")
WEIGHTINGS = ("none", "snr_v", "min_snr")


def masked_mean_per_sample(values: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
    """Mean of ``values`` (B, N, ...) per sample over the elements whose frame is valid in ``mask`` (B, N) bool → (B,).

    A sample with no valid frame gets 0 (its denominator is clamped to 1), so it neither crashes nor weighs on the loss.
    """
    if mask is None:
        return values.reshape(values.shape[0], -1).mean(dim=1)
    m = mask.to(values.dtype).reshape(mask.shape + (1,) * (values.ndim - mask.ndim))
    per_frame = math.prod(values.shape[mask.ndim :])
    total = (values * m).reshape(values.shape[0], -1).sum(dim=1)
    return total / (mask.reshape(mask.shape[0], -1).sum(dim=1).to(values.dtype) * per_frame).clamp_min(1)


class GaussianDiffusion:
    """Forward process, x0/ε/v targets and conversions, loss weights and the DDPM posterior for one β schedule.

    ``prediction`` is what the network outputs: ``x0`` (MDM), ``eps`` (DDPM, GuidedMotion) or ``v`` (vvMDM).
    ``weighting`` scales each sample's loss: ``none`` → 1; ``snr_v`` → SNR/(SNR+1) = ᾱ_t (vvMDM's ω(t));
    ``min_snr`` → min-SNR-γ (Hang et al. 2023), expressed for the prediction: x0: min(SNR, γ), ε: min(SNR, γ)/SNR,
    v: min(SNR, γ)/(SNR+1). ``None`` picks ``snr_v`` for v and ``none`` otherwise.
    """

    def __init__(
        self,
        betas: torch.Tensor | Sequence[float],
        prediction: str = "x0",
        weighting: str | None = None,
        min_snr_gamma: float = 5.0,
    ) -> None:
        if prediction not in PREDICTIONS:
            raise ValueError(f"unknown prediction {prediction!r}; choose one of {list(PREDICTIONS)}")
        weighting = ("snr_v" if prediction == "v" else "none") if weighting is None else weighting
        if weighting not in WEIGHTINGS:
            raise ValueError(f"unknown loss weighting {weighting!r}; choose one of {list(WEIGHTINGS)}")
        betas = torch.as_tensor(betas, dtype=torch.float64).detach().cpu()
        if betas.ndim != 1 or betas.numel() == 0 or not bool(((betas > 0) & (betas < 1)).all()):
            raise ValueError("betas must be a non-empty 1-D sequence with every value in (0, 1)")
        self.prediction, self.weighting, self.min_snr_gamma = prediction, weighting, float(min_snr_gamma)
        self.betas = betas
        self.alphas = 1.0 - betas
        self.alphas_cumprod = torch.cumprod(self.alphas, dim=0)
        self.alphas_cumprod_prev = torch.cat([betas.new_ones(1), self.alphas_cumprod[:-1]])
        ab, ab_prev = self.alphas_cumprod, self.alphas_cumprod_prev
        self.sqrt_alphas_cumprod = ab.sqrt()
        self.sqrt_one_minus_alphas_cumprod = (1.0 - ab).sqrt()
        self.snr = ab / (1.0 - ab)
        # q(x_{t−1} | x_t, x0) = N(c1 x0 + c2 x_t, β̃_t), β̃_t = β_t (1 − ᾱ_{t−1})/(1 − ᾱ_t)   (Ho et al. 2020, eq. 7)
        self.posterior_variance = betas * (1.0 - ab_prev) / (1.0 - ab)
        # β̃_0 = 0: its log is clipped to β̃_1's, as in improved-diffusion (the t = 0 step adds no noise anyway).
        clip_from = self.posterior_variance[1] if len(betas) > 1 else self.posterior_variance[0]
        self.posterior_log_variance_clipped = torch.cat([clip_from.reshape(1), self.posterior_variance[1:]]).log()
        self.posterior_mean_coef1 = betas * ab_prev.sqrt() / (1.0 - ab)
        self.posterior_mean_coef2 = (1.0 - ab_prev) * self.alphas.sqrt() / (1.0 - ab)
        clipped = self.snr.clamp_max(self.min_snr_gamma)
        self.loss_weights = {
            "none": torch.ones_like(ab),
            "snr_v": ab,  # SNR/(SNR + 1) = ᾱ_t
            "min_snr": {"x0": clipped, "eps": clipped / self.snr, "v": clipped / (self.snr + 1)}[prediction],
        }[weighting]
        self._cache: dict[tuple[torch.device, torch.dtype], dict[str, torch.Tensor]] = {}

    @classmethod
    def create(
        cls,
        schedule: str = "cosine",
        num_steps: int = 1000,
        prediction: str = "x0",
        weighting: str | None = None,
        min_snr_gamma: float = 5.0,
        **schedule_kw: float,
    ) -> GaussianDiffusion:
        """Build from a schedule name (see ``schedules.make_betas``): the Hydra-friendly constructor."""
        return cls(make_betas(schedule, num_steps, **schedule_kw), prediction, weighting, min_snr_gamma)

    @property
    def num_steps(self) -> int:
        return len(self.betas)

    def __repr__(self) -> str:
        return f"GaussianDiffusion(T={self.num_steps}, prediction={self.prediction!r}, weighting={self.weighting!r})"

    def respace(self, timesteps: Sequence[int]) -> GaussianDiffusion:
        """The process restricted to the kept steps k_0 < … < k_{S−1} (Nichol & Dhariwal 2021, respacing).

        β'_i = 1 − ᾱ_{k_i}/ᾱ_{k_{i−1}} (ᾱ_{k_{−1}} = 1), so step i of the new process has ᾱ'_i = ᾱ_{k_i}.
        """
        kept = torch.as_tensor(list(timesteps), dtype=torch.long)
        if kept.ndim != 1 or kept.numel() == 0 or bool((kept.diff() <= 0).any()):
            raise ValueError("respace needs a non-empty, strictly increasing list of timesteps")
        if int(kept[0]) < 0 or int(kept[-1]) >= self.num_steps:
            raise ValueError(f"timesteps must lie in [0, {self.num_steps - 1}], got {kept[0]}..{kept[-1]}")
        ab = self.alphas_cumprod[kept]
        betas = 1.0 - ab / torch.cat([ab.new_ones(1), ab[:-1]])
        return GaussianDiffusion(betas, self.prediction, self.weighting, self.min_snr_gamma)

    # ---- table lookup -------------------------------------------------------------------------------------------
    _TABLES = (
        "betas",
        "alphas_cumprod",
        "alphas_cumprod_prev",
        "sqrt_alphas_cumprod",
        "sqrt_one_minus_alphas_cumprod",
        "snr",
        "loss_weights",
        "posterior_variance",
        "posterior_log_variance_clipped",
        "posterior_mean_coef1",
        "posterior_mean_coef2",
    )

    def _extract(self, name: str, t: torch.Tensor, like: torch.Tensor) -> torch.Tensor:
        """Table ``name`` at t, in ``like``'s dtype/device, shaped (B, 1, …, 1) to broadcast against ``like``."""
        key = (like.device, like.dtype)
        tables = self._cache.get(key)
        if tables is None:
            tables = {n: getattr(self, n).to(device=like.device, dtype=like.dtype) for n in self._TABLES}
            self._cache[key] = tables
        values = tables[name][t]
        return values.reshape(values.shape + (1,) * (like.ndim - values.ndim))

    # ---- forward process and conversions --------------------------------------------------------------------
    def q_sample(self, x0: torch.Tensor, t: torch.Tensor, noise: torch.Tensor | None = None) -> torch.Tensor:
        """x_t = √ᾱ_t x0 + √(1 − ᾱ_t) ε (ε ~ N(0, I) drawn here when ``noise`` is None)."""
        noise = torch.randn_like(x0) if noise is None else noise
        a = self._extract("sqrt_alphas_cumprod", t, x0)
        return a * x0 + self._extract("sqrt_one_minus_alphas_cumprod", t, x0) * noise

    def eps_from_x0(self, x0: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """ε = (x_t − √ᾱ_t x0)/√(1 − ᾱ_t) (ill-conditioned at small t, where 1 − ᾱ_t → 0)."""
        a, b = self._extract("sqrt_alphas_cumprod", t, x_t), self._extract("sqrt_one_minus_alphas_cumprod", t, x_t)
        return (x_t - a * x0) / b

    def x0_from_eps(self, eps: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """x0 = (x_t − √(1 − ᾱ_t) ε)/√ᾱ_t (ill-conditioned at large t, where ᾱ_t → 0)."""
        a, b = self._extract("sqrt_alphas_cumprod", t, x_t), self._extract("sqrt_one_minus_alphas_cumprod", t, x_t)
        return (x_t - b * eps) / a

    def v_from_x0_eps(self, x0: torch.Tensor, eps: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """v = √ᾱ_t ε − √(1 − ᾱ_t) x0 (Salimans & Ho 2022)."""
        a, b = self._extract("sqrt_alphas_cumprod", t, x0), self._extract("sqrt_one_minus_alphas_cumprod", t, x0)
        return a * eps - b * x0

    def x0_from_v(self, v: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """x0 = √ᾱ_t x_t − √(1 − ᾱ_t) v (a rotation of (x_t, v): well-conditioned at every t)."""
        a, b = self._extract("sqrt_alphas_cumprod", t, x_t), self._extract("sqrt_one_minus_alphas_cumprod", t, x_t)
        return a * x_t - b * v

    def eps_from_v(self, v: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """ε = √(1 − ᾱ_t) x_t + √ᾱ_t v."""
        a, b = self._extract("sqrt_alphas_cumprod", t, x_t), self._extract("sqrt_one_minus_alphas_cumprod", t, x_t)
        return b * x_t + a * v

    def to_x0(self, model_output: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """x̂0 from whatever the network predicts (``self.prediction``)."""
        if self.prediction == "x0":
            return model_output
        if self.prediction == "eps":
            return self.x0_from_eps(model_output, x_t, t)
        return self.x0_from_v(model_output, x_t, t)

    def to_eps(self, model_output: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """ε̂ from whatever the network predicts (``self.prediction``)."""
        if self.prediction == "x0":
            return self.eps_from_x0(model_output, x_t, t)
        if self.prediction == "eps":
            return model_output
        return self.eps_from_v(model_output, x_t, t)

    def target(self, x0: torch.Tensor, noise: torch.Tensor, t: torch.Tensor) -> torch.Tensor:
        """The regression target for ``self.prediction``: x0, ε, or v = √ᾱ_t ε − √(1 − ᾱ_t) x0."""
        if self.prediction == "x0":
            return x0
        if self.prediction == "eps":
            return noise
        return self.v_from_x0_eps(x0, noise, t)

    # ---- loss ---------------------------------------------------------------------------------------------------
    def alpha_bar(self, t: torch.Tensor, dtype: torch.dtype | None = None) -> torch.Tensor:
        """ᾱ_t per sample, shape (B,), from the cached tables; float32 by default."""
        return self._extract("alphas_cumprod", t, torch.empty(0, dtype=dtype or torch.float32, device=t.device))

    def loss_weight(self, t: torch.Tensor, dtype: torch.dtype | None = None) -> torch.Tensor:
        """Per-sample weight w(t), shape (B,), for ``self.weighting`` (see the class docstring); float32 by default."""
        return self._extract("loss_weights", t, torch.empty(0, dtype=dtype or torch.float32, device=t.device))

    def loss_per_sample(
        self,
        model_output: torch.Tensor,
        x0: torch.Tensor,
        noise: torch.Tensor,
        t: torch.Tensor,
        mask: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """w(t) · mean over the valid elements of (target − output)², one value per sample (B,)."""
        err = (self.target(x0, noise, t) - model_output) ** 2
        return self.loss_weight(t, err.dtype) * masked_mean_per_sample(err, mask)

    def loss(self, model_output: torch.Tensor, x0: torch.Tensor, noise: torch.Tensor, t: torch.Tensor,
             mask: torch.Tensor | None = None) -> torch.Tensor:  # fmt: skip
        """Weighted MSE: per sample the mean over its valid elements (frames where ``mask`` (B, N) is True, all
        features), times w(t); then the plain mean over the batch (every sample counts once, whatever its length)."""
        return self.loss_per_sample(model_output, x0, noise, t, mask).mean()

    # ---- reverse process -----------------------------------------------------------------------------------
    def q_posterior(
        self, x0: torch.Tensor, x_t: torch.Tensor, t: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """q(x_{t−1} | x_t, x0): mean = β_t√ᾱ_{t−1}/(1−ᾱ_t) x0 + (1−ᾱ_{t−1})√α_t/(1−ᾱ_t) x_t, variance β̃_t, clipped log β̃_t."""
        mean = self._extract("posterior_mean_coef1", t, x_t) * x0 + self._extract("posterior_mean_coef2", t, x_t) * x_t
        return (
            mean,
            self._extract("posterior_variance", t, x_t),
            self._extract("posterior_log_variance_clipped", t, x_t),
        )
