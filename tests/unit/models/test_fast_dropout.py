"""FastDropout is dropout (keep rate, scale, expectation, gradient), and the encoder layer built on it computes what
nn.TransformerEncoderLayer computes with the same weights (the reference path), in inference and in training."""

from __future__ import annotations

import pytest
import torch
from fixtures.layer_pairs import padding_mask, valid_outputs_and_grads
from torch import nn

from motiondiff.models.backbones.encoder_layer import FastDropoutEncoderLayer
from motiondiff.models.fast_dropout import FastDropout, fast_dropout, keep_mask


def test_keep_mask_keeps_one_minus_p_and_says_the_exact_probability():
    torch.manual_seed(0)
    for p in (0.1, 0.5, 0.9):
        mask, keep = keep_mask((1000, 4003), p)  # an odd size: the last 64-bit word is used in part
        assert mask.dtype == torch.bool and mask.shape == (1000, 4003)
        assert abs(keep - (1 - p)) <= 1 / 512  # rounded to a multiple of 1/256
        assert abs(mask.float().mean().item() - keep) < 2e-3
    for tiny in (0.0, 1e-3):  # rounds to keeping everything
        mask, keep = keep_mask((10, 10), tiny)
        assert mask.all() and keep == 1.0
    with pytest.raises(ValueError, match=r"\[0, 1\)"):
        keep_mask((3,), 1.0)


def test_fast_dropout_is_unbiased_and_its_gradient_is_the_same_mask():
    torch.manual_seed(0)
    x = torch.ones(2000, 1000, requires_grad=True)
    y = fast_dropout(x, 0.1)
    _, keep = keep_mask((1,), 0.1)
    values = torch.unique(y.detach())
    assert len(values) == 2 and values[0] == 0 and abs(values[1].item() - 1 / keep) < 1e-6
    assert abs(y.mean().item() - 1.0) < 3e-3  # E[y] = x
    y.sum().backward()
    torch.testing.assert_close(x.grad, y.detach())  # dy/dx = mask / keep, the same mask
    assert torch.equal(fast_dropout(x, 0.1, training=False), x) and torch.equal(fast_dropout(x, 0.0), x)


@pytest.mark.parametrize("dtype", [torch.float32, torch.bfloat16])
def test_the_multiplied_mask_gives_the_numbers_of_a_selected_one(dtype):
    """The 0/1 mask in the activation's dtype is the bool mask of the same draws, and multiplying by it gives, to the
    bit, what selecting with torch.where gave (forward and gradient)."""
    torch.manual_seed(5)
    boolean, keep = keep_mask((37, 129), 0.1)
    torch.manual_seed(5)
    numeric, same_keep = keep_mask((37, 129), 0.1, dtype=dtype)
    assert numeric.dtype == dtype and keep == same_keep and torch.equal(numeric.bool(), boolean)
    x = torch.randn(37, 129).to(dtype).requires_grad_()
    torch.manual_seed(5)
    y = fast_dropout(x, 0.1)
    g = torch.randn(37, 129).to(dtype)
    y.backward(g)
    assert y.dtype == dtype
    assert torch.equal(y.detach(), torch.where(boolean, x.detach(), 0.0).mul_(1 / keep))
    assert torch.equal(x.grad, torch.where(boolean, g, 0.0).mul_(1 / keep))


def test_fast_dropout_repeats_under_the_same_seed():
    x = torch.randn(64, 64)
    torch.manual_seed(3)
    a = FastDropout(0.3).train()(x)
    torch.manual_seed(3)
    b = FastDropout(0.3).train()(x)
    assert torch.equal(a, b) and not torch.equal(a, FastDropout(0.3).train()(x))
    assert torch.equal(FastDropout(0.3).eval()(x), x)


def _pair(dropout: float, norm_first: bool = False):
    torch.manual_seed(0)
    args = dict(activation="gelu", batch_first=True, norm_first=norm_first)
    ref = nn.TransformerEncoderLayer(32, 4, 64, dropout, **args)
    fast = FastDropoutEncoderLayer(32, 4, 64, dropout, **args)
    fast.load_state_dict(ref.state_dict())  # the same parameters, the same names
    return ref, fast


def _inputs():
    g = torch.Generator().manual_seed(1)
    x = torch.randn(3, 11, 32, generator=g)
    pad = padding_mask()  # padded keys
    return x, pad


@pytest.mark.parametrize("norm_first", [False, True])
@pytest.mark.parametrize("padded", [False, True])
def test_inference_is_pytorchs_layer(padded, norm_first):
    """CPU inference attends through scaled_dot_product_attention instead of PyTorch's fused layer: the same output
    to float rounding, for a layer alone (bool padding mask) and in nn.TransformerEncoder (which passes an additive
    float one), post- and pre-norm."""
    ref, fast = _pair(0.1, norm_first)
    x, pad = _inputs()
    mask = pad if padded else None
    with torch.inference_mode():
        torch.testing.assert_close(fast.eval()(x, src_key_padding_mask=mask), ref.eval()(x, src_key_padding_mask=mask),
                                   atol=1e-6, rtol=0)  # fmt: skip
        a, b = (nn.TransformerEncoder(layer, num_layers=2, enable_nested_tensor=False).eval() for layer in (ref, fast))
        valid = ~pad[..., None] if padded else torch.ones(*x.shape[:2], 1, dtype=torch.bool)
        ya, yb = a(x, src_key_padding_mask=mask), b(x, src_key_padding_mask=mask)
        torch.testing.assert_close(yb[valid.expand_as(yb)], ya[valid.expand_as(ya)], atol=1e-5, rtol=0)


@pytest.mark.parametrize("padded", [False, True])
def test_training_pass_equals_the_reference_without_dropout(padded):
    """With p = 0 the hand-written attention is the only difference: outputs and gradients agree to 1e-5, also
    through nn.TransformerEncoder (which turns a bool padding mask into an additive float one)."""
    ref, fast = _pair(0.0)
    x, pad = _inputs()
    mask = pad if padded else None
    (out_ref, grad_ref), (out_fast, grad_fast) = [
        valid_outputs_and_grads(
            nn.TransformerEncoder(layer, num_layers=2, enable_nested_tensor=False),
            lambda enc: enc(x, src_key_padding_mask=mask),
            mask,
        )
        for layer in (ref, fast)
    ]
    torch.testing.assert_close(out_fast, out_ref, atol=1e-5, rtol=0)
    torch.testing.assert_close(grad_fast, grad_ref, atol=1e-5, rtol=1e-4)


def test_training_drops_the_attention_weights():
    """Only the attention dropout on: the training output changes from call to call and differs from inference."""
    _, fast = _pair(0.0)
    fast.self_attn.dropout = 0.5
    x, _ = _inputs()
    torch.manual_seed(0)
    a, b = fast.train()(x), fast.train()(x)
    with torch.no_grad():
        clean = fast.eval()(x)
    assert not torch.allclose(a, b) and not torch.allclose(a, clean)
    fast.self_attn.dropout = 0.0
    torch.testing.assert_close(fast.train()(x), clean, atol=1e-5, rtol=0)
