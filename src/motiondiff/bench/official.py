"""The benchmark's workloads on the official MDM code (loaded by ``official_code.load_official`` from a user's
checkout), with the signatures of ``workloads``' own so the suite times both sides the same way:

- ``train_step``: its training loop's step (train/training_loop.py's run_step without the logging and the unused EMA
  and learning-rate annealing): uniform timestep sampling, ``training_losses`` of its SpacedDiffusion (masked x0 MSE;
  the geometric losses are 0 for HumanML3D), backward, and MixedPrecisionTrainer.optimize (gradient and parameter
  norms, then AdamW at lr 1e-4 and its default weight decay 0). MDM drops the caption for 10% of the batch itself.
- ``forward``: MDM's forward in eval mode under no_grad (as its sampling loops run it); ``guided``: through its
  ClassifierFreeSampleModel, which runs the conditional and the unconditional forward one after the other.
- ``sampling``: one motion through its own loops with that wrapper: ``p_sample_loop`` (sample/generate.py's default,
  DDPM over all 1000 steps) or ``ddim_sample_loop`` on a SpacedDiffusion respaced with ``'ddim50'``; both are the
  ``*_progressive`` generators run to the end, which lets a long chain stop after its first steps.

The model is built with the arguments utils/model_util.get_model_args gives for HumanML3D with text (hml_vec, 263
features, trans_enc, cond_mask_prob 0.1, mask_frames off, CLIP's 512-wide caption features), with our preset's sizes;
the diffusion with its own create_gaussian_diffusion (cosine, 1000 steps, x0 prediction).
"""

from __future__ import annotations

import contextlib
import io
import itertools
import warnings
from collections.abc import Callable
from types import SimpleNamespace

import torch

from motiondiff.bench.flops import count_flops
from motiondiff.bench.official_code import OfficialCode
from motiondiff.bench.workloads import FEATURE_DIM, GUIDANCE, autocast, random_batch
from motiondiff.models.denoiser import PRESETS

STEPS = 1000


def model_kwargs(preset: str | dict) -> dict:
    """MDM's constructor arguments for HumanML3D with text, at ``preset``'s sizes (a PRESETS name or dict)."""
    arch = PRESETS[preset] if isinstance(preset, str) else preset
    return dict(
        modeltype="", njoints=FEATURE_DIM, nfeats=1, num_actions=1, translation=True, pose_rep="rot6d", glob=True,
        glob_rot=True, latent_dim=arch["d_model"], ff_size=arch["ff_size"], num_layers=arch["num_layers"],
        num_heads=arch["num_heads"], dropout=arch.get("dropout", 0.1), activation=arch.get("activation", "gelu"),
        data_rep="hml_vec", cond_mode="text", cond_mask_prob=0.1, action_emb="tensor", arch="trans_enc",
        emb_trans_dec=False, clip_version="ViT-B/32", dataset="humanml", text_encoder_type="clip",
        pos_embed_max_len=5000, mask_frames=False, pred_len=0, context_len=0, emb_policy="add",
        all_goal_joint_names=[], multi_target_cond=False,
    )  # fmt: skip


def build_model(code: OfficialCode, preset: str | dict, seed: int = 0) -> torch.nn.Module:
    """The official MDM (its constructor's progress prints and PyTorch's nested-tensor warning kept quiet)."""
    torch.manual_seed(seed)
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return code.MDM(**model_kwargs(preset))


def param_count(model: torch.nn.Module) -> int:
    """Trainable size without CLIP (what its parameters_wo_clip gives)."""
    return sum(p.numel() for name, p in model.named_parameters() if not name.startswith("clip_model."))


def create_diffusion(code: OfficialCode, respacing: str = ""):
    """Its SpacedDiffusion: create_gaussian_diffusion's (all 1000 steps) or, with ``respacing`` such as 'ddim50', the
    same process on ``space_timesteps(1000, respacing)``."""
    args = SimpleNamespace(noise_schedule="cosine", diffusion_steps=STEPS, sigma_small=True, lambda_vel=0.0,
                           lambda_rcxyz=0.0, lambda_fc=0.0, lambda_target_loc=0.0)  # fmt: skip
    base = code.create_gaussian_diffusion(args)
    if not respacing:
        return base
    return code.SpacedDiffusion(
        use_timesteps=code.space_timesteps(STEPS, respacing),
        betas=code.gaussian_diffusion.get_named_beta_schedule("cosine", STEPS),
        model_mean_type=base.model_mean_type,
        model_var_type=base.model_var_type,
        loss_type=base.loss_type,
        rescale_timesteps=base.rescale_timesteps,
    )


