"""Shared CLI plumbing: config resolvers, user-error reporting, finding checkpoints."""

from __future__ import annotations

import functools
import logging
import os
import sys
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

REPO_DIR = Path(__file__).resolve().parents[3]
# checkpoint=shipped: the models released with the repo (safetensors + JSON, see checkpoints/models), by condition
SHIPPED_MODELS = {
    "text": REPO_DIR / "checkpoints" / "models" / "bandai_mini_text_cpu.safetensors",
    "action": REPO_DIR / "checkpoints" / "models" / "bandai_action_cpu.safetensors",
}
SHIPPED_MODEL = SHIPPED_MODELS["text"]
RELEASE_SUFFIXES = (".safetensors", ".json")


class UsageError(ValueError):
    """A mistake the user can fix (bad prompt, length, name, path); printed as one line, exit code 2."""


def register_resolvers() -> None:
    if not OmegaConf.has_resolver("repo_dir"):
        OmegaConf.register_new_resolver("repo_dir", lambda: str(REPO_DIR))
    if not OmegaConf.has_resolver("fast_cpu_precision"):
        from motiondiff.hardware import fast_cpu_precision

        OmegaConf.register_new_resolver("fast_cpu_precision", fast_cpu_precision)


def quiet_tool_caches() -> None:
    """Offline defaults and project-local caches for W&B, matplotlib and Hugging Face (never the user's home)."""
    cache = Path(os.environ.get("MOTIONDIFF_CACHE_DIR", REPO_DIR / ".cache" / "motiondiff"))
    os.environ.setdefault("WANDB_MODE", "offline")
    os.environ.setdefault("WANDB_SILENT", "true")
    os.environ.setdefault("WANDB_CACHE_DIR", str(cache / "wandb"))
    os.environ.setdefault("WANDB_CONFIG_DIR", str(cache / "wandb"))
    os.environ.setdefault("MPLCONFIGDIR", str(cache / "matplotlib"))
    os.environ.setdefault("HF_HOME", str(cache / "huggingface"))
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")


def user_errors(fn):
    """Report user errors as one clear line instead of a traceback."""
    from motiondiff.data.errors import DatasetNotFoundError, RepresentationError

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except (UsageError, DatasetNotFoundError, RepresentationError) as err:
            print(f"error: {err}", file=sys.stderr)
            sys.exit(2)

    return wrapper


def trainer_parts(cfg: DictConfig) -> tuple[list, list]:
    """(loggers, callbacks) instantiated from ``cfg.logger`` and ``cfg.callbacks`` (null entries left out).

    ``logger=none`` is a supported choice, but Lightning's LearningRateMonitor refuses a Trainer without a logger:
    it is dropped then (there is nowhere to log the rate to), with a note."""
    from hydra.utils import instantiate
    from lightning.pytorch.callbacks import LearningRateMonitor

    loggers = [instantiate(c) for c in (cfg.get("logger") or {}).values() if c is not None]
    callbacks = [instantiate(c) for c in (cfg.get("callbacks") or {}).values() if c is not None]
    if not loggers and any(isinstance(c, LearningRateMonitor) for c in callbacks):
        callbacks = [c for c in callbacks if not isinstance(c, LearningRateMonitor)]
        logging.getLogger(__name__).info("logger=none: the learning-rate monitor is left out (nothing to log to)")
    return loggers, callbacks


def to_dict(cfg: DictConfig | dict | None) -> dict | None:
    """Plain containers (checkpoints store hyper-parameters that load with torch.load(weights_only=True))."""
    if cfg is None:
        return None
    if isinstance(cfg, DictConfig):
        return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
    return dict(cfg)


def find_checkpoint(spec: str, output_dir: str | Path, condition: str = "text") -> Path:
    """A checkpoint path: a .ckpt or a release (.safetensors/.json); 'shipped': the model released with the repo
    for that condition (text or action); 'latest': the newest last.ckpt of a training run under output_dir/train;
    'best': that run's best-FID one."""
    if spec == "shipped":
        shipped = SHIPPED_MODELS[condition]
        if not shipped.is_file():
            raise UsageError(f"the shipped {condition} model {shipped} is missing: restore it with "
                             "`git checkout -- checkpoints`")  # fmt: skip
        return shipped
    if spec not in ("latest", "best"):
        path = Path(spec)
        if not path.is_file():
            raise UsageError(
                f"checkpoint {path} not found; pass checkpoint=<path to a .ckpt or .safetensors release>, "
                "checkpoint=shipped, checkpoint=latest or checkpoint=best"
            )
        return path
    runs = sorted(Path(output_dir).glob("train*/**/checkpoints/last.ckpt"), key=lambda p: p.stat().st_mtime)
    if not runs:
        raise UsageError(
            f"no trained checkpoint under {output_dir}/train*: train one first (`make train` or `python train.py`) "
            "pass checkpoint=<path to a .ckpt>, or use the released model: checkpoint=shipped"
        )
    if spec == "latest":
        return runs[-1]
    best = sorted(runs[-1].parent.glob("best-fid-*.ckpt"))
    if not best:
        raise UsageError(
            f"the newest run {runs[-1].parent.parent} has no best-FID checkpoint (it trained without evaluators or "
            "never evaluated); use checkpoint=latest"
        )
    return best[-1]


def sampling_steps(cfg: DictConfig, module) -> int | None:
    """The sampling steps to run: ``steps=`` as given (it must fit the model's T diffusion steps), else the sampler's
    default capped at T, so a model trained with few steps (MDM Tab. 6, T = 10) samples with DDIM over its whole
    chain instead of failing on DDIM-50. None: every step of the chain (DDPM's default)."""
    num_steps = int(module.diffusion.num_steps)
    if cfg.steps is not None:
        if not 1 <= int(cfg.steps) <= num_steps:
            raise UsageError(f"steps must be between 1 and the model's {num_steps} diffusion steps, got {cfg.steps}")
        return int(cfg.steps)
    default = cfg.sampler.steps
    return None if default is None else min(int(default), num_steps)


def apply_clip_x0(cfg: DictConfig, module) -> str | None:
    """clip_x0= (none | static | dynamic; null keeps the model's own rule) set on the module; returns the rule used."""
    rule = cfg.get("clip_x0")
    if rule is not None:
        try:
            module.set_clip_rule(str(rule))
        except ValueError as err:
            raise UsageError(f"clip_x0={rule}: {err}") from err
    return module.clip_rule


def text_encoder_kwargs(cfg_text: DictConfig | dict) -> dict:
    """Arguments of `build_text_encoder` from a text_encoder config (its `dim` is informational)."""
    return {k: v for k, v in to_dict(cfg_text).items() if k != "dim"}


def key_value_args(argv: list[str], keys) -> dict[str, str]:
    """``key=value`` arguments of a ``python -m motiondiff...`` command, each key one of ``keys``."""
    args = {}
    for a in argv:
        key, eq, value = a.partition("=")
        if not eq or key not in keys:
            raise UsageError(f"unknown argument {a!r}; arguments are key=value with key one of {', '.join(keys)}")
        args[key] = value
    return args
