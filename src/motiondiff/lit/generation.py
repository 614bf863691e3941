"""The one generation chain: conditions -> the model's condition batches -> sampling -> de-normalised features.

Every caller that makes motion from prompts, actions or nothing (the pipelines, sample.py, the evaluation protocol,
the behaviour report) goes through `generate_features`, and so does editing, with its known frames (in-painting,
`lit.inpainting`); GuidedMotion samples its latent levels in `pipelines.guided`. Every one of them checks its output
with `check_finite_output` before anything is written: a NaN motion is one error line, never a file of NaNs.
"""

from __future__ import annotations

import numpy as np
import torch

from motiondiff.diffusion.samplers import select_timesteps
from motiondiff.lit.conditions import condition_batch
from motiondiff.lit.inpainting import inpaint, known_batch
from motiondiff.models.bf16_inference import bf16_inference
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import MAX_NUM_SAMPLES  # the bounds table

SAMPLE_BATCH = 64  # motions sampled at once: noise and activations for this many, whatever num_samples asks
MAX_LONG_SAMPLES = SAMPLE_BATCH  # long motions (timed prompts) are sampled in one batch


def check_num_samples(value, limit: int = MAX_NUM_SAMPLES) -> int:
    """``num_samples`` as a whole number 1..limit, else UsageError naming the bound and the fix."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= limit:
        raise UsageError(f"num_samples={value!r}: must be a whole number from 1 to {limit} (motions are sampled "
                         f"{SAMPLE_BATCH} at a time); for more, run again with another seed=")  # fmt: skip
    return value


class NonFiniteOutput(UsageError):
    """The model generated NaN or infinite numbers (broken weights or extreme settings); nothing is written."""


def check_finite_output(values, what: str = "the generated motion") -> None:
    """Raise NonFiniteOutput when ``values`` (a tensor, an array or a list of them) hold a NaN or an infinity."""
    items = values if isinstance(values, list | tuple) else [values]
    bad = total = 0
    for v in items:
        v = v.detach().float().cpu().numpy() if isinstance(v, torch.Tensor) else np.asarray(v, dtype=np.float64)
        bad, total = bad + int((~np.isfinite(v)).sum()), total + v.size
    if bad:
        raise NonFiniteOutput(f"{what} holds {bad} NaN or infinite value(s) of {total}, so nothing was written: the "
                              "model's weights are broken or the settings extreme; use another checkpoint (e.g. "
                              "checkpoint=shipped) or a lower guidance=")  # fmt: skip


def fitted_steps(module, steps, default: int | None) -> int | None:
    """The sampling steps to run: ``steps`` as given (a whole number that fits the model's T diffusion steps), else
    ``default`` capped at T, so a model trained with few steps (MDM Tab. 6, T = 10) samples with DDIM over its whole
    chain instead of failing on DDIM-50. None: every step of the chain (DDPM's default)."""
    num_steps = int(module.diffusion.num_steps)
    if steps is not None:
        if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= num_steps:
            raise UsageError(f"steps must be between 1 and the model's {num_steps} diffusion steps, got {steps!r}")
    else:
        steps = None if default is None else min(int(default), num_steps)
    spacing = getattr(module, "timestep_spacing", None)
    if spacing is not None:  # a spacing that cannot take these steps is named before anything samples
        try:
            select_timesteps(num_steps, steps, spacing, module.diffusion.alphas_cumprod.tolist())
        except ValueError as err:
            raise UsageError(f"timestep_spacing={spacing}: {err}") from err
    return steps


def resolved_sampling(module, sampler: str | None, steps) -> tuple[str, int | None]:
    """(sampler, steps) that run for a request: "auto"/None is the model's own sampler, and steps not given are that
    sampler's default for this model (``default_steps``), both fitted to its diffusion steps (`fitted_steps`)."""
    name = module.resolve_sampler(sampler)
    return name, fitted_steps(module, steps, module.default_steps(name))


def feed_forward_shape(module, motions: int, frames: int) -> tuple[int, int, int]:
    """(rows, d_model, ff_size) of the denoiser's feed-forward matmul when sampling `motions` guided motions of
    `frames` frames (two streams each): what `hardware.inference_precision` times to choose bf16 or not."""
    arch = module.hparams.model
    return (2 * motions * frames, int(arch.get("d_model", 512)), int(arch.get("ff_size", 1024)))


def sampling_precision(module, precision: str = "32-true"):
    """The context the denoiser samples in: bf16 autocast for "bf16-mixed" (as such models train; the sampler's own
    arithmetic stays float32) with the matmul weights cast once rather than at every step, full precision for
    anything else."""
    return bf16_inference(module, module.device.type, enabled=str(precision).startswith("bf16"))


@torch.inference_mode()
def generate_features(
    module,
    conditions: list,
    lengths: torch.Tensor,
    batch_size: int = SAMPLE_BATCH,
    generator: torch.Generator | None = None,
    bar=None,
    precision: str = "32-true",
    *,
    known: list | None = None,
    keep: list | None = None,
    what: str = "the generated motion",
    **sampling,
) -> list[np.ndarray]:
    """De-normalised features (N_i, D), one per condition (prompt, action name/id or None), at the given lengths.

    `sampling`: guidance, sampler, steps, eta, ... (see MotionDiffusionModule.sample). Conditions are sorted by
    length so each batch pads little; `bar` (a tqdm bar or None) is advanced per motion; `precision` "bf16-mixed" runs
    the denoiser under bf16 autocast (as such models train), anything else in full precision. On the CPU, with a
    deterministic sampler (DDIM with eta=0, DPM-Solver++) and equal lengths, batches of SAMPLE_BATCH give the motions
    of one batch up to float rounding (torch draws CPU noise 16 values at a time, in one stream).

    Editing: ``known`` (de-normalised features (N_i, D) per item) and ``keep`` ((N_i, D) bool) hold each item's known
    part (`lit.inpainting.inpaint`, with `sampling`'s mode, hold_from and reconstruction); the result is the input's
    own numbers there. Edits are batched in the order given (a seed draws the noise it drew before editing came
    through this chain). ``what`` names the motion in the non-finite error."""
    lengths = torch.as_tensor(lengths)
    if len(conditions) != len(lengths):
        raise ValueError(f"{len(conditions)} conditions for {len(lengths)} lengths")
    if known is not None and (keep is None or not len(known) == len(keep) == len(lengths)):
        raise ValueError(f"give one known motion and one keep mask per length ({len(lengths)}), got {len(known)} "
                         f"and {None if keep is None else len(keep)}")  # fmt: skip
    if known is None:
        order = torch.argsort(lengths, descending=True, stable=True)  # equal lengths keep their order
    else:
        order = torch.arange(len(lengths))
    results: dict[int, np.ndarray] = {}
    for s in range(0, len(order), batch_size):
        idx = order[s : s + batch_size].tolist()
        cond = condition_batch(module, [conditions[i] for i in idx])
        lens = lengths[idx]
        with sampling_precision(module, precision):
            if known is None:
                feats = module.sample(cond, lens, generator=generator, **sampling)
            else:
                x_known, x_keep = known_batch(module, known, keep, idx)
                feats = inpaint(module, cond, x_known, x_keep, lens, generator=generator, **sampling)
        feats = module.denormalise(feats.float()).cpu().numpy()
        check_finite_output(feats, what)
        for row, i in enumerate(idx):
            results[i] = feats[row, : int(lengths[i])]
            if known is not None:  # the kept part is the input's own numbers (not normalised and back)
                results[i] = np.where(keep[i], known[i], results[i])
        if bar is not None:
            bar.update(len(idx))
    return [results[i] for i in range(len(conditions))]
