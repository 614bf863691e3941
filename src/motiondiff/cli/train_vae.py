"""`python train_vae.py [level=motion|action|specific] ...`: train one of GuidedMotion's motion VAEs.

Same datamodule, trainer, loggers and checkpointing as train.py; the best checkpoint is the one with the lowest
validation MPJPE (`best-mpjpe-*.ckpt`), and run.json records the steps, wall time and parameter count that the
level comparison (`python -m motiondiff.studies.vae_levels`) reports.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import lightning as L
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf, open_dict

from motiondiff.cli.common import UsageError, check_ckpt_path, to_dict, trainer_parts
from motiondiff.cli.validate import RULES_TRAIN, check
from motiondiff.data.datamodules import MotionDataModule
from motiondiff.lit.checkpoint_io import AtomicCheckpointIO
from motiondiff.lit.compute_time import run_totals
from motiondiff.lit.vae import MotionVAEModule
from motiondiff.models.vae import LEVEL_TOKENS
from motiondiff.runtime.provenance import provenance, update_run_json

log = logging.getLogger(__name__)


def resolve_tokens(level: str | None, tokens: int | None) -> int:
    """Q from `vae.tokens` when given, else from the level; a level that is not one of the three is an error."""
    if level is not None and level not in LEVEL_TOKENS:
        choices = ", ".join(f"{k} (Q={v})" for k, v in LEVEL_TOKENS.items())
        raise UsageError(f"unknown level={level!r}; choose one of {choices}, or set vae.tokens=<Q> directly")
    if tokens is not None:
        if int(tokens) < 1:
            raise UsageError(f"vae.tokens must be a positive number of latent tokens, got {tokens}")
        return int(tokens)
    if level is None:
        raise UsageError("set level=motion|action|specific or vae.tokens=<Q>")
    return LEVEL_TOKENS[level]


def build_module(cfg: DictConfig, dm: MotionDataModule, tokens: int) -> MotionVAEModule:
    return MotionVAEModule(
        **dm.model_hparams(cfg.dataset.name),
        vae={**to_dict(cfg.vae), "tokens": tokens},
        optim=to_dict(cfg.optim),
        kl_weight=float(cfg.kl_weight),
        level=cfg.level,
    )


def _name_wandb_run(cfg: DictConfig) -> None:
    # The shared W&B logger names runs after the diffusion model's groups, which a VAE run does not have.
    if cfg.logger and "wandb" in cfg.logger:
        with open_dict(cfg):
            cfg.logger.wandb.name = f"{cfg.dataset.name}-vae-{cfg.level}-{cfg.vae.name}"


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_TRAIN)  # types and ranges before any work
    tokens = resolve_tokens(cfg.level, cfg.vae.tokens)  # before any work: a bad level fails at once
    ckpt = cfg.ckpt_path
    check_ckpt_path(ckpt)
    L.seed_everything(cfg.seed, workers=True)
    out = Path(HydraConfig.get().runtime.output_dir)
    dm: MotionDataModule = instantiate(cfg.dataset.datamodule)
    dm.setup("fit")
    module = build_module(cfg, dm, tokens)
    _name_wandb_run(cfg)
    loggers, callbacks = trainer_parts(cfg)
    trainer = L.Trainer(**OmegaConf.to_container(cfg.trainer, resolve=True), logger=loggers,
                        callbacks=callbacks, default_root_dir=out, plugins=[AtomicCheckpointIO()])  # fmt: skip
    n_params = sum(p.numel() for p in module.vae.parameters() if p.requires_grad)
    log.info("motion VAE, level %s (Q=%d): %.2f M parameters; outputs in %s", cfg.level, tokens, n_params / 1e6, out)
    if trainer.is_global_zero:  # before the first step: even a killed run says what it was
        update_run_json(out, provenance=provenance(cfg))
    start = time.perf_counter()
    trainer.fit(module, datamodule=dm, ckpt_path=ckpt, weights_only=True)  # a resumed checkpoint runs no pickled code
    seconds = time.perf_counter() - start
    best = next((c for c in callbacks if getattr(c, "monitor", None) == "val/mpjpe"), None)
    meta = {
        "level": cfg.level,
        "tokens": tokens,
        "train_steps": trainer.global_step,
        "train_seconds": round(seconds, 1),
        "parameters": n_params,
        "best_checkpoint": (best.best_model_path or None) if best else None,
        "best_val_mpjpe_m": float(best.best_model_score) if best and best.best_model_score is not None else None,
        "overrides": list(HydraConfig.get().overrides.task),
    }
    update_run_json(out, **meta, **run_totals(callbacks))
    last = out / "checkpoints" / "last.ckpt"
    print(f"\ntrained {trainer.global_step} steps in {seconds:.0f} s; checkpoint: {last}")
    if meta["best_checkpoint"]:
        print(f"best val MPJPE {meta['best_val_mpjpe_m']:.4f} m: {meta['best_checkpoint']}")
    return last
