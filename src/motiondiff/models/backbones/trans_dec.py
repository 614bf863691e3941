"""MDM's Transformer-decoder backbone (paper Sec. 4.1, Table 1): the token enters through cross-attention.

MDM's ablation swaps the encoder for a decoder whose self-attention reads the frames and whose cross-attention reads
z_tk (time + condition) as the only memory entry; "+ input token" also prepends z_tk to the frames, so it is seen both
ways. Same sizes as the encoder (8 layers, 4 heads, d 512, ff 1024); the extra cross-attention per layer is why the
paper lists 26.29 M parameters instead of 17.88 M. The paper found both variants worse than the encoder (FID 0.767 /
0.567 vs 0.544), which is why trans_enc stays the default.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor, nn

from motiondiff.models.backbones.decoder_layer import FastDropoutDecoderLayer
from motiondiff.models.backbones.transformer import TransformerBackbone


class TransDecBackbone(TransformerBackbone):
    """frames (+ positions) -> nn.TransformerDecoder(tgt = frames, memory = [token]) -> frames.

    `input_token=True` is MDM's "decoder + input token": the token is also prepended to the frames (its output is
    dropped). Post-norm layers and no final norm, like trans_enc and PyTorch's defaults.
    """

    def build(self, layer_args: dict[str, Any], num_layers: int, input_token: bool = False) -> None:
        self.input_token = bool(input_token)
        self.decoder = nn.TransformerDecoder(FastDropoutDecoderLayer(**layer_args), num_layers=num_layers)

    def forward(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor:
        seq = torch.cat([token.unsqueeze(1), h], dim=1) if self.input_token else h
        seq = self.pos_encoding(seq)  # as MDM: positions on the target sequence only, not on the memory
        pad = None
        if mask is not None and not bool(mask.all()):
            keep = mask.to(torch.bool)
            if self.input_token:
                keep = torch.cat([keep.new_ones(keep.shape[0], 1), keep], dim=1)
            # A clip with no valid frame at all would mask every key of its rows (NaN); let it attend to everything.
            pad = ~keep & keep.any(dim=1, keepdim=True)
        out = self.decoder(seq, token.unsqueeze(1), tgt_key_padding_mask=pad)
        return out[:, 1:] if self.input_token else out
