"""The decoder layer's CPU passes (training with FastDropout, inference in scaled_dot_product_attention) against
PyTorch's own layer."""

from __future__ import annotations

import pytest
import torch
from fixtures.layer_pairs import padding_mask, valid_outputs_and_grads
from torch import nn

from motiondiff.models.backbones.decoder_layer import FastDropoutDecoderLayer
from motiondiff.models.fast_dropout import FastDropout


def _pair(norm_first: bool, dropout: float = 0.1):
    torch.manual_seed(0)
    args = dict(activation="gelu", batch_first=True, norm_first=norm_first)
    ref = nn.TransformerDecoderLayer(32, 4, 64, dropout, **args)
    ours = FastDropoutDecoderLayer(32, 4, 64, dropout, **args)
    ours.load_state_dict(ref.state_dict())  # the same parameters, the same names
    return ref.eval(), ours.eval()


@pytest.mark.parametrize("memory_len", [1, 3])  # MDM's decoder reads one memory entry (the time + condition token)
@pytest.mark.parametrize("norm_first", [False, True])
@pytest.mark.parametrize("padded", [False, True])
def test_inference_is_pytorchs_layer(padded, norm_first, memory_len):
    ref, ours = _pair(norm_first)
    g = torch.Generator().manual_seed(1)
    x, memory = torch.randn(3, 11, 32, generator=g), torch.randn(3, memory_len, 32, generator=g)
    pad = padding_mask()
    mask = pad if padded else None
    valid = (~pad if padded else torch.ones_like(pad))[..., None].expand_as(x)
    with torch.inference_mode():
        stacks = tuple(nn.TransformerDecoder(layer, num_layers=2) for layer in (ref, ours))
        for a, b in ((ref, ours), stacks):  # one layer, and a stack as trans_dec builds it
            ya, yb = a(x, memory, tgt_key_padding_mask=mask), b(x, memory, tgt_key_padding_mask=mask)
            torch.testing.assert_close(yb[valid], ya[valid], atol=1e-5, rtol=0)


@pytest.mark.parametrize("memory_len", [1, 3])
@pytest.mark.parametrize("norm_first", [False, True])
@pytest.mark.parametrize("padded", [False, True])
def test_training_pass_equals_pytorchs_layer_without_dropout(padded, norm_first, memory_len):
    """With p = 0 the written-out attentions are the only difference: outputs and gradients agree through a stack."""
    ref, ours = _pair(norm_first, dropout=0.0)
    g = torch.Generator().manual_seed(2)
    x, memory = torch.randn(3, 11, 32, generator=g), torch.randn(3, memory_len, 32, generator=g)
    pad = padding_mask() if padded else None
    (out_ref, grad_ref), (out_ours, grad_ours) = [
        valid_outputs_and_grads(
            nn.TransformerDecoder(layer, num_layers=2), lambda stack: stack(x, memory, tgt_key_padding_mask=pad), pad
        )
        for layer in (ref, ours)
    ]
    torch.testing.assert_close(out_ours, out_ref, atol=1e-5, rtol=0)
    # 3e-5: with two torch threads the gradients' reductions run in another order (1.2e-5 apart at one element of
    # 25,664 in the post-norm, one-key case; one thread: within 1e-5)
    torch.testing.assert_close(grad_ours, grad_ref, atol=3e-5, rtol=1e-4)


@pytest.mark.parametrize("which", ["self_attn", "multihead_attn"])
def test_training_drops_each_attentions_weights(which):
    """Only one attention's dropout on: the training output changes from call to call and differs from inference;
    with it off again, training equals inference."""
    _, ours = _pair(False, dropout=0.0)
    getattr(ours, which).dropout = 0.5
    x, memory = torch.randn(2, 7, 32), torch.randn(2, 3, 32)
    torch.manual_seed(0)
    a, b = ours.train()(x, memory), ours.train()(x, memory)
    with torch.no_grad():
        clean = ours.eval()(x, memory)
    assert not torch.allclose(a, b) and not torch.allclose(a, clean)
    getattr(ours, which).dropout = 0.0
    torch.testing.assert_close(ours.train()(x, memory), clean, atol=1e-5, rtol=0)


def test_dropout_modules_are_the_fast_ones_with_the_same_probability():
    _, ours = _pair(False)
    assert all(isinstance(m, FastDropout) and m.p == 0.1 for m in (ours.dropout, ours.dropout1, ours.dropout2,
                                                                     ours.dropout3))  # fmt: skip
