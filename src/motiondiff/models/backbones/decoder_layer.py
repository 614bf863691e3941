"""``nn.TransformerDecoderLayer`` whose CPU inference attends in ``scaled_dot_product_attention``.

PyTorch's layer runs both attentions through ``MultiheadAttention``'s native path, unfused and slower still with a
padding mask: on a padded batch of the CPU-size model the layer written out (`cpu_attention`) is 2-3x faster, with
the same output to float rounding (``bench/cpu_attention.py``). Training and GPUs run PyTorch's layer unchanged;
the parameters and state dict are the parent's, so a checkpoint loads into either class.
"""

from __future__ import annotations

from torch import Tensor, nn

from motiondiff.models.backbones.cpu_attention import cross_attention, self_attention


class CpuInferenceDecoderLayer(nn.TransformerDecoderLayer):
    """Same arguments and parameters as ``nn.TransformerDecoderLayer`` (batch_first=True for the CPU path)."""

    fused_inference = False  # True: CPU inference in PyTorch's own layer (bench/cpu_attention.py's reference)

    def forward(self, tgt: Tensor, memory: Tensor, tgt_mask: Tensor | None = None, memory_mask: Tensor | None = None,
                tgt_key_padding_mask: Tensor | None = None, memory_key_padding_mask: Tensor | None = None,
                tgt_is_causal: bool = False, memory_is_causal: bool = False) -> Tensor:  # fmt: skip
        own = not (self.training or self.fused_inference or tgt.device.type != "cpu" or not self.self_attn.batch_first
                   or tgt_mask is not None or memory_mask is not None or tgt_is_causal or memory_is_causal)  # fmt: skip
        if not own:
            return super().forward(tgt, memory, tgt_mask, memory_mask, tgt_key_padding_mask, memory_key_padding_mask,
                                   tgt_is_causal, memory_is_causal)  # fmt: skip
        x = tgt
        if self.norm_first:
            x = x + self_attention(self.self_attn, self.norm1(x), tgt_key_padding_mask)
            x = x + cross_attention(self.multihead_attn, self.norm2(x), memory, memory_key_padding_mask)
            return x + self._ff_block(self.norm3(x))
        x = self.norm1(x + self_attention(self.self_attn, x, tgt_key_padding_mask))
        x = self.norm2(x + cross_attention(self.multihead_attn, x, memory, memory_key_padding_mask))
        return self.norm3(x + self._ff_block(x))
