"""``nn.TransformerEncoderLayer`` whose training pass drops out with ``FastDropout``, attention weights included.

Inference, and training on GPUs, run PyTorch's own layer unchanged (its fused kernels). In CPU training, PyTorch
computes attention in ``scaled_dot_product_attention``, whose dropout on the attention weights draws its mask
inside the kernel with the slow ``bernoulli_``; for the CPU-size denoiser those weights (heads x frames x frames
per motion) are the largest tensors dropped. So the CPU training pass writes attention out (projection, scaled
scores, softmax, dropout, weighted sum, output projection) with the layer's own parameters: the state dict is the
parent's, and a checkpoint loads into either class.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor, nn

from motiondiff.models.fast_dropout import FastDropout, fast_dropout


class FastDropoutEncoderLayer(nn.TransformerEncoderLayer):
    """Same arguments and parameters as ``nn.TransformerEncoderLayer`` (batch_first=True only)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not self.self_attn.batch_first or not self.self_attn._qkv_same_embed_dim:
            raise ValueError("FastDropoutEncoderLayer needs batch_first=True and one embedding size")
        self.dropout, self.dropout1, self.dropout2 = (
            FastDropout(d.p) for d in (self.dropout, self.dropout1, self.dropout2)
        )

    def _sa_block(self, x: Tensor, attn_mask: Tensor | None, key_padding_mask: Tensor | None, is_causal: bool = False):
        # GPUs: PyTorch's fused attention (flash / memory-efficient kernels) drops out cheaply and saves memory
        if not self.training or attn_mask is not None or is_causal or x.device.type != "cpu":
            return super()._sa_block(x, attn_mask, key_padding_mask, is_causal)
        attn = self.self_attn
        b, n, d = x.shape
        heads = attn.num_heads
        qkv = nn.functional.linear(x, attn.in_proj_weight, attn.in_proj_bias)
        q, k, v = qkv.view(b, n, 3, heads, d // heads).permute(2, 0, 3, 1, 4)  # each (B, heads, N, d/heads)
        scores = torch.matmul(q, k.transpose(-1, -2)) * (d // heads) ** -0.5
        if key_padding_mask is not None:  # True / -inf: a key to ignore (the encoder may pass either form)
            pad = key_padding_mask[:, None, None, :]
            scores = scores.masked_fill(pad, float("-inf")) if pad.dtype == torch.bool else scores + pad
        weights = fast_dropout(scores.softmax(dim=-1), attn.dropout, True)
        out = torch.matmul(weights, v).transpose(1, 2).reshape(b, n, d)
        return self.dropout1(attn.out_proj(out))


@dataclass(frozen=True)
class TransformerSize:
    """The sizes of a stack of GELU ``FastDropoutEncoderLayer``s: GuidedMotion's VAEs and latent denoisers take them
    as keyword arguments (the keys of ``vae`` and ``latent.model`` in conf/)."""

    d_model: int = 256
    num_layers: int = 4
    num_heads: int = 4
    ff_size: int = 1024
    dropout: float = 0.1

    def layer(self) -> FastDropoutEncoderLayer:
        return FastDropoutEncoderLayer(self.d_model, self.num_heads, self.ff_size, self.dropout, activation="gelu",
                                       batch_first=True)  # fmt: skip
