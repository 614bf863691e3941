"""In-painting-aware models: the denoiser reads the clean known part, training shows random known parts, and a
fine-tune starts from a plain model's weights with the new projection at zero (so it starts from its predictions)."""

from __future__ import annotations

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module
from safetensors.torch import save_file

from motiondiff.cli.common import UsageError
from motiondiff.cli.train import init_weights
from motiondiff.edit.inpaint import inpaint
from motiondiff.lit.known_masks import random_known_keep
from motiondiff.models.denoiser import MDMDenoiser

KNOWN = ["+known_conditioning={prob: 0.5, frame_share: 0.5}"]


@pytest.fixture(scope="module")
def datamodule():
    return tiny_datamodule()


def _module(dm, overrides):
    return tiny_module(dm, ["condition=none", *overrides])


def test_zero_initialised_projection_leaves_predictions_unchanged():
    torch.manual_seed(0)
    plain = MDMDenoiser.from_config(12, preset=dict(d_model=16, num_layers=1, num_heads=2, ff_size=32, dropout=0.0,
                                                    activation="gelu"), condition="none")  # fmt: skip
    aware = MDMDenoiser.from_config(12, preset=dict(d_model=16, num_layers=1, num_heads=2, ff_size=32, dropout=0.0,
                                                    activation="gelu"), condition="none", known_input=True)  # fmt: skip
    missing = aware.load_state_dict(plain.state_dict(), strict=False).missing_keys
    assert sorted(missing) == ["known_proj.bias", "known_proj.weight"]
    x, t = torch.randn(2, 7, 12), torch.tensor([3, 9])
    known, keep = torch.randn(2, 7, 12), torch.rand(2, 7, 12) > 0.5
    ref = plain(x, t)
    assert torch.allclose(aware(x, t, known=known, keep=keep), ref, atol=1e-6)
    assert torch.allclose(aware(x, t), ref, atol=1e-6)
    with pytest.raises(ValueError, match="without known_input"):
        plain(x, t, known=known, keep=keep)


def test_known_part_reaches_the_prediction_and_none_means_nothing_known():
    torch.manual_seed(0)
    net = MDMDenoiser.from_config(12, preset=dict(d_model=16, num_layers=1, num_heads=2, ff_size=32, dropout=0.0,
                                                  activation="gelu"), condition="none", known_input=True)  # fmt: skip
    torch.nn.init.normal_(net.known_proj.weight)
    torch.nn.init.normal_(net.known_proj.bias)
    x, t = torch.randn(2, 7, 12), torch.tensor([3, 9])
    known, keep = torch.randn(2, 7, 12), torch.zeros(2, 7, 12, dtype=torch.bool)
    keep[:, :2] = True
    assert not torch.allclose(net(x, t, known=known, keep=keep), net(x, t))
    # known values outside keep are not seen; "nothing known" equals an all-False keep
    assert torch.allclose(net(x, t, known=torch.where(keep, known, 0), keep=keep), net(x, t, known=known, keep=keep))
    assert torch.allclose(net(x, t, known=known, keep=torch.zeros_like(keep)), net(x, t), atol=1e-6)
    with pytest.raises(ValueError, match="known and keep"):
        net(x, t, known=known[:, :3], keep=keep[:, :3])


def test_random_known_parts_are_frames_or_body_parts_inside_each_clip():
    valid = torch.zeros(400, 50, dtype=torch.bool)
    lengths = torch.randint(10, 51, (400,), generator=torch.Generator().manual_seed(0))
    for i, n in enumerate(lengths):
        valid[i, :n] = True
    parts = torch.zeros(3, 9, dtype=torch.bool)
    parts[0, :3], parts[1, 3:6], parts[2, 6:] = True, True, True
    keep = random_known_keep(valid, parts, prob=0.5, frame_share=0.5, generator=torch.Generator().manual_seed(1))
    assert keep.shape == (400, 50, 9) and not keep[~valid].any()
    shown = keep.flatten(1).any(1)
    assert 0.4 < shown.float().mean() < 0.6
    frames = part = 0
    for i in torch.nonzero(shown).flatten():
        n, k = int(lengths[i]), keep[i, : int(lengths[i])]
        rows = k.any(1)
        if k[rows].all():  # a frame mask: whole rows, a prefix and/or a suffix, never the whole clip
            frames += 1
            assert not rows.all()
            r = rows.int()
            changes = int((r[1:] != r[:-1]).sum())  # prefix: 1..0, suffix: 0..1, both: 1..0..1
            assert (changes == 1 and (r[0] == 1 or r[-1] == 1)) or (changes == 2 and r[0] == 1 and r[-1] == 1)
        else:  # a body part: the same dims on every valid frame
            part += 1
            assert any(torch.equal(k, p.expand(n, 9)) for p in parts)
    assert frames > 50 and part > 50
    none = random_known_keep(valid, parts, prob=0.0, frame_share=0.5)
    assert not none.any()


def test_fine_tune_starts_from_a_plain_model_and_training_sees_known_parts(datamodule, tmp_path):
    plain = _module(datamodule, [])
    weights = tmp_path / "plain.safetensors"
    save_file({k: v.contiguous() for k, v in plain.state_dict().items()}, str(weights))
    aware = _module(datamodule, KNOWN)
    assert aware.denoiser.known_input and aware.part_masks.shape[1] == aware.hparams.feature_dim
    init_weights(aware, str(weights))
    for name, value in plain.state_dict().items():
        assert torch.equal(aware.state_dict()[name], value)
    assert not aware.denoiser.known_proj.weight.any()

    batch = next(iter(datamodule.train_dataloader()))
    seen = {}
    original = aware.denoiser.forward

    def spy(*args, **kwargs):
        seen.update(kwargs)
        return original(*args, **kwargs)

    aware.denoiser.forward = spy
    loss, _ = aware._loss(batch, 0.1)
    loss.backward()
    assert seen["keep"].shape == batch["motion"].shape and torch.equal(seen["known"], batch["motion"])
    assert aware.denoiser.known_proj.weight.grad.abs().sum() > 0  # the new projection learns

    other = _module(datamodule, ["model.d_model=48"] + KNOWN)
    with pytest.raises(UsageError, match="does not fit this model"):
        init_weights(other, str(weights))
    with pytest.raises(UsageError, match="not found"):
        init_weights(aware, str(tmp_path / "missing.ckpt"))


def test_inpaint_hands_the_known_part_to_an_aware_model(datamodule):
    aware = _module(datamodule, KNOWN).eval()
    torch.nn.init.normal_(aware.denoiser.known_proj.weight, std=0.5)
    b, n, d = 2, 30, aware.hparams.feature_dim
    known = torch.randn(b, n, d, generator=torch.Generator().manual_seed(1))
    keep = torch.zeros(b, n, 1, dtype=torch.bool)
    keep[:, :8] = keep[:, -8:] = True
    calls = []
    original = aware.denoiser.forward

    def spy(*args, **kwargs):
        calls.append(kwargs)
        return original(*args, **kwargs)

    aware.denoiser.forward = spy
    out = inpaint(aware, None, known, keep, torch.full((b,), n), steps=5, generator=torch.Generator().manual_seed(0))
    assert len(calls) == 5 and torch.equal(out[:, :8], known[:, :8])
    for kwargs in calls:  # every step reads the clean known part and where it is
        assert torch.equal(kwargs["known"], known) and torch.equal(kwargs["keep"], keep.expand(b, n, d))
