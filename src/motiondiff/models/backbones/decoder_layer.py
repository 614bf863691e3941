"""``nn.TransformerDecoderLayer`` with faster CPU passes, as the encoder's (``encoder_layer``): training drops out with
``FastDropout`` (attention weights included), inference attends with ``scaled_dot_product_attention``.

In CPU training PyTorch's layer draws every dropout mask with the slow ``bernoulli_``, the largest inside the
self-attention kernel (heads x frames x frames per motion), so the CPU training pass writes both attentions out
(projections, scaled scores, softmax, dropout, weighted sum, output projection). PyTorch's inference runs both
attentions through ``MultiheadAttention``'s native path, unfused and slower still with a padding mask: on a padded
batch of the CPU-size model the layer written out around ``scaled_dot_product_attention`` is 2-3x faster, with the
same output to float rounding (``bench/cpu_attention.py``). GPUs run PyTorch's layer unchanged; the parameters and
state dict are the parent's, so a checkpoint loads into either class.
"""

from __future__ import annotations

from torch import Tensor, nn

from motiondiff.models.backbones.cpu_attention import (
    attend_dropping,
    cross_attention,
    cross_qkv,
    merge_heads,
    self_attention,
    self_qkv,
)
from motiondiff.models.fast_dropout import FastDropout


class FastDropoutDecoderLayer(nn.TransformerDecoderLayer):
    """Same arguments and parameters as ``nn.TransformerDecoderLayer`` (batch_first=True for the CPU paths)."""

    fused_inference = False  # True: CPU inference in PyTorch's own layer (bench/cpu_attention.py's reference)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.dropout, self.dropout1, self.dropout2, self.dropout3 = (
            FastDropout(d.p) for d in (self.dropout, self.dropout1, self.dropout2, self.dropout3)
        )

    def forward(self, tgt: Tensor, memory: Tensor, tgt_mask: Tensor | None = None, memory_mask: Tensor | None = None,
                tgt_key_padding_mask: Tensor | None = None, memory_key_padding_mask: Tensor | None = None,
                tgt_is_causal: bool = False, memory_is_causal: bool = False) -> Tensor:  # fmt: skip
        if self.training or self.fused_inference or not self._own_attention(tgt, tgt_mask, memory_mask, tgt_is_causal,
                                                                              memory_is_causal):  # fmt: skip
            return super().forward(tgt, memory, tgt_mask, memory_mask, tgt_key_padding_mask, memory_key_padding_mask,
                                   tgt_is_causal, memory_is_causal)  # fmt: skip
        x = tgt  # CPU inference: PyTorch's layer, its attentions through scaled_dot_product_attention
        if self.norm_first:
            x = x + self_attention(self.self_attn, self.norm1(x), tgt_key_padding_mask)
            x = x + cross_attention(self.multihead_attn, self.norm2(x), memory, memory_key_padding_mask)
            return x + self._ff_block(self.norm3(x))
        x = self.norm1(x + self_attention(self.self_attn, x, tgt_key_padding_mask))
        x = self.norm2(x + cross_attention(self.multihead_attn, x, memory, memory_key_padding_mask))
        return self.norm3(x + self._ff_block(x))

    def _own_attention(self, x: Tensor, *masks_and_causal) -> bool:
        """Whether this class attends itself: on the CPU, batch-first, one embedding size, with padding masks only (no
        attention mask, not causal). Otherwise PyTorch's layer runs (GPUs: its fused kernels drop out cheaply)."""
        same_dims = self.self_attn._qkv_same_embed_dim and self.multihead_attn._qkv_same_embed_dim
        return (
            x.device.type == "cpu"
            and self.self_attn.batch_first
            and same_dims
            and not any(m is not None and m is not False for m in masks_and_causal)
        )

    def _sa_block(self, x: Tensor, attn_mask: Tensor | None, key_padding_mask: Tensor | None,
                  is_causal: bool = False) -> Tensor:  # fmt: skip
        if not self.training or not self._own_attention(x, attn_mask, is_causal):
            return super()._sa_block(x, attn_mask, key_padding_mask, is_causal)
        q, k, v = self_qkv(self.self_attn, x)
        out = attend_dropping(q, k, v, key_padding_mask, self.self_attn.dropout)
        return self.dropout1(merge_heads(self.self_attn, out))

    def _mha_block(self, x: Tensor, mem: Tensor, attn_mask: Tensor | None, key_padding_mask: Tensor | None,
                   is_causal: bool = False) -> Tensor:  # fmt: skip
        if not self.training or not self._own_attention(x, attn_mask, is_causal):
            return super()._mha_block(x, mem, attn_mask, key_padding_mask, is_causal)
        attn = self.multihead_attn
        q, k, v = cross_qkv(attn, x, mem)
        return self.dropout2(merge_heads(attn, attend_dropping(q, k, v, key_padding_mask, attn.dropout)))
