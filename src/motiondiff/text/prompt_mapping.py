"""Prompt mapping: condition a text model on the training caption a prompt is nearest to, not on the prompt itself.

A model conditioned on generated captions learns their small corner of the text encoder's space; a person's own
wording ("someone takes a deep bow to the audience") lands between those captions, where the model's condition
network was never trained, while the same encoder still finds the right caption by cosine similarity
(docs/results/recipe_search/rules.md, round C). Mapping replaces the prompt's features by those of a caption of the
release's coverage bank (`text.coverage`):
- ``nearest``: the single nearest caption;
- ``vote``: the K nearest captions vote for an action, each with its similarity, and the prompt becomes its nearest
  caption of the winning action (one odd caption cannot decide).
``none`` conditions on the prompt as written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondiff.text.coverage import PromptCoverage

MODES = ("none", "nearest", "vote")
VOTERS = 10


def check_mode(mode: str) -> str:
    if mode not in MODES:
        raise ValueError(f"prompt_mapping={mode!r}: choose one of {', '.join(MODES)}")
    return mode


@dataclass(frozen=True)
class PromptMapping:
    """A coverage bank and the rule that maps prompt features onto its captions."""

    bank: PromptCoverage
    mode: str = "vote"
    voters: int = VOTERS

    def __post_init__(self):
        check_mode(self.mode)

    def rows(self, features: np.ndarray) -> np.ndarray:
        """(P,) the bank row each prompt is mapped to (-1: kept as written)."""
        if self.mode == "none":
            return np.full(len(features), -1)
        sims = self.bank.similarities(features)
        if self.mode == "nearest":
            return sims.argmax(axis=1)
        chosen = np.empty(len(sims), dtype=np.int64)
        for p, row in enumerate(sims):
            top = np.argsort(-row)[: self.voters]
            votes = np.zeros(len(self.bank.action_names))
            np.add.at(votes, self.bank.actions[top], row[top])
            winner = int(votes.argmax())
            of_winner = np.flatnonzero(self.bank.actions == winner)
            chosen[p] = of_winner[row[of_winner].argmax()]
        return chosen

    def __call__(self, features: np.ndarray) -> np.ndarray:
        """(P, E) the features to condition on: the mapped captions' (unit, as the encoder's), or the prompt's own."""
        features = np.asarray(features, dtype=np.float32)
        rows = self.rows(features)
        mapped = features.copy()
        kept = rows >= 0
        mapped[kept] = self.bank.features[rows[kept]]
        return mapped

    def actions(self, features: np.ndarray) -> list[str | None]:
        """The action of the caption each prompt is mapped to (None: kept as written)."""
        return [self.bank.action_names[self.bank.actions[r]] if r >= 0 else None for r in self.rows(features)]
