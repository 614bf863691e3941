"""Which model file a name or path means: the one resolver behind `checkpoint=` on every command and
`from_pretrained` in the Python API, so both take the same names.

Names: "shipped" (the released model for the condition asked: text, action or guidedmotion), the condition names
themselves ("text", "action", "guidedmotion"), a release's file stem in checkpoints/models ("bandai_text_cpu"),
"latest" / "best" (the newest training run's last or best-FID checkpoint), or a path to a .ckpt / .safetensors /
.json file.
"""

from __future__ import annotations

from pathlib import Path

from motiondiff.runtime.best_checkpoints import best_of
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.file_kinds import file_problem
from motiondiff.runtime.paths import REPO_DIR, work_dir

MODELS_DIR = REPO_DIR / "checkpoints" / "models"
RELEASE_SUFFIXES = (".safetensors", ".json")
# checkpoint=shipped: the models released with the repo (safetensors + JSON, see checkpoints/models), by condition
SHIPPED_MODELS = {
    "text": MODELS_DIR / "bandai_text_trans_dec_40k.safetensors",  # docs/results/shipping/rules.md (2026-12-07)
    "action": MODELS_DIR / "bandai_action_trans_dec_14k.safetensors",  # rule W, docs/results/bandai_action (2026-12-07)
    "guidedmotion": MODELS_DIR / "bandai_guided_cpu.safetensors",  # with its three VAEs; docs/results/guidedmotion
}
RUN_NAMES = ("latest", "best")


def released_names() -> list[str]:
    """Every name `find_model` takes for a released file: the condition names and the stems in checkpoints/models."""
    return sorted({*SHIPPED_MODELS, *(p.stem for p in MODELS_DIR.glob("*.safetensors") if "." not in p.stem)})


def find_model(spec: str | Path, output_dir: str | Path | None = None, condition: str = "text") -> Path:
    """The model file that `spec` names (see the module docstring); `condition` picks what "shipped" means;
    `output_dir` is where "latest"/"best" look for runs (default: this checkout's or folder's outputs/)."""
    key = str(spec)
    if not isinstance(spec, str | Path) or not key.strip():
        raise UsageError(f"no model named: give a released model's name ({', '.join(released_names())}) or the path "
                         "of a .ckpt/.safetensors file")  # fmt: skip
    if Path(key).name.endswith((".coverage", ".coverage.safetensors")):
        raise UsageError(f"{key} is a release's prompt-coverage bank, not a model: name the release itself "
                         f"({key.split('.coverage')[0]})")  # fmt: skip
    if key == "shipped":
        key = condition
    if key in SHIPPED_MODELS and not Path(key).is_file():
        shipped = SHIPPED_MODELS[key]
        if not shipped.is_file():
            raise UsageError(f"the shipped {key} model {shipped} is missing: restore it with "
                             "`git checkout -- checkpoints`")  # fmt: skip
        return shipped
    if key in RUN_NAMES:
        return _from_runs(key, Path(output_dir) if output_dir is not None else work_dir() / "outputs")
    if "/" not in key and (MODELS_DIR / f"{key}.safetensors").is_file():
        return MODELS_DIR / f"{key}.safetensors"
    path = Path(key)
    if path.is_file():
        return path
    if path.is_dir():
        raise UsageError(f"checkpoint {path} is a folder, not a model file: pass checkpoint=<path to a .ckpt or "
                         ".safetensors file>, checkpoint=shipped, checkpoint=latest or checkpoint=best")  # fmt: skip
    if "/" in key or path.suffix:  # meant as a file
        problem = file_problem(path, allow_empty=True)
        if problem is not None and not problem.startswith("not found"):
            raise UsageError(f"checkpoint {path} {problem}; pass checkpoint=<path to a .ckpt or .safetensors file>")
        raise UsageError(f"checkpoint {path} not found; pass checkpoint=<path to a .ckpt or .safetensors release>, "
                         f"checkpoint=shipped, checkpoint=latest, checkpoint=best or a released model's name "
                         f"({', '.join(released_names())})")  # fmt: skip
    raise UsageError(f"no model {key!r}: give a released model ({', '.join(released_names())}), shipped, latest, "
                     "best, or a path to a .ckpt or .safetensors file")  # fmt: skip


def _from_runs(which: str, output_dir: Path) -> Path:
    runs = sorted(output_dir.glob("train*/**/checkpoints/last.ckpt"), key=lambda p: p.stat().st_mtime)
    if not runs:
        raise UsageError(
            f"no trained checkpoint under {output_dir}/train*: train one first (`make train` or `python train.py`) "
            "pass checkpoint=<path to a .ckpt>, or use the released model: checkpoint=shipped"
        )
    if which == "latest":
        return runs[-1]
    best = best_of(sorted(runs[-1].parent.glob("best-fid-*.ckpt")), "val/fid")  # by stored FID, not by name
    if best is None:
        raise UsageError(
            f"the newest run {runs[-1].parent.parent} has no best-FID checkpoint (it trained without evaluators or "
            "never evaluated); use checkpoint=latest"
        )
    return best
