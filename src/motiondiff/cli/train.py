"""`python train.py ...`: build the datamodule, text features, model, loggers and callbacks from the Hydra config."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import lightning as L
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from motiondiff.cli.common import (
    REPO_DIR,
    UsageError,
    check_ckpt_path,
    file_problem,
    text_encoder_kwargs,
    to_dict,
    trainer_parts,
)
from motiondiff.cli.validate import RULES_TRAIN, check
from motiondiff.data.datamodules import MotionDataModule
from motiondiff.lit.checkpoint_io import AtomicCheckpointIO
from motiondiff.lit.compute_time import run_totals
from motiondiff.lit.diffusion import MotionDiffusionModule
from motiondiff.lit.resume import KEY
from motiondiff.model_files.release_checks import release_paths
from motiondiff.runtime.checked_loading import CKPT_FIX, check_finite_state, check_same_shapes, reading, torch_load
from motiondiff.runtime.provenance import provenance, update_run_json
from motiondiff.text.cache import TextEmbeddingCache
from motiondiff.text.encoders import build_text_encoder

log = logging.getLogger(__name__)


def build_text_table(cfg: DictConfig, dm: MotionDataModule):
    """Features of every caption of the train and val splits, encoded once and cached on disk."""

    encoder = build_text_encoder(**text_encoder_kwargs(cfg.text_encoder))
    cache = TextEmbeddingCache(encoder, Path(cfg.paths.cache_dir) / "text")
    texts = sorted({t for split in ("train", "val") for rec in dm.dataset(split).records for t in rec.texts})
    if not texts:
        raise UsageError(f"dataset {cfg.dataset.name} has no captions: use condition=action or condition=none")
    return cache.table(texts)


def build_module(cfg: DictConfig, dm: MotionDataModule) -> MotionDiffusionModule:
    kind = cfg.condition.kind
    action_names = list(getattr(dm, "action_names", None) or []) if kind == "action" else None
    if kind == "action" and not action_names:
        raise UsageError(f"dataset {cfg.dataset.name} has no action labels: use condition=text or condition=none")
    return MotionDiffusionModule(
        **dm.model_hparams(cfg.dataset.name),
        model=to_dict(cfg.model),
        backbone=to_dict(cfg.backbone),
        condition=to_dict(cfg.condition),
        diffusion=to_dict(cfg.diffusion),
        optim=to_dict(cfg.optim),
        action_names=action_names,
        text_encoder=to_dict(cfg.text_encoder) if kind == "text" else None,
        loss=to_dict(cfg.loss),
        known_conditioning=to_dict(cfg.known_conditioning) if cfg.get("known_conditioning") else None,
        x0_range=[a.tolist() for a in dm.dataset("train").normalised_range()],
    )


# Parameters a fine-tune may add to the weights it starts from (they start at zero: the model's own predictions).
NEW_IN_FINE_TUNE = ("denoiser.known_proj.",)


def init_weights(module: MotionDiffusionModule, source: str) -> None:
    """Start from the weights of a checkpoint or release (a fine-tune), not a resume: optimizer and step start anew.

    The architecture must match, except for parameters this run adds (``NEW_IN_FINE_TUNE``)."""
    from safetensors.torch import load_file

    path = Path(source)
    if path.suffix in (".safetensors", ".json"):
        path = release_paths(path)[0]
    problem = file_problem(path)
    if problem is not None:
        raise UsageError(f"init_from={source} {problem}; give a .ckpt of a run or a release (.safetensors)")
    if path.suffix == ".safetensors":
        with reading(path, "init_from weights"):
            state = load_file(str(path))
    else:
        state = _state_dict(torch_load(path, "init_from checkpoint"), path)
    check_finite_state(state, f"init_from={source}")
    own = module.state_dict()
    shapes = [k for k in state if k in own and state[k].shape != own[k].shape]
    missing = [k for k in own if k not in state and not k.startswith(NEW_IN_FINE_TUNE)]
    unexpected = [k for k in state if k not in own]
    if shapes or missing or unexpected:
        raise UsageError(
            f"init_from={source} does not fit this model (shape differs: {shapes[:3]}, missing: {missing[:3]}, "
            f"unexpected: {unexpected[:3]}); use the same model, backbone, condition and dataset as its run"
        )
    module.load_state_dict(state, strict=False)
    log.info("initialised from %s (%d tensors)", source, len(state))


# What Lightning's resume reads besides the weights (a checkpoint without them is weights only: init_from=).
LIGHTNING_KEYS = ("pytorch-lightning_version", "epoch", "global_step", "optimizer_states", "loops")


def _state_dict(checkpoint: dict, path: Path) -> dict:

    state = checkpoint.get("state_dict")
    if not isinstance(state, dict):
        raise UsageError(f"{path} has no state_dict: it is not a Lightning checkpoint; {CKPT_FIX}")
    return state


def check_resume(ckpt: str, module: MotionDiffusionModule, batch_size: int) -> None:
    """A checkpoint to resume must be readable, finite, of this run's batch size and this architecture: one line
    before training starts, not a traceback from inside Lightning's restore."""

    path = Path(ckpt)
    checkpoint = torch_load(path, f"ckpt_path={ckpt}: the checkpoint")
    state = _state_dict(checkpoint, path)
    lacking = [k for k in LIGHTNING_KEYS if k not in checkpoint]
    if lacking:
        raise UsageError(f"ckpt_path={ckpt} is not a training checkpoint to resume (it has no {lacking[0]!r}): "
                         "resume from a run's last.ckpt, or start from its weights with init_from=")  # fmt: skip
    saved = checkpoint.get(KEY) if isinstance(checkpoint.get(KEY), dict) else {}
    if "batch_size" in saved and saved["batch_size"] != batch_size:
        raise UsageError(f"ckpt_path={ckpt} was trained with batch_size={saved['batch_size']}: resume with the same "
                         f"batch_size (got {batch_size}) or use init_from= to fine-tune")  # fmt: skip
    check_finite_state(state, f"ckpt_path={ckpt}")
    fix = "resume with the settings of its run (its .hydra/overrides.yaml), or start anew with init_from="
    check_same_shapes(state, module.state_dict(), f"ckpt_path={ckpt}", fix, "this run's model (another architecture)")


