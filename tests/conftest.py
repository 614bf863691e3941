"""Shared fixtures. Tests that read ../shared (CI has it) skip with a reason where it is absent (a user's clone)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("MOTIONDIFF_SHARED", REPO.parent / "shared"))


def _shared_path(*parts: str) -> Path:
    path = SHARED.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{path} not found: this test needs the project's shared data (set MOTIONDIFF_SHARED)")
    return path


@pytest.fixture(scope="session")
def shared():
    """Callable fixture: shared('reference', 'humanml3d') -> Path, or skip when missing."""
    return _shared_path


def pytest_configure(config):
    """Under `make test` (two xdist workers on a 2-core machine) each worker and the commands it starts use one torch
    thread: two workers of two threads each would oversubscribe the cores, and torch's threads spin waiting on each
    other. A plain `pytest` run keeps torch's default."""
    if os.environ.get("PYTEST_XDIST_WORKER") and os.cpu_count() and os.cpu_count() <= 2:
        os.environ.setdefault("OMP_NUM_THREADS", "1")
        os.environ.setdefault("MKL_NUM_THREADS", "1")
        import torch

        torch.set_num_threads(1)


@pytest.fixture(autouse=True, scope="session")
def _keep_caches_out_of_home(tmp_path_factory):
    """Tool caches (wandb, matplotlib, HF) go to a temp dir, never into the user's home."""
    cache = tmp_path_factory.mktemp("caches")
    for var, sub in [("WANDB_DIR", "wandb"), ("WANDB_CACHE_DIR", "wandb-cache"), ("WANDB_CONFIG_DIR", "wandb-config"),
                     ("MPLCONFIGDIR", "mpl"), ("HF_HOME", "hf"), ("XDG_CACHE_HOME", "xdg")]:  # fmt: skip
        os.environ[var] = str(cache / sub)
    os.environ.setdefault("WANDB_MODE", "offline")
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
    yield


# The longest test files first (seconds on 2 cores, from `pytest --durations`): `make test` deals files to its two
# workers in collection order (`--dist loadfile`), so the long ones start at once and the short ones fill in after,
# and the workers finish together instead of one waiting on a long file dealt last.
LONGEST_FIRST = [  # `--durations` of a `make test` run, 2026-12-06 (DDP and the kill tests shortened since)
    "e2e/test_guidedmotion_cli.py",  # 139
    "e2e/test_notebooks.py",  # 125
    "hostile/test_issue41_refusals.py",  # ~100 (16 subprocesses; added 2026-12-06)
    "hostile/test_issue41_runs.py",  # ~100
    "e2e/test_train_sample_cli.py",  # 88
    "hostile/test_boundary.py",  # 71
    "e2e/test_ddp_cli.py",  # ~70
    "hostile/test_releases.py",  # 64
    "e2e/test_evaluation_cli.py",  # 61
    "hostile/test_kill_training.py",  # ~60
    "hostile/test_interrupts.py",  # 59
    "e2e/test_edit_cli.py",  # 50
    "e2e/test_demo.py",  # ~45 (every mode in Chromium)
    "unit/test_packaging.py",  # ~40 (builds the wheel, installs it in a fresh venv)
    "integration/test_prepare_bandai.py",  # 48
    "e2e/test_dashboard.py",  # 46
    "hostile/test_kill_sampling.py",  # ~42
    "hostile/test_bounds.py",  # 42
    "hostile/test_kill_prepare.py",  # ~37
    "e2e/test_backbones_cli.py",  # 35
    "unit/export/test_export_smpl.py",  # 30
    "hostile/test_user_files.py",  # 25
    "e2e/test_few_step_presets.py",  # 24
    "e2e/test_dataset_cli.py",  # 21
    "hostile/test_full_disk.py",  # 19
    "integration/test_variant_matrix.py",  # 17
]


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}

    def key(item) -> int:
        path = Path(str(item.fspath)).relative_to(REPO / "tests").as_posix()
        return rank.get(path, len(rank))

    items.sort(key=key)  # stable: the rest keep their order
