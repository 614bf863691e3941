"""FLOPs of a piece of work (PyTorch's FlopCounterMode: matmuls, convolutions and attention, 2 per multiply-add)
and the FLOP/s of a plain matmul of given shapes, so a model's speed reads as a share of what the machine's GEMM
does in the same run (model FLOPs utilisation)."""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch.utils.flop_counter import FlopCounterMode

from motiondiff.bench.timing import median_seconds


def count_flops(fn: Callable[[], object]) -> int:
    counter = FlopCounterMode(display=False)
    with counter:
        fn()
    return int(counter.get_total_flops())


def matmul_flops_per_s(m: int, k: int, n: int, dtype: torch.dtype = torch.float32, repeats: int = 5) -> dict:
    """(m, k) @ (k, n) in ``dtype``: median seconds and FLOP/s (2·m·k·n per product)."""
    a, b = torch.randn(m, k, dtype=dtype), torch.randn(k, n, dtype=dtype)
    timing = median_seconds(lambda: a @ b, repeats=repeats)
    return {"shape": [m, k, n], "dtype": str(dtype).removeprefix("torch."), "median_s": timing["median_s"],
            "flops_per_s": 2 * m * k * n / timing["median_s"]}  # fmt: skip
