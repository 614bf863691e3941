"""Where the project's files are: its configs, released models and evaluators and the embedded data (`REPO_DIR`),
where a run writes (`work_dir`). Which model file a name means is `model_files.resolve`.

From a source checkout both are the checkout. An installed wheel carries the configs, checkpoints and data in
motiondiff/_bundled/ (see setup.py); then runs write under the current folder.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]  # src/motiondiff (this file is runtime/paths.py)
BUNDLED_DIR = PACKAGE_DIR / "_bundled"
INSTALLED = (BUNDLED_DIR / "conf").is_dir()
REPO_DIR = BUNDLED_DIR if INSTALLED else PACKAGE_DIR.parents[1]  # conf/, checkpoints/, data/
CONF_DIR = REPO_DIR / "conf"


def shown(path: str | Path) -> str:
    """A path as a committed report names it: repo-relative where possible, never this machine's folders."""
    path = Path(path).resolve()
    return str(path.relative_to(REPO_DIR)) if path.is_relative_to(REPO_DIR) else str(path)


def work_dir() -> Path:
    """Where outputs/ and .cache/ go: the checkout, or the current folder for an installed package."""
    return Path.cwd() if INSTALLED else REPO_DIR
