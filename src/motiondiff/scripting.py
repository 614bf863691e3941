"""What every entry point does before its work (the CLI scripts and the `python -m motiondiff...` studies alike):
config resolvers, offline project-local tool caches, one-line user errors, key=value arguments."""

from __future__ import annotations

import functools
import os
import sys
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from motiondiff.data.sources.errors import DatasetNotFoundError, RepresentationError
from motiondiff.errors import UsageError
from motiondiff.paths import REPO_DIR, work_dir


def register_resolvers() -> None:
    if not OmegaConf.has_resolver("repo_dir"):
        OmegaConf.register_new_resolver("repo_dir", lambda: str(REPO_DIR))
    if not OmegaConf.has_resolver("work_dir"):
        OmegaConf.register_new_resolver("work_dir", lambda: str(work_dir()))
    if not OmegaConf.has_resolver("fast_cpu_precision"):
        from motiondiff.hardware import fast_cpu_precision

        OmegaConf.register_new_resolver("fast_cpu_precision", fast_cpu_precision)


def quiet_tool_caches() -> None:
    """Offline defaults and project-local caches for W&B, matplotlib and Hugging Face (never the user's home)."""
    cache = Path(os.environ.get("MOTIONDIFF_CACHE_DIR", work_dir() / ".cache" / "motiondiff"))
    os.environ.setdefault("WANDB_MODE", "offline")
    os.environ.setdefault("WANDB_SILENT", "true")
    os.environ.setdefault("WANDB_CACHE_DIR", str(cache / "wandb"))
    os.environ.setdefault("WANDB_CONFIG_DIR", str(cache / "wandb"))
    os.environ.setdefault("MPLCONFIGDIR", str(cache / "matplotlib"))
    os.environ.setdefault("HF_HOME", str(cache / "huggingface"))
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")


USER_ERRORS = (UsageError, DatasetNotFoundError, RepresentationError)  # reported as one line, exit code 2


def user_errors(fn):
    """Report user errors as one clear line instead of a traceback."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except USER_ERRORS as err:
            print(f"error: {err}", file=sys.stderr)
            sys.exit(2)

    return wrapper


def key_value_args(argv: list[str], keys) -> dict[str, str]:
    """``key=value`` arguments of a ``python -m motiondiff...`` command, each key one of ``keys``."""
    args = {}
    for a in argv:
        key, eq, value = a.partition("=")
        if not eq or key not in keys:
            raise UsageError(f"unknown argument {a!r}; arguments are key=value with key one of {', '.join(keys)}")
        args[key] = value
    return args


def to_dict(cfg: DictConfig | dict | None) -> dict | None:
    """Plain containers (checkpoints store hyper-parameters that load with torch.load(weights_only=True))."""
    if cfg is None:
        return None
    if isinstance(cfg, DictConfig):
        return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
    return dict(cfg)


def run_hydra(config_name: str, run) -> None:
    """One Hydra run of ``run(cfg)`` with the project's config ``config_name`` (command line overrides from
    sys.argv), after the resolvers and tool caches are set; user errors become one line and exit code 2."""
    import hydra

    from motiondiff.paths import CONF_DIR

    register_resolvers()
    quiet_tool_caches()
    if not any(a.startswith("hydra.job.name=") for a in sys.argv[1:]):  # log files named after the command
        sys.argv.append(f"hydra.job.name={config_name}")
    hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name=config_name)(user_errors(run))()