def evaluation_callbacks(callbacks: list) -> list:
    """Leave out the generation evaluation and the best-FID checkpoint when the dataset has no evaluators, and the
    best-FID checkpoint when the evaluation is switched off (``callbacks.evaluation=null``): nothing logs val/fid."""
    from lightning.pytorch.callbacks import ModelCheckpoint

    from motiondiff.eval.callbacks import GenerationEvaluation  # lazy: torchmetrics (+2.6 s to import)

    evaluations = [c for c in callbacks if isinstance(c, GenerationEvaluation)]
    missing = [c for c in evaluations if not c.available]
    needs_fid = [c for c in callbacks if isinstance(c, ModelCheckpoint) and (c.monitor or "").startswith("val/")
                 and c.monitor != "val/loss"]  # fmt: skip
    if not missing and (evaluations or not needs_fid):
        return callbacks
    if missing:
        log.warning(
            "no evaluators in %s: training without FID/R-precision evaluation or best-FID checkpoint (make them "
            "with `python -m motiondiff.cli.train_evaluator dataset=<name>`)",
            missing[0].evaluator_dir,
        )
    else:
        log.info("callbacks.evaluation is off: no best-FID checkpoint either (last.ckpt holds the final weights)")
    return [c for c in callbacks if c not in missing and c not in needs_fid]


