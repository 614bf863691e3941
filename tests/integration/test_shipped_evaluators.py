"""The evaluators shipped for the embedded data do their job on its real test clips (no generated motion)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiondiff.cli.common import REPO_DIR
from motiondiff.cli.train_evaluator import test_checks as evaluator_checks
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.eval.protocol import EvalClips, Evaluators, time_reversed

FOLDER = REPO_DIR / "checkpoints" / "evaluators" / "bandai_mini"


@pytest.fixture(scope="module")
def setup():
    if not (FOLDER / "text_motion.safetensors").is_file():
        pytest.skip(f"no shipped evaluators in {FOLDER}: python -m motiondiff.cli.train_evaluator")
    dm = PreparedDataModule(embedded_data_root(), max_frames=80)
    dm.setup(None)
    return Evaluators.load(FOLDER), dm


def test_shipped_evaluators_pass_their_checks(setup):
    evaluators, dm = setup
    checks = evaluator_checks(evaluators, dm)
    print("\nshipped evaluators on the embedded test split (real clips):")
    for k, v in checks.items():
        print(f"  {k}: {v:.4g}" if isinstance(v, float) else f"  {k}: {v}")
    assert checks["r_precision_top3"] >= 0.60  # chance: 3/31
    assert checks["fid_test_vs_reversed"] >= 10 * checks["fid_test_vs_train"]
    assert checks["accuracy"] >= 0.85
    # the released JSON records the same checks (nothing was changed after they were measured); checks added to
    # the code after the release (balanced_accuracy) are not in it
    recorded = json.loads((FOLDER / "text_motion.json").read_text())["meta"]["test_checks"]
    for k, v in recorded.items():
        assert checks[k] == pytest.approx(v, rel=1e-4, abs=1e-6), k


def test_time_reversal_is_reencoded_not_flipped(setup):
    _, dm = setup
    clip = EvalClips.from_dataset(dm.dataset("test")).features[0]
    back = time_reversed(clip, 22)
    assert back.shape == (clip.shape[0] - 1, clip.shape[1])  # features of N frames have N - 1 rows
    twice = time_reversed(back, 22)
    # Same poses after two reversals: root-relative joint heights and horizontal distances (the facing direction
    # is re-estimated with a smoothing filter whose ends differ, so compare what does not depend on it).
    a = twice[:, 4:67].reshape(len(twice), 21, 3)
    b = clip[1 : 1 + len(twice), 4:67].reshape(len(twice), 21, 3)
    assert np.abs(a[..., 1] - b[..., 1]).max() < 1e-4
    assert np.abs(np.linalg.norm(a[..., [0, 2]], axis=-1) - np.linalg.norm(b[..., [0, 2]], axis=-1)).max() < 1e-3


def test_full_bandai_evaluators_recognise_the_embedded_clips():
    """The evaluators released for the full Bandai set (checkpoints/evaluators/bandai) read the embedded clips, which
    are a subset of that set, as a released classifier should: the actions of the real clips, and their val/test
    checks recorded beside the training provenance."""
    folder = REPO_DIR / "checkpoints" / "evaluators" / "bandai"
    if not (folder / "action.safetensors").is_file():
        pytest.skip(f"no evaluators in {folder}: python -m motiondiff.cli.train_evaluator dataset=bandai")
    evaluators = Evaluators.load(folder)
    names = evaluators.action_names
    assert len(names) == 24 and "kick" in names
    for kind in ("action", "text_motion"):
        meta = evaluators.meta[kind]
        assert (
            meta["dataset"] == "bandai"
            and meta["val_checks"]["val_clips"] > 200
            and "dataset=bandai" in meta["command"]
        )
    dm = PreparedDataModule(embedded_data_root(), max_frames=120)
    dm.setup(None)
    clips = EvalClips.from_dataset(dm.dataset("test"))
    asked = np.array([names.index(dm.action_names[a]) for a in clips.actions])
    predicted = evaluators.embed_motion(clips.features)["action_logits"].argmax(-1)
    # The embedded clips are 4-s crops of their most active frames, which the classifier (trained on whole clips)
    # never saw, and mostly Bandai-1 actions with 1-15 clips, which it recognises poorly even whole
    # (docs/results/bandai_text/README.md): 0.58 when released. A floor far above chance (1/24), not the headline.
    assert (predicted == asked).mean() >= 0.5
    assert meta["test_checks"]["test_clips"] > 200 and evaluators.meta["action"]["test_checks"]["accuracy"] >= 0.9
