"""Attention of a PyTorch ``nn.MultiheadAttention`` (batch_first, one embedding size) written out with its own
weights, for the CPU passes of this project's Transformer layers.

PyTorch's inference paths on the CPU (the fused encoder layer, ``MultiheadAttention``'s native fast path) attend
unfused (batched matmuls, a separate softmax, a q/k/v rescale pass) and slow down further with a padding mask;
``scaled_dot_product_attention`` (the CPU flash kernel) gives the same result to float rounding in less time
(``bench/cpu_attention.py``). CPU training attends with ``attend_dropping`` instead, so that the attention weights
drop out with ``FastDropout`` (``bench/decoder_training.py``).
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from motiondiff.models.fast_dropout import fast_dropout


def sdpa_mask(key_padding_mask: Tensor | None) -> Tensor | None:
    """A (B, N) key padding mask, in either form PyTorch's layers pass (True or -inf: a key to ignore), as the
    (B, 1, 1, N) mask ``scaled_dot_product_attention`` takes (True or 0: a key to attend to)."""
    if key_padding_mask is None:
        return None
    pad = key_padding_mask[:, None, None, :]
    return ~pad if pad.dtype == torch.bool else pad


def split_heads(x: Tensor, heads: int) -> Tensor:
    """(B, N, d) -> (B, heads, N, d / heads)."""
    b, n, d = x.shape
    return x.view(b, n, heads, d // heads).transpose(1, 2)


def self_qkv(attn: nn.MultiheadAttention, x: Tensor) -> tuple[Tensor, Tensor, Tensor]:
    """q, k, v of ``x`` (B, N, d) from one packed projection, each (B, heads, N, d / heads)."""
    b, n, d = x.shape
    qkv = nn.functional.linear(x, attn.in_proj_weight, attn.in_proj_bias)
    return qkv.view(b, n, 3, attn.num_heads, d // attn.num_heads).permute(2, 0, 3, 1, 4)


def merge_heads(attn: nn.MultiheadAttention, heads: Tensor) -> Tensor:
    """(B, heads, N, d / heads) -> the output projection of (B, N, d)."""
    b, h, n, dh = heads.shape
    return attn.out_proj(heads.transpose(1, 2).reshape(b, n, h * dh))


def self_attention(attn: nn.MultiheadAttention, x: Tensor, key_padding_mask: Tensor | None = None) -> Tensor:
    """``attn(x, x, x)`` without dropout (inference) in ``scaled_dot_product_attention``."""
    q, k, v = self_qkv(attn, x)
    return merge_heads(attn, nn.functional.scaled_dot_product_attention(q, k, v, attn_mask=sdpa_mask(key_padding_mask)))


def cross_qkv(attn: nn.MultiheadAttention, x: Tensor, memory: Tensor) -> tuple[Tensor, Tensor, Tensor]:
    """q of ``x`` (B, N, d), k and v of ``memory`` (B, M, d), each split into heads (B, heads, ·, d / heads)."""
    d, h = x.shape[-1], attn.num_heads
    w, b = attn.in_proj_weight, attn.in_proj_bias
    q = split_heads(nn.functional.linear(x, w[:d], b[:d]), h)
    k = split_heads(nn.functional.linear(memory, w[d : 2 * d], b[d : 2 * d]), h)
    v = split_heads(nn.functional.linear(memory, w[2 * d :], b[2 * d :]), h)
    return q, k, v


def cross_attention(attn: nn.MultiheadAttention, x: Tensor, memory: Tensor,
                    key_padding_mask: Tensor | None = None) -> Tensor:  # fmt: skip
    """``attn(x, memory, memory)`` without dropout (inference) in ``scaled_dot_product_attention``."""
    q, k, v = cross_qkv(attn, x, memory)
    out = nn.functional.scaled_dot_product_attention(q, k, v, attn_mask=sdpa_mask(key_padding_mask))
    return merge_heads(attn, out)


def attend_dropping(q: Tensor, k: Tensor, v: Tensor, key_padding_mask: Tensor | None, p: float) -> Tensor:
    """softmax(q kᵀ / √d) v with ``FastDropout`` p on the weights (CPU training): written out, because the attention
    kernel would draw its dropout mask with the slow ``bernoulli_``. The padding mask in either form (True / -inf:
    a key to ignore)."""
    scores = torch.matmul(q, k.transpose(-1, -2)) * q.shape[-1] ** -0.5
    if key_padding_mask is not None:
        pad = key_padding_mask[:, None, None, :]
        scores = scores.masked_fill(pad, float("-inf")) if pad.dtype == torch.bool else scores + pad
    return torch.matmul(fast_dropout(scores.softmax(dim=-1), p, True), v)
