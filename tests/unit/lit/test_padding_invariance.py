"""Padding never reaches the training signal: real clips padded to their batch's longest clip (what length-bucketed
batches give) and the same clips padded to 196 frames give the same masked loss, the same gradients and the same
outputs on the real frames, for a fixed time step, noise and condition drop. So how a batch is padded changes only
what a step costs."""

from __future__ import annotations

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.data.datasets import collate_motion

WIDE = 196  # HumanML3D's longest clip


@pytest.fixture(scope="module")
def dm():
    return tiny_datamodule(max_frames=80)


def _clips(dm) -> dict:
    """Five real training clips of different lengths (23..79 frames), padded to the longest of them."""
    ds = dm.dataset("train")
    lengths = ds.item_lengths(0).tolist()
    distinct = sorted(set(lengths))
    picks = [lengths.index(distinct[round(q * (len(distinct) - 1))]) for q in (0.0, 0.25, 0.5, 0.75, 1.0)]
    batch = collate_motion([ds[(0, i)] for i in picks])
    assert len(set(batch["length"].tolist())) == 5 and int(batch["length"].min()) < 40
    return batch


def _padded(batch: dict, frames: int) -> dict:
    extra = frames - batch["motion"].shape[1]
    wide = dict(batch)
    wide["motion"] = torch.nn.functional.pad(batch["motion"], (0, 0, 0, extra))
    wide["mask"] = torch.nn.functional.pad(batch["mask"], (0, extra), value=False)
    return wide


def _step(module, batch: dict, noise: torch.Tensor, monkeypatch) -> tuple[torch.Tensor, dict, torch.Tensor]:
    """`_loss` as training_step runs it, its gradients and the denoiser's output, with ``noise`` for every run.

    `_loss` draws the noise with randn_like over the padded shape, so the real frames would get other numbers in a
    wider batch; serving every draw from one fixed tensor gives them the same ones. t and the condition drop are
    drawn per sample and come back with the seed."""
    monkeypatch.setattr(torch, "randn_like", lambda x, **kw: noise[:, : x.shape[1]].to(x))
    seen = {}
    hook = module.denoiser.register_forward_hook(lambda mod, args, out: seen.update(out=out.detach()))
    module.zero_grad()
    torch.manual_seed(0)
    loss, _ = module._loss(batch, drop_prob=0.5)
    loss.backward()
    hook.remove()
    grads = {k: p.grad.clone() for k, p in module.named_parameters() if p.grad is not None}
    return loss.detach(), grads, seen["out"]


@pytest.mark.parametrize(
    "overrides",
    [
        ["backbone=trans_enc"],  # MDM's default; its CPU training pass writes attention out (FastDropoutEncoderLayer)
        ["backbone=trans_enc", "loss=geometric"],  # + position, velocity and foot terms
        ["backbone=trans_enc", "+known_conditioning={prob: 1.0, frame_share: 0.5}"],  # in-painting-aware training
        ["backbone=trans_dec"],
        ["backbone=gru"],
        ["backbone=unet"],
    ],
    ids=["trans_enc", "trans_enc+geometric", "trans_enc+known", "trans_dec", "gru", "unet"],
)
def test_masked_loss_is_the_same_padded_to_the_batch_or_to_196(dm, overrides, monkeypatch):
    module = tiny_module(dm, ["condition=action", "model.dropout=0.0", *overrides])
    tight = _clips(dm)
    wide = _padded(tight, WIDE)
    assert tight["motion"].shape[1] == int(tight["length"].max()) < WIDE == wide["motion"].shape[1]
    noise = torch.randn(len(tight["length"]), WIDE, dm.feature_dim, generator=torch.Generator().manual_seed(1))
    real = tight["mask"]
    for train in (True, False):  # the training pass and the validation one (PyTorch's fused attention)
        module.train(train)
        loss_a, grads_a, out_a = _step(module, tight, noise, monkeypatch)
        loss_b, grads_b, out_b = _step(module, wide, noise, monkeypatch)
        torch.testing.assert_close(loss_b, loss_a, rtol=1e-5, atol=0)
        torch.testing.assert_close(out_b[:, : real.shape[1]][real], out_a[real], rtol=1e-4, atol=1e-5)
        assert grads_a.keys() == grads_b.keys() and grads_a
        for name, grad in grads_a.items():
            torch.testing.assert_close(grads_b[name], grad, rtol=1e-3, atol=1e-6, msg=name)


def test_the_check_sees_padding_that_leaks(dm, monkeypatch):
    """The same comparison fails when the padded frames are not masked out (all frames marked valid)."""
    module = tiny_module(dm, ["condition=action", "model.dropout=0.0"]).train()
    tight = _clips(dm)
    wide = _padded(tight, WIDE)
    wide["mask"] = torch.ones_like(wide["mask"])
    noise = torch.randn(len(tight["length"]), WIDE, dm.feature_dim, generator=torch.Generator().manual_seed(1))
    loss_a, _, _ = _step(module, tight, noise, monkeypatch)
    loss_b, _, _ = _step(module, wide, noise, monkeypatch)
    assert not torch.allclose(loss_a, loss_b, rtol=1e-3)
