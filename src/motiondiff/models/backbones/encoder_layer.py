"""``nn.TransformerEncoderLayer`` with faster CPU passes: training drops out with ``FastDropout`` (attention weights
included), inference attends with ``scaled_dot_product_attention``.

GPUs run PyTorch's own layer unchanged (its fused kernels). In CPU training, PyTorch computes attention in
``scaled_dot_product_attention``, whose dropout on the attention weights draws its mask inside the kernel with the
slow ``bernoulli_``; for the CPU-size denoiser those weights (heads x frames x frames per motion) are the largest
tensors dropped, so the CPU training pass writes attention out (projection, scaled scores, softmax, dropout, weighted
sum, output projection). CPU inference skips PyTorch's fused encoder-layer path, whose attention runs unfused
(batched matmuls, a separate softmax, a q/k/v rescale pass) and slows down further with a padding mask: the layer
written out around ``scaled_dot_product_attention`` (the CPU flash kernel) gives the same motions to float rounding
in about half the time on a padded evaluation batch (docs/performance.md). Both use the layer's own parameters: the
state dict is the parent's, and a checkpoint loads into either class.
"""

from __future__ import annotations

from dataclasses import dataclass

from torch import Tensor, nn

from motiondiff.models.backbones.cpu_attention import attend_dropping, merge_heads, self_attention, self_qkv
from motiondiff.models.fast_dropout import FastDropout


class FastDropoutEncoderLayer(nn.TransformerEncoderLayer):
    """Same arguments and parameters as ``nn.TransformerEncoderLayer`` (batch_first=True only)."""

    fused_inference = False  # True: CPU inference in PyTorch's fused layer (bench/cpu_attention.py's reference)

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        if not self.self_attn.batch_first or not self.self_attn._qkv_same_embed_dim:
            raise ValueError("FastDropoutEncoderLayer needs batch_first=True and one embedding size")
        self.dropout, self.dropout1, self.dropout2 = (
            FastDropout(d.p) for d in (self.dropout, self.dropout1, self.dropout2)
        )

    def forward(self, src: Tensor, src_mask: Tensor | None = None, src_key_padding_mask: Tensor | None = None,
                is_causal: bool = False) -> Tensor:  # fmt: skip
        if self.training or src_mask is not None or is_causal or src.device.type != "cpu" or self.fused_inference:
            return super().forward(src, src_mask, src_key_padding_mask, is_causal)
        if self.norm_first:  # CPU inference: PyTorch's layer, its attention through scaled_dot_product_attention
            x = src + self._attend(self.norm1(src), src_key_padding_mask)
            return x + self._ff_block(self.norm2(x))
        x = self.norm1(src + self._attend(src, src_key_padding_mask))
        return self.norm2(x + self._ff_block(x))

    def _sa_block(self, x: Tensor, attn_mask: Tensor | None, key_padding_mask: Tensor | None, is_causal: bool = False):
        # GPUs: PyTorch's fused attention (flash / memory-efficient kernels) drops out cheaply and saves memory
        if not self.training or attn_mask is not None or is_causal or x.device.type != "cpu":
            return super()._sa_block(x, attn_mask, key_padding_mask, is_causal)
        q, k, v = self_qkv(self.self_attn, x)  # the encoder may pass the padding mask as bool or -inf
        out = attend_dropping(q, k, v, key_padding_mask, self.self_attn.dropout)
        return self.dropout1(merge_heads(self.self_attn, out))

    def _attend(self, x: Tensor, key_padding_mask: Tensor | None) -> Tensor:
        return self_attention(self.self_attn, x, key_padding_mask)


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
