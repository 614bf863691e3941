"""bf16_inference gives autocast's numbers (bit for bit where the backbone's kernels do not depend on the weights'
dtype; the decoder's self-attention takes the other attention kernel, same bf16 error), and leaves the float32 weights exactly as they were (after
an error and after nested or overlapping uses too)."""

from __future__ import annotations

import threading

import pytest
import torch

from motiondiff.models.bf16_inference import bf16_inference
from motiondiff.models.denoiser import MDMDenoiser

SMALL = dict(d_model=32, num_layers=2, num_heads=2, ff_size=64, dropout=0.1, activation="gelu")


def _denoiser(backbone: str) -> MDMDenoiser:
    torch.manual_seed(0)
    return MDMDenoiser.from_config(12, preset=SMALL, backbone=backbone, cond_dim=16).eval()


def _inputs():
    g = torch.Generator().manual_seed(1)
    x = torch.randn(2, 24, 12, generator=g)
    return x, torch.tensor([3, 700]), torch.randn(2, 16, generator=g), torch.ones(2, 24, dtype=torch.bool)


def _snapshot(model):
    return {name: (p.dtype, p.detach().clone()) for name, p in model.named_parameters()}


@pytest.mark.parametrize("backbone", ["trans_enc", "trans_dec", "gru", "unet"])
def test_autocasts_numbers_and_weights_restored(backbone):
    model = _denoiser(backbone)
    x, t, cond, mask = _inputs()
    before = _snapshot(model)
    with torch.inference_mode():
        full = model(x, t, cond=cond, mask=mask)
        with torch.autocast("cpu", dtype=torch.bfloat16):
            expected = model(x, t, cond=cond, mask=mask)
        with bf16_inference(model, "cpu"):
            assert any(p.dtype == torch.bfloat16 for p in model.parameters())
            got = model(x, t, cond=cond, mask=mask)
    if backbone == "trans_dec":
        autocast_error = (expected.float() - full).abs().max()
        assert (got.float() - full).abs().max() <= 1.5 * autocast_error and autocast_error < 0.05
    else:
        assert torch.equal(got, expected)
    after = _snapshot(model)
    assert all(after[k][0] == torch.float32 and torch.equal(after[k][1], before[k][1]) for k in before)


def test_restored_after_an_error_and_only_when_the_outermost_use_ends():
    model = _denoiser("trans_enc")
    before = _snapshot(model)
    with pytest.raises(RuntimeError, match="boom"), bf16_inference(model, "cpu"):
        with bf16_inference(model, "cpu"):
            pass
        assert model.output_proj.weight.dtype == torch.bfloat16  # the inner exit did not restore
        raise RuntimeError("boom")
    after = _snapshot(model)
    assert all(after[k][0] == torch.float32 and torch.equal(after[k][1], before[k][1]) for k in before)


def test_disabled_is_full_precision():
    model = _denoiser("trans_enc")
    x, t, cond, mask = _inputs()
    with torch.autocast("cpu", dtype=torch.bfloat16), bf16_inference(model, "cpu", enabled=False):
        out = model(x, t, cond=cond, mask=mask)
    assert out.dtype == torch.float32 and all(p.dtype == torch.float32 for p in model.parameters())


def test_disabled_inside_an_enabled_block_of_the_same_model_keeps_its_bf16():
    # MotionPipeline samples an edit under its bf16 block around edit functions whose generation defaults to full
    # precision: full precision there would meet the block's bf16 weights without autocast (a dtype error)
    model, other = _denoiser("trans_enc"), _denoiser("gru")
    x, t, cond, mask = _inputs()
    with torch.inference_mode(), bf16_inference(model, "cpu"):
        expected = model(x, t, cond=cond, mask=mask)
        with bf16_inference(model, "cpu", enabled=False):
            assert torch.equal(model(x, t, cond=cond, mask=mask), expected)
        with bf16_inference(other, "cpu", enabled=False):  # another model's full precision stays full precision
            assert other(x, t, cond=cond, mask=mask).dtype == torch.float32
    assert all(p.dtype == torch.float32 for p in model.parameters())


def _in_thread(fn):
    errors = []

    def run():
        try:
            fn()
        except Exception as e:  # noqa: BLE001 - handed to the test thread, which fails with it
            errors.append(e)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, errors


def test_a_bf16_block_started_during_another_threads_full_precision_block_leaves_its_weights_float32():
    # the demo serves requests in worker threads: a cast in one would hand another's float32 matmuls bf16 weights
    model = _denoiser("trans_enc")
    x, t, cond, mask = _inputs()
    with torch.inference_mode():
        full = model(x, t, cond=cond, mask=mask)
        with torch.autocast("cpu", dtype=torch.bfloat16):
            expected_bf16 = model(x, t, cond=cond, mask=mask)
    inside, bf16_done, got = threading.Event(), threading.Event(), {}

    def full_precision():
        with torch.inference_mode(), bf16_inference(model, "cpu", enabled=False):
            inside.set()
            assert bf16_done.wait(30)
            got["full"] = model(x, t, cond=cond, mask=mask)

    thread, errors = _in_thread(full_precision)
    assert inside.wait(30)
    with torch.inference_mode(), bf16_inference(model, "cpu"):
        assert all(p.dtype == torch.float32 for p in model.parameters())
        got["bf16"] = model(x, t, cond=cond, mask=mask)
    bf16_done.set()
    thread.join(30)
    assert not errors and not thread.is_alive()
    assert torch.equal(got["full"], full) and torch.equal(got["bf16"], expected_bf16)


def test_a_full_precision_block_waits_for_another_threads_cast_to_end():
    model = _denoiser("gru")
    x, t, cond, mask = _inputs()
    with torch.inference_mode():
        full = model(x, t, cond=cond, mask=mask)
    started, got = threading.Event(), {}

    def full_precision():
        started.set()
        with torch.inference_mode(), bf16_inference(model, "cpu", enabled=False):
            got["dtypes"] = {p.dtype for p in model.parameters()}
            got["full"] = model(x, t, cond=cond, mask=mask)

    with torch.inference_mode(), bf16_inference(model, "cpu"):
        thread, errors = _in_thread(full_precision)
        assert started.wait(30)
        thread.join(0.5)
        assert thread.is_alive() and "full" not in got  # waiting: the weights are bf16 here
    thread.join(30)
    assert not errors and not thread.is_alive()
    assert got["dtypes"] == {torch.float32} and torch.equal(got["full"], full)
