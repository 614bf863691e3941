"""Prompt coverage (issue 39): the bank keeps distinct captions per action, the threshold rule separates in-domain
from out-of-domain similarities at the middle of the best range, a far prompt's report names the nearest actions,
and a bank round-trips through its file while a damaged file is one clear error."""

from __future__ import annotations

import numpy as np
import pytest

from motiondiff.text.coverage import PromptCoverage, build_coverage, choose_threshold, coverage_path

VOCAB = ["walk", "walks", "forward", "run", "runs", "wave", "waves", "hand", "jump", "jumps", "person", "a"]


def bag_of_words(texts):
    """A stand-in encoder whose similarities are word overlaps (the real one is MiniLM, tested end to end)."""
    rows = np.zeros((len(texts), len(VOCAB)))
    for i, text in enumerate(texts):
        for word in text.lower().replace(".", "").split():
            if word in VOCAB:
                rows[i, VOCAB.index(word)] += 1
    return rows + 1e-3


CAPTIONS = {"walk": ["a person walks forward.", "a person walks forward.", "walk forward"],
            "run": ["a person runs forward.", "runs"], "wave": ["a person waves a hand."]}  # fmt: skip


def test_the_bank_keeps_distinct_captions_per_action_and_at_most_per_action():
    bank = build_coverage(CAPTIONS, bag_of_words, threshold=0.9, encoder="bow")
    assert bank.action_names == ["run", "walk", "wave"]
    assert np.bincount(bank.actions).tolist() == [2, 2, 1]  # the repeated walk caption once
    small = build_coverage(CAPTIONS, bag_of_words, threshold=0.9, encoder="bow", per_action=1)
    assert np.bincount(small.actions).tolist() == [1, 1, 1]
    assert np.allclose(np.linalg.norm(bank.features, axis=1), 1.0)


def test_a_far_prompt_is_reported_with_its_nearest_actions():
    bank = build_coverage(CAPTIONS, bag_of_words, threshold=0.9, encoder="bow")
    near, far = bank.check(["a person walks forward", "a person jumps"], bag_of_words(["a person walks forward",
                                                                                     "a person jumps"]))  # fmt: skip
    assert not near.far and near.nearest[0][0] == "walk" and near.similarity > 0.99
    assert far.far and far.similarity < 0.9 and len(far.nearest) == 3
    line = far.warning()
    assert "'a person jumps'" in line and "nearest known actions" in line and "\n" not in line


def test_the_threshold_is_the_middle_of_the_best_separating_range():
    assert choose_threshold(np.array([0.9, 0.95, 0.8]), np.array([0.3, 0.5, 0.6])) == pytest.approx((0.7, 1.0))
    # one in-domain value below two out-of-domain ones: the best range is (0.6, 0.9]
    threshold, balanced = choose_threshold(np.array([0.9, 0.95, 0.5]), np.array([0.3, 0.55, 0.6]))
    assert threshold == pytest.approx(0.75) and balanced == pytest.approx(5 / 6)


def test_a_bank_round_trips_and_a_damaged_file_is_one_error(tmp_path):
    bank = build_coverage(CAPTIONS, bag_of_words, threshold=0.8125, encoder="bow")
    path = bank.save(coverage_path(tmp_path / "model.safetensors"))
    assert path.name == "model.coverage.safetensors"
    loaded = PromptCoverage.load(path)
    assert loaded.action_names == bank.action_names and loaded.threshold == 0.8125 and loaded.encoder == "bow"
    assert np.allclose(loaded.features, bank.features, atol=1e-3) and np.array_equal(loaded.actions, bank.actions)
    path.write_bytes(path.read_bytes()[:40])
    with pytest.raises(ValueError, match="coverage bank .* cannot be read"):
        PromptCoverage.load(path)
