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
LONGEST_FIRST = [
    "e2e/test_guidedmotion_cli.py",  # 128
    "e2e/test_notebooks.py",  # 127
    "e2e/test_ddp_cli.py",  # 96
    "e2e/test_train_sample_cli.py",  # 90
    "integration/test_variant_matrix.py",  # 78
    "hostile/test_kill_training.py",  # 74
    "hostile/test_kill_sampling.py",  # 67
    "e2e/test_evaluation_cli.py",  # 65
    "hostile/test_boundary.py",  # 61
    "hostile/test_releases.py",  # 60
    "hostile/test_kill_prepare.py",  # 50
    "e2e/test_dashboard.py",  # 50
    "hostile/test_interrupts.py",  # 48
    "e2e/test_edit_cli.py",  # 48
    "hostile/test_bounds.py",  # 47
]


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}

    def key(item) -> int:
        path = Path(str(item.fspath)).relative_to(REPO / "tests").as_posix()
        return rank.get(path, len(rank))

    items.sort(key=key)  # stable: the rest keep their order