def check_sample_videos(callbacks: list, module: MotionDiffusionModule) -> None:
    """The evaluation's sample videos (``callbacks.evaluation.videos``) ask for prompts or action names this model
    has: a wrong one fails now, before anything is written, not at the first evaluation."""
    from motiondiff.eval.callbacks import GenerationEvaluation  # lazy: torchmetrics (+2.6 s to import)

    for callback in callbacks:
        if isinstance(callback, GenerationEvaluation) and callback.videos is not None:
            callback.videos.conditions(module)


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_TRAIN)  # types and ranges before any work
    L.seed_everything(cfg.seed, workers=True)
    out = Path(HydraConfig.get().runtime.output_dir)
    check_ckpt_path(cfg.ckpt_path)
    dm: MotionDataModule = instantiate(cfg.dataset.datamodule)
    dm.setup("fit")
    module = build_module(cfg, dm)
    if cfg.ckpt_path is not None:  # before the text table and the trainer: a wrong checkpoint fails at once
        check_resume(cfg.ckpt_path, module, int(cfg.batch_size))
    if cfg.get("init_from"):  # before the text table: the centring of caption features comes with the weights
        init_weights(module, cfg.init_from)
    if cfg.condition.kind == "text":
        module.set_text_table(*build_text_table(cfg, dm))
    loggers, callbacks = trainer_parts(cfg)
    callbacks = evaluation_callbacks(callbacks)
    check_sample_videos(callbacks, module)
    if cfg.ema:
        from lightning.pytorch.callbacks import EMAWeightAveraging

        callbacks.append(EMAWeightAveraging(decay=cfg.ema_decay))
    trainer = L.Trainer(
        **OmegaConf.to_container(cfg.trainer, resolve=True),
        logger=loggers,
        callbacks=callbacks,
        default_root_dir=out,
        plugins=[AtomicCheckpointIO()],
    )
    n_params = sum(p.numel() for p in module.denoiser.parameters() if p.requires_grad)
    log.info("denoiser: %.2f M trainable parameters; outputs in %s", n_params / 1e6, out)
    ckpt = cfg.ckpt_path
    if trainer.is_global_zero:  # before the first step: even a killed run says what it was
        update_run_json(out, provenance=provenance(cfg))
    start = time.perf_counter()
    trainer.fit(module, datamodule=dm, ckpt_path=ckpt, weights_only=True)  # a resumed checkpoint runs no pickled code
    seconds = time.perf_counter() - start  # wall time of fit (evaluation callbacks included): equal-time comparisons
    last = out / "checkpoints" / "last.ckpt"
    if not trainer.is_global_zero:  # DDP: the other processes only train; rank 0 writes and evaluates
        return last
    meta = {"train_steps": trainer.global_step, "train_seconds": round(seconds, 1),
            "overrides": list(HydraConfig.get().overrides.task)}  # fmt: skip
    update_run_json(out, **meta, **run_totals(callbacks))
    print(f"\ntrained {trainer.global_step} steps; checkpoint: {last}")
    if cfg.final_evaluation is not None:
        final_evaluation(cfg, module, dm, out, trainer.global_step)
    return last


def final_evaluation(cfg: DictConfig, module: MotionDiffusionModule, dm: MotionDataModule, out: Path, steps: int):
    """evaluate.py's protocol on the trained weights (the EMA ones when ema=true), written into the run folder:
    what a multirun's summary table reads (`motiondiff.eval.ablation`)."""
    from motiondiff.cli.evaluation import report_evaluation  # lazy: torchmetrics (+2.6 s to import)

    base = OmegaConf.load(REPO_DIR / "conf" / "evaluate.yaml")
    for key in ("defaults", "hydra", "checkpoint"):
        base.pop(key)
    sampler = OmegaConf.load(REPO_DIR / "conf" / "sampler" / f"{cfg.final_evaluation.get('sampler', 'ddim')}.yaml")
    overrides = {k: v for k, v in to_dict(cfg.final_evaluation).items() if k != "sampler"}
    eval_cfg = OmegaConf.merge(base, {"paths": cfg.paths, "dataset": cfg.dataset, "sampler": sampler,
                                      "wandb": False, "precision": cfg.trainer.precision}, overrides)  # fmt: skip
    module.to(eval_cfg.device)
    summary = report_evaluation(eval_cfg, module, dm, out, f"{out} (end of training, step {steps})")
    update_run_json(out, train_steps=steps, overrides=list(HydraConfig.get().overrides.task),
                    study=to_dict(cfg.study) if cfg.get("study") else None)  # fmt: skip
    return summary