def random_inputs(model, batch: int, frames: int, seed: int = 0) -> tuple[torch.Tensor, dict]:
    """The motion features of ``workloads.random_batch`` in MDM's layout [B, 263, 1, F], and its condition dict: the
    frame mask [B, 1, 1, F], lengths, and random caption features [1, B, clip_dim] as ``y['text_embed']``."""
    data = random_batch(batch, frames, seed)
    x0 = data["x0"].permute(0, 2, 1).unsqueeze(2).contiguous()
    text = torch.randn(1, batch, model.clip_dim, generator=torch.Generator().manual_seed(seed + 1))
    return x0, {"mask": data["mask"][:, None, None, :], "lengths": torch.full((batch,), frames), "text_embed": text}


def train_step(
    code: OfficialCode, preset: str | dict, batch: int, frames: int, bf16: bool = False
) -> Callable[[], float]:
    """One step of its training loop (see the module docstring); ``bf16``: the loss under CPU bf16 autocast."""
    model = build_model(code, preset)
    model.train()  # MDM's train() returns None
    diffusion = create_diffusion(code)
    trainer = code.MixedPrecisionTrainer(model=model, use_fp16=False)
    opt = torch.optim.AdamW(trainer.master_params, lr=1e-4, weight_decay=0.0)
    schedule = code.UniformSampler(diffusion)
    code.logger.Logger.CURRENT = code.logger.Logger(dir=None, output_formats=[])  # its metrics, kept in memory
    x0, y = random_inputs(model, batch, frames)

    def step() -> float:
        trainer.zero_grad()
        t, weights = schedule.sample(batch, "cpu")
        with autocast(bf16):
            losses = diffusion.training_losses(model, x0, t, model_kwargs={"y": y}, dataset=None)
            loss = (losses["loss"] * weights).mean()
        trainer.backward(loss)
        trainer.optimize(opt)
        return float(loss.detach())

    return step


def _network(code: OfficialCode, preset: str | dict, guided: bool, train: bool = False):
    model = build_model(code, preset)
    net = code.ClassifierFreeSampleModel(model) if guided else model
    net.train(train)  # MDM's train() returns None
    return model, net


def forward(code: OfficialCode, preset: str | dict, batch: int, frames: int, guided: bool = False,
            scale: float = GUIDANCE, bf16: bool = False) -> Callable[[], torch.Tensor]:  # fmt: skip
    """MDM's inference forward (``guided``: classifier-free guidance as its ClassifierFreeSampleModel runs it)."""
    model, net = _network(code, preset, guided)
    x, y = random_inputs(model, batch, frames)
    y["scale"] = torch.full((batch,), float(scale))
    t = torch.full((batch,), 500)

    def run() -> torch.Tensor:
        with torch.no_grad(), autocast(bf16):
            return net(x, t, y=y)

    return run


def forward_flops(code: OfficialCode, preset: str | dict, batch: int, frames: int, guided: bool = False) -> int:
    """FLOPs of that forward, counted in train mode under no_grad as ``workloads.forward_flops`` counts ours."""

    model, net = _network(code, preset, guided, train=True)
    x, y = random_inputs(model, batch, frames)
    y["scale"] = torch.full((batch,), GUIDANCE)
    with torch.no_grad():
        return count_flops(lambda: net(x, torch.full((batch,), 500), y=y))


def sampling(code: OfficialCode, preset: str | dict, frames: int, sampler: str, scale: float = GUIDANCE,
             timed_steps: int | None = None) -> tuple[Callable[[], object], int, int]:  # fmt: skip
    """One guided motion with its own loop: ``sampler`` 'ddpm' (p_sample_loop, 1000 steps) or 'ddim' (ddim_sample_loop,
    'ddim50'). Returns (run, steps_total, steps_run) as ``workloads.sampling`` does (the caller scales the time)."""
    if sampler not in ("ddim", "ddpm"):
        raise ValueError(f"the official sampling runs ddim or ddpm, got {sampler!r}")
    model, net = _network(code, preset, guided=True)
    diffusion = create_diffusion(code, "ddim50" if sampler == "ddim" else "")
    loop = diffusion.ddim_sample_loop_progressive if sampler == "ddim" else diffusion.p_sample_loop_progressive
    _, y = random_inputs(model, 1, frames)
    y["scale"] = torch.full((1,), float(scale))
    total = diffusion.num_timesteps
    limit = total if timed_steps is None else min(total, timed_steps)
    shape = (1, model.njoints, model.nfeats, frames)

    def run():
        # sample/generate.py's call: clip_denoised=False, noise drawn by the loop
        for _ in itertools.islice(loop(net, shape, clip_denoised=False, model_kwargs={"y": y}), limit):
            pass

    return run, total, limit
