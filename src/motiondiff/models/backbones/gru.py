"""MDM's GRU backbone (paper Sec. 4.1, Table 1; appendix C): z_tk is concatenated to every input frame.

MDM's recurrent baseline feeds each frame together with the time + condition token z_tk to a unidirectional
PyTorch GRU with hidden size d = 512; it was best with 2 layers (not the transformers' 8), 4.47 M parameters in all,
and the weakest backbone of the ablation (FID 4.569). Here the token is concatenated to the projected frame
embedding, so the first GRU layer reads 2d features (MDM concatenates it to the raw features before its input
Linear; the function class is the same, the parameter count is not - see tests/unit/models/test_backbones.py).

Padding: the frames are packed (pack_padded_sequence), so the recurrence stops at each clip's last valid frame and
padded frames never reach a valid one; padded outputs are zeros. Valid frames must be a prefix of each row.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn
from torch.nn.utils.rnn import pack_padded_sequence, pad_packed_sequence

from motiondiff.models.embeddings import SinusoidalPositionalEncoding


class GRUBackbone(nn.Module):
    """cat(frames + positions, token) per frame -> nn.GRU(2d -> d, num_layers) -> frames.

    num_heads, ff_size and activation are accepted so every backbone takes the model preset, and ignored.
    conf/backbone/gru.yaml sets num_layers: 2 (MDM's best), which wins over the preset's 8.
    """

    def __init__(
        self,
        d_model: int,
        num_layers: int,
        num_heads: int | None = None,
        ff_size: int | None = None,
        dropout: float = 0.1,
        activation: str | None = None,
        max_len: int = 5000,
    ):
        super().__init__()
        del num_heads, ff_size, activation  # transformer-only settings
        self.d_model = d_model
        # MDM adds sinusoidal positions (and dropout) to the GRU input too; a GRU knows the order anyway.
        self.pos_encoding = SinusoidalPositionalEncoding(d_model, max_len=max_len, dropout=dropout)
        self.gru = nn.GRU(2 * d_model, d_model, num_layers=num_layers, batch_first=True)

    def forward(self, h: Tensor, token: Tensor, mask: Tensor | None = None) -> Tensor:
        frames = h.shape[1]
        seq = torch.cat([self.pos_encoding(h), token.unsqueeze(1).expand(-1, frames, -1)], dim=-1)
        if mask is None or bool(mask.all()):
            return self.gru(seq)[0]
        mask = mask.to(torch.bool)
        lengths = mask.sum(dim=1)
        if not torch.equal(mask, torch.arange(frames, device=mask.device)[None] < lengths[:, None]):
            raise ValueError("GRUBackbone needs the valid frames of every row to come first (a prefix mask)")
        # A clip without valid frames still gets one step (pack_padded_sequence refuses length 0); zeroed below.
        packed = pack_padded_sequence(seq, lengths.clamp(min=1).cpu(), batch_first=True, enforce_sorted=False)
        out = pad_packed_sequence(self.gru(packed)[0], batch_first=True, total_length=frames)[0]
        return out * mask.unsqueeze(-1).to(out.dtype)
