"""Dropout with a cheaper mask on CPU: the same operation as ``nn.Dropout``, drawn from another random stream.

PyTorch's CPU dropout draws its mask with ``bernoulli_`` at about 90 M elements/s on this project's 2-core machine:
22% of a training step of the CPU-size denoiser and 15% of the paper-size one (``torch.profiler``). Here the mask
comes from raw 64-bit random words (``random_``), read as eight 8-bit numbers each and compared with a threshold
(twice as fast as 16-bit numbers, which took 12 ms per 8 M elements against 6). The comparison writes the mask as
0/1 in the activation's dtype, kept for the backward pass, and both passes multiply by it, then by the scale: on a
bf16 tensor a multiply is vectorised where ``torch.where`` with a bool mask and a bool-to-bf16 cast are not
(docs/performance.md). The numbers are the same as with ``torch.where`` (x * 1 = x, x * 0 = 0 for finite x). On
other devices this is ``F.dropout``.

The keep probability is rounded to a multiple of 1/256 (0.9 -> 0.8984, so p = 0.1 drops 10.16%); the kept values
are scaled by the reciprocal of that rounded probability, so the output's expectation is the input exactly. The words come from
PyTorch's default generator, so ``torch.manual_seed`` makes a run repeatable as before, but the masks differ from
``nn.Dropout``'s: a training run reproduces its own numbers, not those of a run made with ``nn.Dropout``.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn

_LEVELS = 256  # 8-bit numbers


def keep_mask(shape: tuple[int, ...], p: float, device: torch.device | None = None,
              dtype: torch.dtype = torch.bool) -> tuple[Tensor, float]:  # fmt: skip
    """(mask of ``shape``, True (1) with probability ≈ 1 − p; that probability exactly). ``dtype``: bool, or a
    floating dtype for a 0/1 mask to multiply by (the same draws and the same mask either way)."""
    if not 0 <= p < 1:
        raise ValueError(f"dropout probability must be in [0, 1), got {p}")
    levels = max(round((1 - p) * _LEVELS), 1)
    if levels == _LEVELS:  # p below 1/512 rounds to 0 (and the threshold would not fit in 8 bits)
        return torch.ones(shape, dtype=dtype, device=device), 1.0
    n = math.prod(shape)
    words = torch.empty((n + 7) // 8, dtype=torch.int64, device=device).random_(-(2**63), 2**63 - 1)
    numbers = words.view(torch.int8)[:n].view(shape)
    mask = torch.empty(shape, dtype=dtype, device=device)
    return torch.lt(numbers, levels - _LEVELS // 2, out=mask), levels / _LEVELS


class _MaskedScale(torch.autograd.Function):
    """y = x · mask · scale for a 0/1 mask; the backward pass is the same map on the gradient. The scale is applied
    as a Python float (in the op's full-precision arithmetic), not folded into a bf16 mask, where 1/0.8984 would round
    by 0.3%."""

    @staticmethod
    def forward(ctx, x: Tensor, mask: Tensor, scale: float) -> Tensor:
        ctx.save_for_backward(mask)
        ctx.scale = scale
        return (x * mask).mul_(scale)

    @staticmethod
    def backward(ctx, grad: Tensor):
        (mask,) = ctx.saved_tensors
        return (grad * mask).mul_(ctx.scale), None, None


def fast_dropout(x: Tensor, p: float, training: bool = True) -> Tensor:
    """``F.dropout(x, p, training)`` with the cheaper mask (identity when not training or p = 0)."""
    if not training or p == 0:
        return x
    if x.device.type != "cpu":  # GPUs draw dropout masks fast (and fused); the cheaper mask is for CPUs
        return nn.functional.dropout(x, p, True)
    mask, keep = keep_mask(tuple(x.shape), p, x.device, x.dtype)
    return _MaskedScale.apply(x, mask, 1.0 / keep)


class FastDropout(nn.Dropout):
    """``nn.Dropout`` with the cheaper mask; a drop-in replacement (no parameters, same ``p``)."""

    def forward(self, x: Tensor) -> Tensor:
        return fast_dropout(x, self.p, self.training)
