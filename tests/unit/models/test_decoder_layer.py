"""The decoder layer's CPU inference (attention in scaled_dot_product_attention) against PyTorch's own layer."""

from __future__ import annotations

import pytest
import torch
from torch import nn

from motiondiff.models.backbones.decoder_layer import CpuInferenceDecoderLayer


def _pair(norm_first: bool):
    torch.manual_seed(0)
    args = dict(activation="gelu", batch_first=True, norm_first=norm_first)
    ref = nn.TransformerDecoderLayer(32, 4, 64, 0.1, **args)
    ours = CpuInferenceDecoderLayer(32, 4, 64, 0.1, **args)
    ours.load_state_dict(ref.state_dict())  # the same parameters, the same names
    return ref.eval(), ours.eval()


@pytest.mark.parametrize("memory_len", [1, 3])  # MDM's decoder reads one memory entry (the time + condition token)
@pytest.mark.parametrize("norm_first", [False, True])
@pytest.mark.parametrize("padded", [False, True])
def test_inference_is_pytorchs_layer(padded, norm_first, memory_len):
    ref, ours = _pair(norm_first)
    g = torch.Generator().manual_seed(1)
    x, memory = torch.randn(3, 11, 32, generator=g), torch.randn(3, memory_len, 32, generator=g)
    pad = torch.zeros(3, 11, dtype=torch.bool)
    pad[1, 8:] = pad[2, 5:] = True
    mask = pad if padded else None
    valid = (~pad if padded else torch.ones_like(pad))[..., None].expand_as(x)
    with torch.inference_mode():
        stacks = tuple(nn.TransformerDecoder(layer, num_layers=2) for layer in (ref, ours))
        for a, b in ((ref, ours), stacks):  # one layer, and a stack as trans_dec builds it
            ya, yb = a(x, memory, tgt_key_padding_mask=mask), b(x, memory, tgt_key_padding_mask=mask)
            torch.testing.assert_close(yb[valid], ya[valid], atol=1e-5, rtol=0)


def test_training_is_pytorchs_layer_unchanged():
    ref, ours = _pair(False)
    x, memory = torch.randn(2, 7, 32), torch.randn(2, 1, 32)
    torch.manual_seed(5)
    a = ref.train()(x, memory)
    torch.manual_seed(5)
    b = ours.train()(x, memory)
    assert torch.equal(a, b)
