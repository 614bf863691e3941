"""Random known parts for in-painting-aware training (``known_conditioning``): what a training sample is shown clean.

Each sample is shown a known part with probability ``prob``; of those, a ``frame_share`` get frames (a prefix and a
suffix as in in-betweening, or only a prefix as when a long motion continues, or only a suffix), the rest a body part
(every dim of one of the skeleton's part presets, root trajectory included where the part holds the root), as
body-part editing keeps. The rest see nothing, so the same model still generates from scratch.
"""

from __future__ import annotations

import torch

FRAME_RANGE = (0.1, 0.4)  # share of the clip a kept prefix or suffix covers (MDM's default edit keeps 0.25)


def random_known_keep(
    valid: torch.Tensor,
    part_masks: torch.Tensor,
    prob: float,
    frame_share: float,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """valid (B, N) bool frames of each clip, part_masks (P, D) bool dims of each body part -> keep (B, N, D) bool."""
    b, n = valid.shape
    d = part_masks.shape[1]
    keep = torch.zeros(b, n, d, dtype=torch.bool)
    draws = torch.rand(b, 6, generator=generator)  # per sample: known?, frames?, which kind/part, prefix, suffix, spare
    lengths = valid.sum(1).cpu()
    low, high = FRAME_RANGE
    for i in range(b):
        length = int(lengths[i])
        if draws[i, 0] >= prob or length < 3:
            continue
        if draws[i, 1] < frame_share or len(part_masks) == 0:
            kind = int(draws[i, 2] * 3)  # 0: prefix and suffix, 1: prefix only, 2: suffix only
            prefix = 0 if kind == 2 else max(1, round((low + (high - low) * float(draws[i, 3])) * length))
            suffix = 0 if kind == 1 else max(1, round((low + (high - low) * float(draws[i, 4])) * length))
            keep[i, :prefix] = True
            keep[i, length - suffix : length] = True
        else:
            part = part_masks[min(int(draws[i, 2] * len(part_masks)), len(part_masks) - 1)]
            keep[i, :length] = part.cpu()
    return keep.to(valid.device)
