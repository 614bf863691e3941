"""Rule E's measurement (bandai_action_v2.md): the released full-Bandai action classifier and a candidate, on the
real clips of the val split: accuracy, balanced accuracy (mean per-action recall) and recall per action.

    python docs/results/evaluators/compare_action.py <candidate folder holding action.safetensors/.json>
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from motiondiff.data.datamodules import PreparedDataModule
from motiondiff.eval.protocol import EvalClips, Evaluators
from motiondiff.model_files.evaluators import load_released
from motiondiff.runtime.paths import REPO_DIR


def scores(folder: Path, dm) -> tuple[dict, dict]:
    model, meta = load_released(folder / "action")
    evaluators = Evaluators(None, model, dm.num_joints)
    clips = EvalClips.from_dataset(dm.dataset("val"))
    predicted = evaluators.embed_motion(clips.features)["action_logits"].argmax(-1)
    names = meta["action_names"]
    recall = {names[a]: (float((predicted[clips.actions == a] == a).mean()), int((clips.actions == a).sum()))
              for a in np.unique(clips.actions)}  # fmt: skip
    return {"accuracy": float((predicted == clips.actions).mean()),
            "balanced_accuracy": float(np.mean([r for r, _ in recall.values()]))}, recall  # fmt: skip


def main(candidate: str) -> None:
    dm = PreparedDataModule(root=str(REPO_DIR / "data" / "bandai"), batch_size=64)
    dm.setup(None)
    rows = {name: scores(Path(f), dm) for name, f in (("released", REPO_DIR / "checkpoints/evaluators/bandai"),
                                                      ("candidate", candidate))}  # fmt: skip
    print("| classifier | val accuracy | val balanced accuracy |\n|---|---:|---:|")
    for name, (total, _) in rows.items():
        print(f"| {name} | {total['accuracy']:.3f} | {total['balanced_accuracy']:.3f} |")
    print("\n| action | val clips | released | candidate |\n|---|---:|---:|---:|")
    for action, (recall, count) in rows["released"][1].items():
        print(f"| {action} | {count} | {recall:.2f} | {rows['candidate'][1][action][0]:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1])
