"""The measured pieces of work: a training step of the MDM denoiser, its forward pass, sampling one or many motions
with each sampler, and text encoding. Training and forward use random features of the HumanML3D width and random
caption features (no text encoder runs in a training step: the project looks captions up in a pre-computed table);
sampling uses a real model (the shipped one by default) and a real prompt. The rows compared with the official MDM
code (``guided_forward``, ``feature_sampling``) use a randomly initialised denoiser and random caption features on
both sides: the cost of a step does not depend on the weights."""

from __future__ import annotations

import contextlib
from collections.abc import Callable

import torch

from motiondiff.bench.flops import count_flops
from motiondiff.diffusion import GaussianDiffusion, make_betas
from motiondiff.diffusion.dpm_solver import dpmpp_sample
from motiondiff.diffusion.guidance import classifier_free_guidance, guided_model_fn
from motiondiff.diffusion.samplers import ddim_sample, ddpm_sample, select_timesteps
from motiondiff.lit.conditions import condition_batch
from motiondiff.models.bf16_inference import bf16_inference
from motiondiff.models.denoiser import PRESETS, MDMDenoiser
from motiondiff.text.cache import TextEmbeddingCache
from motiondiff.text.encoders import build_text_encoder

FEATURE_DIM = 263  # HumanML3D features
COND_DIM = 384  # MiniLM sentence features (the project's default text encoder)
PROMPT = "a person walks forward and waves both hands"
TINY = dict(d_model=32, num_layers=1, num_heads=2, ff_size=64, dropout=0.1, activation="gelu")  # --quick's network
GUIDANCE = 2.5  # MDM's default guidance scale (the comparison rows; the cost does not depend on it unless it is 0 or 1)


def autocast(bf16: bool):
    return torch.autocast("cpu", dtype=torch.bfloat16) if bf16 else contextlib.nullcontext()


def build_denoiser(preset: str | dict, seed: int = 0) -> MDMDenoiser:
    torch.manual_seed(seed)
    return MDMDenoiser.from_config(FEATURE_DIM, preset=PRESETS[preset] if isinstance(preset, str) else preset,
                                   cond_dim=COND_DIM)  # fmt: skip


def random_batch(batch: int, frames: int, seed: int = 0) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    return {"x0": torch.randn(batch, frames, FEATURE_DIM, generator=g),
            "cond": torch.randn(batch, COND_DIM, generator=g), "mask": torch.ones(batch, frames, dtype=torch.bool)}  # fmt: skip


def window_batch(batch: int, frames: int = 120, shortest: int = 40,
                 seed: int = 1) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:  # fmt: skip
    """``(x0, mask, cond)`` for ``batch_step``: random clips padded to ``frames`` with valid lengths drawn over
    ``shortest``-``frames`` (the full-Bandai recipe's 40-120-frame windows), random caption features."""
    g = torch.Generator().manual_seed(seed)
    lengths = torch.randint(shortest, frames + 1, (batch,), generator=g)
    x0 = torch.randn(batch, frames, FEATURE_DIM, generator=g)
    mask = torch.arange(frames)[None] < lengths[:, None]
    return x0, mask, torch.randn(batch, COND_DIM, generator=g)


def batch_step(preset: str | dict, bf16: bool = False,
               model: MDMDenoiser | None = None) -> Callable[[torch.Tensor, torch.Tensor, torch.Tensor], float]:  # fmt: skip
    """``step(x0, mask, cond)``: one MDM training step as train.py runs it on a batch (B, N, 263) with its valid-frame
    mask (B, N) and caption features (B, 384): q_sample at random t, 10% condition drop, x0 loss, backward,
    gradient clipping at 1.0 and AdamW, on one denoiser of ``preset`` (or ``model``) kept across calls."""
    model = (model if model is not None else build_denoiser(preset)).train()
    diffusion = GaussianDiffusion(make_betas("cosine", 1000), prediction="x0")
    opt = torch.optim.AdamW(model.parameters(), lr=1e-4)

    def step(x0: torch.Tensor, mask: torch.Tensor, cond: torch.Tensor) -> float:
        batch = x0.shape[0]
        t = torch.randint(0, diffusion.num_steps, (batch,))
        noise = torch.randn_like(x0)
        with autocast(bf16):
            out = model(diffusion.q_sample(x0, t, noise), t, cond=cond, mask=mask, drop_cond=torch.rand(batch) < 0.1)
            loss = diffusion.loss(out, x0, noise, t, mask=mask)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        return float(loss.detach())

    return step


def train_step(preset: str | dict, batch: int, frames: int, bf16: bool = False) -> Callable[[], float]:
    """``batch_step`` on one fixed random batch of ``batch`` x ``frames`` frames (every frame valid)."""
    on_batch = batch_step(preset, bf16)
    data = random_batch(batch, frames)

    def step() -> float:
        return on_batch(data["x0"], data["mask"], data["cond"])

    return step


def forward(
    preset: str | dict, batch: int, frames: int, bf16: bool = False, compile: bool = False
) -> Callable[[], torch.Tensor]:
    """The denoiser's inference forward (eval mode: PyTorch's fused encoder path), as each sampling step runs it;
    ``compile``: through torch.compile (inductor; the first call compiles)."""
    model = build_denoiser(preset).eval()
    if compile:
        model = torch.compile(model)
    data = random_batch(batch, frames)
    t = torch.full((batch,), 500)

    @torch.inference_mode()
    def run() -> torch.Tensor:
        with autocast(bf16):
            return model(data["x0"], t, cond=data["cond"], mask=data["mask"])

    return run


