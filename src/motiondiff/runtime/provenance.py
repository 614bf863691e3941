"""What produced a run: its fully resolved config, the code's git commit (and whether the tree had uncommitted
changes), the versions of the packages that shape results, the Python and the machine (CPU, cores, the instruction
sets that decide its speed, torch's threads). Training writes it into `run.json` before the first step, so even a
killed run says what it was."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from motiondiff.runtime.atomic import finite_or_null, write_json

REPO_DIR = Path(__file__).resolve().parents[3]  # the checkout (this file is src/motiondiff/runtime/provenance.py)
PACKAGES = ("motiondiff", "torch", "lightning", "hydra-core", "omegaconf", "torchmetrics", "wandb",
            "sentence-transformers", "transformers", "spacy", "numpy", "scipy", "safetensors")  # fmt: skip


def git_state(repo: Path = REPO_DIR) -> dict:
    """{"commit": sha, "dirty": tracked files differ from it}; None values outside a git checkout."""

    def git(*args: str) -> str | None:
        try:
            done = subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True, timeout=10)
        except (OSError, subprocess.TimeoutExpired):
            return None
        return done.stdout.strip() if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    status = git("status", "--porcelain", "--untracked-files=no") if commit else None
    return {"commit": commit, "dirty": None if status is None else bool(status)}


def package_versions(names: tuple[str, ...] = PACKAGES) -> dict[str, str | None]:
    versions = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def machine() -> dict:
    """The CPU that ran it: model name, cores, the instruction sets that decide matmul speed, torch's threads (one
    model name covers CPUs with and without native bf16, so the name alone does not say which ran)."""
    import torch

    from motiondiff.runtime.hardware import cpu_flags, cpu_model

    return {"cpu": cpu_model(), "cores": os.cpu_count(), "flags": [k for k, v in cpu_flags().items() if v],
            "torch_threads": torch.get_num_threads()}  # fmt: skip


def provenance(cfg: DictConfig | None = None) -> dict:
    record = {"git": git_state(), "packages": package_versions(), "python": platform.python_version(),
              "platform": platform.platform(), "machine": machine(), "argv": sys.argv}  # fmt: skip
    if cfg is not None:
        record["config"] = OmegaConf.to_container(cfg, resolve=True)
    return record


def update_run_json(folder: Path, **fields) -> Path:
    """Merge ``fields`` into ``folder``/run.json (atomically; keys already there and not given are kept)."""
    path = Path(folder) / "run.json"
    record = json.loads(path.read_text()) if path.is_file() else {}
    record.update(fields)
    return write_json(path, finite_or_null(record), default=str)
