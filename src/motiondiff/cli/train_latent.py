"""`python train_latent.py vae.motion=... vae.action=... vae.specific=...`: GuidedMotion's hierarchical latent
diffusion on three trained motion VAEs (frozen), with the caption graphs of every caption built once at setup."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import lightning as L
import torch
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf, open_dict

from motiondiff.cli.common import UsageError, check_ckpt_path, text_encoder_kwargs, to_dict, trainer_parts
from motiondiff.cli.validate import RULES_TRAIN, check
from motiondiff.data.datamodules import MotionDataModule
from motiondiff.lit.checkpoint_io import AtomicCheckpointIO
from motiondiff.lit.compute_time import run_totals
from motiondiff.lit.latent import HierarchicalLatentModule
from motiondiff.lit.vae import MotionVAEModule
from motiondiff.model_files.loading import load_vae
from motiondiff.models.hierarchical import LEVELS
from motiondiff.runtime.provenance import provenance, update_run_json
from motiondiff.text.encoders import build_text_encoder
from motiondiff.text.graph_features import graph_table

log = logging.getLogger(__name__)


def load_vaes(paths: dict) -> dict[str, MotionVAEModule]:
    """The three frozen VAEs (vae.motion / vae.action / vae.specific), each refused at once if it cannot be loaded."""
    fix = "train it with `python train_vae.py level={}` on the same dataset and pass its best-mpjpe checkpoint"
    return {level: load_vae(str(paths[level]), f"vae.{level} checkpoint", fix.format(level))[0] for level in LEVELS}


def check_vaes(vaes: dict[str, MotionVAEModule], dm: MotionDataModule, name: str) -> None:
    """The VAEs must read this dataset's normalised features: same width, statistics and length limit."""
    ds = dm.dataset("train")
    for level, vae in vaes.items():
        hp = vae.hparams
        same_stats = hp.feature_dim == dm.feature_dim and torch.allclose(
            torch.tensor(hp.mean), torch.as_tensor(ds.mean, dtype=torch.float32), atol=1e-5
        )
        if not same_stats or hp.max_frames < dm.max_frames:
            raise UsageError(
                f"the {level} VAE was trained on {hp.dataset!r} ({hp.feature_dim} features, max {hp.max_frames} frames),"
                f" which does not match dataset {name!r} here ({dm.feature_dim} features, max "
                f"{dm.max_frames} frames, its own Mean/Std); train the VAEs with train_vae.py on the same dataset"
            )


def build_graph_table(cfg: DictConfig, dm: MotionDataModule) -> dict:

    texts = [t for split in ("train", "val") for rec in dm.dataset(split).records for t in rec.texts]
    if not texts:
        raise UsageError(f"dataset {cfg.dataset.name} has no captions: GuidedMotion is text-to-motion")
    encoder = build_text_encoder(**text_encoder_kwargs(cfg.text_encoder))
    return graph_table(texts, encoder)


def build_module(cfg: DictConfig, vaes: dict[str, MotionVAEModule]) -> HierarchicalLatentModule:
    module = HierarchicalLatentModule(
        vaes={level: dict(vae.hparams) for level, vae in vaes.items()},
        model={k: v for k, v in to_dict(cfg.latent).items() if k != "name"},
        diffusion=to_dict(cfg.diffusion),
        optim=to_dict(cfg.optim),
        node_dim=int(cfg.text_encoder.dim),
        text_encoder=to_dict(cfg.text_encoder),
        condition=to_dict(cfg.condition),
        sampling=to_dict(cfg.sampling),
        dataset=cfg.dataset.name,
    )
    for level, vae in vaes.items():
        module.vaes[level].load_state_dict(vae.state_dict())
    return module


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_TRAIN)  # types and ranges before any work
    check_ckpt_path(cfg.ckpt_path)
    vaes = load_vaes(cfg.vae)  # before any other work: a missing VAE fails at once
    L.seed_everything(cfg.seed, workers=True)
    out = Path(HydraConfig.get().runtime.output_dir)
    dm: MotionDataModule = instantiate(cfg.dataset.datamodule)
    dm.setup("fit")
    check_vaes(vaes, dm, cfg.dataset.name)
    module = build_module(cfg, vaes)
    module.set_latent_stats(list(dm.train_dataloader()))
    module.set_graph_table(build_graph_table(cfg, dm))
    if cfg.logger and "wandb" in cfg.logger:
        with open_dict(cfg):
            cfg.logger.wandb.name = f"{cfg.dataset.name}-guidedmotion-{cfg.latent.name}"
    loggers, callbacks = trainer_parts(cfg)
    trainer = L.Trainer(**OmegaConf.to_container(cfg.trainer, resolve=True), logger=loggers, callbacks=callbacks,
                        default_root_dir=out, plugins=[AtomicCheckpointIO()])  # fmt: skip
    n_params = sum(p.numel() for p in module.denoiser.parameters())
    log.info("GuidedMotion latent denoisers + graph attention: %.2f M parameters; outputs in %s", n_params / 1e6, out)
    if trainer.is_global_zero:  # before the first step: even a killed run says what it was
        update_run_json(out, provenance=provenance(cfg))
    start = time.perf_counter()
    trainer.fit(module, datamodule=dm, ckpt_path=cfg.ckpt_path, weights_only=True)  # no pickled code runs
    seconds = time.perf_counter() - start
    meta = {"train_steps": trainer.global_step, "train_seconds": round(seconds, 1), "parameters": n_params,
            "vaes": {k: str(v) for k, v in cfg.vae.items()}, "overrides": list(HydraConfig.get().overrides.task)}  # fmt: skip
    update_run_json(out, **meta, **run_totals(callbacks))
    last = out / "checkpoints" / "last.ckpt"
    print(f"\ntrained {trainer.global_step} steps in {seconds:.0f} s; checkpoint: {last}")
    return last
