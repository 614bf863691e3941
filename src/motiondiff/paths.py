"""Where the project's files are: its configs, released models and evaluators and the embedded data (`REPO_DIR`),
where a run writes (`WORK_DIR`), and the checkpoints a user names (`find_checkpoint`: a path, shipped, latest or
best).

From a source checkout both are the checkout. An installed wheel carries the configs, checkpoints and data in
motiondiff/_bundled/ (see setup.py); then runs write under the current folder.
"""

from __future__ import annotations

from pathlib import Path

from motiondiff.errors import UsageError

PACKAGE_DIR = Path(__file__).resolve().parent
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


# checkpoint=shipped: the models released with the repo (safetensors + JSON, see checkpoints/models), by condition
SHIPPED_MODELS = {
    "text": REPO_DIR / "checkpoints" / "models" / "bandai_text_long_12k.safetensors",  # docs/results/shipping/rules.md
    "action": REPO_DIR / "checkpoints" / "models" / "bandai_action_cpu.safetensors",
}
SHIPPED_MODEL = SHIPPED_MODELS["text"]
RELEASE_SUFFIXES = (".safetensors", ".json")


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
    if spec in SHIPPED_MODELS and not Path(spec).is_file():  # the Python API's names work here too ("text", "action")
        return find_checkpoint("shipped", output_dir, spec)
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
