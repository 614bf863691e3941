"""Prompt mapping (issue 39, round C): a prompt's features become those of a training caption of the release's
coverage bank: the nearest one, or the nearest of the action its ten nearest captions vote for; ``none`` keeps the
prompt; the model's condition for a batch goes through the mapping; an unknown mode or a missing bank is one error."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.lit.conditions import condition_batch
from motiondiff.pipelines.coverage import load_prompt_mapping
from motiondiff.runtime.errors import UsageError
from motiondiff.text.coverage import PromptCoverage
from motiondiff.text.prompt_mapping import PromptMapping


def unit(rows):
    rows = np.asarray(rows, dtype=np.float32)
    return rows / np.linalg.norm(rows, axis=1, keepdims=True)


def bank_with_an_odd_caption() -> PromptCoverage:
    """Action 0 ('bow'): one caption at e0; action 1 ('walk'): ten captions near e1 but leaning towards e0."""
    bow = [[1.0, 0.0, 0.0]]
    walk = [[0.8, 0.6, 0.05 * i] for i in range(10)]
    return PromptCoverage(unit(bow + walk), np.array([0] + [1] * 10), ["bow", "walk"], 0.5, "test")


def test_nearest_takes_the_single_closest_caption_and_vote_takes_the_majority_action():
    bank = bank_with_an_odd_caption()
    prompt = unit([[0.95, 0.3, 0.0]])  # closest to the lone bow caption, but near all ten walk captions
    assert PromptMapping(bank, "nearest").actions(prompt) == ["bow"]
    assert PromptMapping(bank, "vote").actions(prompt) == ["walk"]
    mapped = PromptMapping(bank, "vote")(prompt)
    assert np.allclose(mapped[0], bank.features[1])  # the walk caption nearest to the prompt (the one with z = 0)
    assert np.allclose(PromptMapping(bank, "nearest")(prompt)[0], bank.features[0])


def test_none_keeps_the_prompt_and_an_unknown_mode_is_refused():
    bank = bank_with_an_odd_caption()
    prompt = unit([[0.2, 0.9, 0.1]])
    np.testing.assert_array_equal(PromptMapping(bank, "none")(prompt), prompt)
    assert PromptMapping(bank, "none").actions(prompt) == [None]
    with pytest.raises(ValueError, match="choose one of none, nearest, vote"):
        PromptMapping(bank, "closest")


class TextModule:
    """What condition_batch reads of a text model: cached prompt features and prepare_text."""

    condition_kind = "text"
    device = torch.device("cpu")

    def __init__(self, features: dict[str, np.ndarray]):
        self._encoder = None
        self._prompt_features = {k: torch.tensor(v) for k, v in features.items()}

    def prepare_text(self, features):
        return features * 2  # stands for the model's own projection


def test_the_model_is_conditioned_on_the_mapped_caption():
    bank = bank_with_an_odd_caption()
    module = TextModule({"take a bow": unit([[0.99, 0.0, 0.1]])[0]})
    as_written = condition_batch(module, ["take a bow"])
    module.prompt_mapping = PromptMapping(bank, "nearest")
    mapped = condition_batch(module, ["take a bow"])
    assert torch.allclose(mapped[0], 2 * torch.from_numpy(bank.features[0]))
    assert not torch.allclose(mapped, as_written)


def test_a_mode_needs_its_bank(tmp_path):
    assert load_prompt_mapping(tmp_path / "model.safetensors", "none") is None
    with pytest.raises(UsageError, match="needs the coverage bank .*model.coverage.safetensors"):
        load_prompt_mapping(tmp_path / "model.safetensors", "vote")
    with pytest.raises(UsageError, match="choose one of"):
        load_prompt_mapping(tmp_path / "model.safetensors", "closest")


def test_evaluate_checks_the_same_modes():
    from motiondiff.cli.validate import RULES_EVALUATE
    from motiondiff.text.prompt_mapping import MODES

    assert RULES_EVALUATE["prompt_mapping"].options == MODES
