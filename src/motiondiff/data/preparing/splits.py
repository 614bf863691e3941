"""Deterministic, stratified train/val/test assignment and stratified subsets."""

from __future__ import annotations

import hashlib
from collections import Counter, defaultdict
from collections.abc import Hashable, Sequence

# Every 10 consecutive clips of the stratified order: 8 train, 1 val, 1 test.
PATTERN = ("train",) * 8 + ("val", "test")


def _key(name: str, seed: int) -> str:
    return hashlib.sha256(f"{seed}:{name}".encode()).hexdigest()


def stratified_split(names: Sequence[str], groups: Sequence[Hashable], seed: int = 0) -> list[str]:
    """Split by clip, stratified by group (e.g. content x style): clips are ordered by group, then by a seeded hash
    inside the group, and dealt out as 8 train / 1 val / 1 test along that order. Groups with 10+ clips get
    80/10/10 each; the many 1-2-clip groups of Bandai-1 are spread over all three splits instead of all landing
    in train. A clip's split depends only on the seed and the set of clips, not on the order they were read in."""
    order = sorted(range(len(names)), key=lambda i: (str(groups[i]), _key(names[i], seed)))
    result = [""] * len(names)
    for rank, i in enumerate(order):
        result[i] = PATTERN[rank % len(PATTERN)]
    return result


def rare_to_train(split: list[str], labels: Sequence[Hashable], min_clips: int) -> list[str]:
    """Clips of a label with fewer than `min_clips` clips in all go to train: one held-out clip measures nothing
    reliably, while it may be the only example of that action a model could learn from (Bandai-1's one kick)."""
    counts = Counter(labels)
    return ["train" if counts[label] < min_clips else s for s, label in zip(split, labels, strict=True)]


def stratified_subset(names: Sequence[str], groups: Sequence[Hashable], per_group: int, seed: int = 0) -> list[int]:
    """Indices of up to `per_group` clips of every group (seeded choice), in the input order."""
    by_group: dict[Hashable, list[int]] = defaultdict(list)
    for i, g in enumerate(groups):
        by_group[g].append(i)
    keep = []
    for members in by_group.values():
        keep += sorted(members, key=lambda i: _key(names[i], seed))[:per_group]
    return sorted(keep)