def forward_flops(preset: str | dict, batch: int, frames: int, guided: bool = False) -> int:
    """FLOPs of that forward (``guided``: of ``guided_forward``). Counted on the unfused path (train mode, no grad):
    PyTorch's FLOP counter does not see inside the fused inference kernels, which compute the same products."""

    model = build_denoiser(preset).train()
    data = random_batch(batch, frames)
    t = torch.full((batch,), 500)
    with torch.no_grad():
        if guided:
            return count_flops(lambda: classifier_free_guidance(model, data["x0"], t, data["cond"], GUIDANCE,
                                                                mask=data["mask"]))  # fmt: skip
        return count_flops(lambda: model(data["x0"], t, cond=data["cond"], mask=data["mask"]))


def guided_forward(preset: str | dict, batch: int, frames: int, scale: float = GUIDANCE) -> Callable[[], torch.Tensor]:
    """The network work of one guided sampling step: classifier-free guidance as the samplers run it (one forward of
    the doubled [conditional; unconditional] batch, eval mode, inference_mode)."""

    model = build_denoiser(preset).eval()
    data = random_batch(batch, frames)
    t = torch.full((batch,), 500)

    @torch.inference_mode()
    def run() -> torch.Tensor:
        return classifier_free_guidance(model, data["x0"], t, data["cond"], scale, mask=data["mask"])

    return run


class _Stop(Exception):
    pass


def _stopper(limit: int, total: int):
    """(xt_hook that stops a chain after ``limit`` steps or None when it runs to the end, reset)."""
    done = [0]

    def stop_after(x, t_next):
        done[0] += 1
        if done[0] >= limit:
            raise _Stop
        return x

    def reset() -> None:
        done[0] = 0

    return (stop_after if limit < total else None), reset


def sampling(module, count: int, frames: int, sampler: str, steps: int | None, guidance: float,
             timed_steps: int | None = None) -> tuple[Callable[[], object], int, int]:  # fmt: skip
    """``count`` motions of ``frames`` frames from PROMPT. Returns (run, steps_total, steps_run): when ``timed_steps``
    is below the chain's length the run stops after that many steps (the caller scales the time: every step of a
    chain costs the same forward), so DDPM-1000 at batch 32 fits the bench's time budget."""

    cond = condition_batch(module, [PROMPT] * count)  # encoded once, then cached: not part of the timing
    lengths = torch.full((count,), frames)
    total = len(select_timesteps(module.diffusion.num_steps, steps if sampler == "ddpm" else steps or 50))
    limit = total if timed_steps is None else min(total, timed_steps)
    hook, reset = _stopper(limit, total)

    def run():
        reset()
        with contextlib.suppress(_Stop):
            module.sample(cond, lengths, guidance=guidance, sampler=sampler, steps=steps, xt_hook=hook)

    return run, total, limit


def feature_sampling(preset: str | dict, frames: int, sampler: str, steps: int | None, scale: float = GUIDANCE,
                     timed_steps: int | None = None, bf16: bool = False) -> tuple[Callable[[], object], int, int]:  # fmt: skip
    """One motion from random caption features with a randomly initialised denoiser of ``preset``: the samplers'
    guided loop (DDIM, DDPM or DPM-Solver++, cosine 1000-step process, x0 prediction, no x̂0 clipping; the denoiser
    in bf16 with ``bf16``, as sampling runs it: `bf16_inference`) without a checkpoint, to compare with the official code on the same sizes.
    Returns (run, steps_total, steps_run) as ``sampling`` does."""

    loops = {"ddim": ddim_sample, "ddpm": ddpm_sample, "dpmpp": dpmpp_sample}
    if sampler not in loops:
        raise ValueError(f"feature_sampling runs ddim, ddpm or dpmpp, got {sampler!r}")
    model = build_denoiser(preset).eval()
    diffusion = GaussianDiffusion(make_betas("cosine", 1000), prediction="x0")
    data = random_batch(1, frames)
    fn = guided_model_fn(model, data["cond"], scale, mask=data["mask"])
    steps = {"ddim": steps or 50, "dpmpp": steps or 7}.get(sampler, steps)
    total = len(select_timesteps(diffusion.num_steps, steps))
    limit = total if timed_steps is None else min(total, timed_steps)
    hook, reset = _stopper(limit, total)
    loop = loops[sampler]

    def run():
        reset()
        with contextlib.suppress(_Stop), bf16_inference(model, "cpu", bf16):
            loop(diffusion, fn, (1, frames, FEATURE_DIM), steps=steps, xt_hook=hook)

    return run, total, limit


def text_encoding(encoder_kwargs: dict) -> tuple[Callable[[], object], Callable[[], object]]:
    """(encode one prompt with the encoder, look the same prompt up in a filled in-memory TextEmbeddingCache)."""

    encoder = build_text_encoder(**encoder_kwargs)
    cache = TextEmbeddingCache(encoder)
    cache.precompute([PROMPT])
    return (lambda: encoder.encode([PROMPT])), (lambda: cache.embed([PROMPT]))
