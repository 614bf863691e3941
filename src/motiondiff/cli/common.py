"""Shared CLI plumbing: the trainer's loggers and callbacks, the sampling settings every command checks the same way.
The helpers every entry point needs live below the CLI (motiondiff.runtime.scripting, .paths, .errors) and are re-exported."""

from __future__ import annotations

import logging

from omegaconf import DictConfig

from motiondiff.lit.conditions import text_encoder_kwargs  # noqa: F401
from motiondiff.lit.generation import fitted_steps
from motiondiff.model_files.resolve import find_model  # noqa: F401  (the commands take it from here)
from motiondiff.runtime.errors import UsageError  # noqa: F401  (re-exported: the CLI's error type)
from motiondiff.runtime.file_kinds import file_problem
from motiondiff.runtime.paths import REPO_DIR
from motiondiff.runtime.scripting import (  # noqa: F401
    USER_ERRORS,
    key_value_args,
    quiet_tool_caches,
    register_resolvers,
    to_dict,
    user_errors,
)


def trainer_parts(cfg: DictConfig) -> tuple[list, list]:
    """(loggers, callbacks) instantiated from ``cfg.logger`` and ``cfg.callbacks`` (null entries left out).

    ``logger=none`` is a supported choice, but Lightning's LearningRateMonitor refuses a Trainer without a logger:
    it is dropped then (there is nowhere to log the rate to), with a note. A user error a constructor raises (e.g. a
    bad ``callbacks.evaluation.videos`` setting) is reported as itself, not inside Hydra's InstantiationException."""
    from lightning.pytorch.callbacks import LearningRateMonitor

    loggers = [_instantiate(c) for c in (cfg.get("logger") or {}).values() if c is not None]
    callbacks = [_instantiate(c) for c in (cfg.get("callbacks") or {}).values() if c is not None]
    if not loggers and any(isinstance(c, LearningRateMonitor) for c in callbacks):
        callbacks = [c for c in callbacks if not isinstance(c, LearningRateMonitor)]
        logging.getLogger(__name__).info("logger=none: the learning-rate monitor is left out (nothing to log to)")
    return loggers, callbacks


def _instantiate(cfg):
    from hydra.errors import InstantiationException
    from hydra.utils import instantiate

    try:
        return instantiate(cfg)
    except InstantiationException as err:
        if isinstance(err.__cause__, USER_ERRORS):
            raise err.__cause__ from None
        raise


def resolve_sampler(cfg: DictConfig, module) -> None:
    """``sampler=auto`` replaced by the model's own default sampler's config (conf/sampler/<name>.yaml), so what runs
    and what results.json records is a named sampler with its steps; the model's own sampler runs the model's own
    steps (``default_steps``) however it was named."""
    from omegaconf import OmegaConf

    if cfg.sampler.get("name") == "auto":
        cfg.sampler = OmegaConf.load(REPO_DIR / "conf" / "sampler" / f"{module.resolve_sampler('auto')}.yaml")
    name = cfg.sampler.get("name")
    if name == module.default_sampler and module.hparams.model.get("sample_steps"):
        cfg.sampler.steps = module.default_steps(name)


def sampling_steps(cfg: DictConfig, module) -> int | None:
    """``steps=`` (or the sampler's default) fitted to the model's diffusion steps (``lit.generation.fitted_steps``),
    once ``sampler=auto`` is resolved to the model's own sampler (`resolve_sampler`)."""
    resolve_sampler(cfg, module)
    return fitted_steps(module, None if cfg.steps is None else int(cfg.steps), cfg.sampler.steps)


def apply_step_rules(cfg: DictConfig, module) -> None:
    """clip_x0= (none | static | dynamic) and timestep_spacing= (uniform | leading | logsnr) set on the module; null
    keeps the model's own (diffusion.clip_x0, diffusion.timestep_spacing). Read back from module.clip_rule and
    module.timestep_spacing."""
    for key, setter in (("clip_x0", module.set_clip_rule), ("timestep_spacing", module.set_timestep_spacing)):
        value = cfg.get(key)
        if value is not None:
            try:
                setter(str(value))
            except ValueError as err:
                raise UsageError(f"{key}={value}: {err}") from err


def check_ckpt_path(ckpt_path) -> None:
    """A training command's ``ckpt_path=`` (resume) is a readable file, or one error saying what it is instead."""
    problem = None if ckpt_path is None else file_problem(ckpt_path)
    if problem is not None:
        raise UsageError(f"ckpt_path={ckpt_path} {problem}; pass the last.ckpt of the run to resume")
