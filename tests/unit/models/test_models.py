"""Denoiser network: shapes, padding invariance, classifier-free ∅ condition, conditions, MDM parameter count."""

from __future__ import annotations

import math

import pytest
import torch
from torch import nn

from motiondiff.models import (
    PRESETS,
    ActionCondition,
    MDMDenoiser,
    NoCondition,
    SinusoidalPositionalEncoding,
    TextCondition,
    TimestepEmbedder,
    build_backbone,
    build_condition,
    count_parameters,
)

TINY = dict(d_model=32, num_layers=2, num_heads=4, ff_size=64, dropout=0.1, activation="gelu")
D = 12  # feature dim of the toy motion


def tiny(condition: str = "text", **kw) -> MDMDenoiser:
    torch.manual_seed(0)
    kw = {"cond_dim": 24, "num_actions": 5} | kw
    return MDMDenoiser.from_config(D, preset=TINY, condition=condition, **kw)


def inputs(batch: int = 3, frames: int = 10, seed: int = 1):
    g = torch.Generator().manual_seed(seed)
    x = torch.randn(batch, frames, D, generator=g)
    t = torch.randint(0, 1000, (batch,), generator=g)
    mask = torch.ones(batch, frames, dtype=torch.bool)
    mask[1, 6:] = False
    mask[2, 3:] = False
    return x, t, mask


@pytest.mark.parametrize("condition", ["text", "action", "none"])
def test_shapes_for_every_condition(condition):
    model = tiny(condition)
    x, t, mask = inputs()
    cond = {"text": torch.randn(3, 24), "action": torch.tensor([0, 4, 2]), "none": None}[condition]
    out = model(x, t, cond, mask)
    assert out.shape == x.shape and torch.isfinite(out).all()
    assert model(x, t, cond).shape == x.shape  # mask optional


@pytest.mark.parametrize("mode", ["eval_no_grad", "train_no_dropout"])
def test_padded_frames_do_not_affect_valid_frames(mode):
    # eval + no_grad takes PyTorch's fused encoder fast path; train mode takes the regular path.
    model = tiny("text", dropout=0.0)
    model.train(mode == "train_no_dropout")
    x, t, mask = inputs()
    cond = torch.randn(3, 24)
    garbage = torch.where(mask.unsqueeze(-1), x, 1e3 * torch.randn_like(x))
    with torch.set_grad_enabled(mode == "train_no_dropout"):
        a, b = model(x, t, cond, mask), model(garbage, t, cond, mask)
        alone = model(x[2:3, :3], t[2:3], cond[2:3])  # the 3-frame clip without any padding
    assert (a - b)[mask].abs().max() <= 1e-5
    assert (a[2, :3] - alone[0]).abs().max() <= 1e-5


def test_drop_cond_makes_output_independent_of_cond():
    model = tiny("text").eval()
    x, t, mask = inputs()
    drop = torch.tensor([True, False, True])
    c1, c2 = torch.randn(3, 24), torch.randn(3, 24)
    c2[0] = float("nan")  # even a NaN in a dropped condition must not leak
    with torch.no_grad():
        y1, y2 = model(x, t, c1, mask, drop), model(x, t, c2, mask, drop)
        y_null = model(x, t, None, mask, torch.ones(3, dtype=torch.bool))
    assert torch.equal(y1[drop], y2[drop]) and torch.equal(y1[drop], y_null[drop])
    assert not torch.allclose(y1[~drop], y2[~drop])
    # The text model's ∅ token is the unconditional model's token: timestep embedding only.
    emb = model.condition(c1, drop)
    assert torch.equal(emb[drop], torch.zeros(2, 32)) and emb[~drop].abs().sum() > 0


def test_condition_embedders():
    text = TextCondition(cond_dim=8, d_model=16)
    assert text(torch.randn(4, 8)).shape == (4, 16)
    with pytest.raises(ValueError, match="cond_dim"):
        text(torch.randn(4, 9))
    with pytest.raises(ValueError, match="needs cond"):
        text(None, batch_size=4)

    action = ActionCondition(num_actions=3, d_model=16)
    emb = action(torch.tensor([0, 1, 2, 1]))
    assert emb.shape == (4, 16) and torch.equal(emb[1], emb[3])
    # dropped rows may carry any label (e.g. a placeholder -1)
    assert torch.equal(action(torch.tensor([-1, 1]), torch.tensor([True, False]))[0], torch.zeros(16))
    with pytest.raises(ValueError, match="out of range"):
        action(torch.tensor([0, 3]))
    with pytest.raises(ValueError, match="integer"):
        action(torch.randn(2))

    none = NoCondition(16)
    assert torch.equal(none(None, batch_size=3), torch.zeros(3, 16))
    assert count_parameters(none) == 0

    assert isinstance(build_condition("none", 16), NoCondition)
    for kind, kw, msg in [("text", {}, "cond_dim"), ("action", {}, "num_actions"), ("audio", {}, "unknown condition")]:
        with pytest.raises(ValueError, match=msg):
            build_condition(kind, 16, **kw)


def test_paper_preset_parameter_count():
    # MDM Table 8: trans_enc 17.88 M for text-to-motion (HumanML3D 263-d features, CLIP 512-d).
    model = MDMDenoiser.from_config(263, preset="paper", condition="text", cond_dim=512)
    n = count_parameters(model)
    print(f"paper preset (text, 263-d, CLIP 512): {n:,} trainable parameters")
    assert n == 17_880_327
    assert math.isclose(n, 17.88e6, rel_tol=0.01)
    # Its make-up: in 263->512, time MLP, 8 encoder layers, text Linear, out 512->263.
    layer = 3 * 512 * 512 + 3 * 512 + 512 * 512 + 512 + 512 * 1024 + 1024 + 1024 * 512 + 512 + 4 * 512
    assert n == (263 * 512 + 512) + 2 * (512 * 512 + 512) + 8 * layer + (512 * 512 + 512) + (512 * 263 + 263)
    # Table 8 note: action-to-motion has 512 parameters per class instead of the text Linear.
    action = MDMDenoiser.from_config(263, preset="paper", condition="action", num_actions=12)
    assert count_parameters(action) == n - (512 * 512 + 512) + 12 * 512


def test_cpu_preset_is_smaller_and_editable():
    model = MDMDenoiser.from_config(263, preset="cpu", condition="text", cond_dim=384)
    print(f"cpu preset (text, 263-d, MiniLM 384): {count_parameters(model):,} trainable parameters")
    assert count_parameters(model) < 17_880_327 / 4
    assert model.d_model == PRESETS["cpu"]["d_model"]
    # overrides win over the preset
    small = MDMDenoiser.from_config(263, preset="cpu", condition="none", num_layers=1)
    assert len(small.backbone.encoder.layers) == 1


def test_uses_batch_first_transformer_encoder():
    model = tiny()
    assert isinstance(model.backbone.encoder, nn.TransformerEncoder)
    layer = model.backbone.encoder.layers[0]
    assert layer.self_attn.batch_first and layer.activation_relu_or_gelu == 2  # gelu, fast-path eligible
    assert len(model.backbone.encoder.layers) == TINY["num_layers"]


def test_registry_and_config_errors():
    with pytest.raises(ValueError, match=r"unknown backbone .lstm.; known: .*trans_enc"):
        build_backbone("lstm", d_model=8)
    with pytest.raises(ValueError, match="unknown preset"):
        MDMDenoiser.from_config(D, preset="huge", condition="none")
    with pytest.raises(ValueError, match="divisible"):
        build_backbone("trans_enc", d_model=30, num_layers=1, num_heads=4, ff_size=8)
    with pytest.raises(ValueError, match="d_model"):
        MDMDenoiser(D, 32, build_backbone("trans_enc", **TINY), TextCondition(8, 16))
    model = tiny("none")
    x, t, _ = inputs()
    with pytest.raises(ValueError, match=r"x must be"):
        model(x[..., :5], t)
    with pytest.raises(ValueError, match="t must be"):
        model(x, t[:2])


def test_gradients_reach_every_parameter():
    model = tiny("text").train()
    x, t, mask = inputs()
    out = model(x, t, torch.randn(3, 24), mask)
    out[mask].pow(2).mean().backward()
    missing = [n for n, p in model.named_parameters() if p.grad is None or not p.grad.abs().sum() > 0]
    assert not missing


def test_embeddings():
    pe = SinusoidalPositionalEncoding(8, max_len=50, dropout=0.0)
    out = pe(torch.zeros(1, 5, 8))
    pos, i = 3, 1  # element 2i = sin(pos / 10000^(2i/d)), 2i+1 = cos(...)
    assert out[0, pos, 2 * i].item() == pytest.approx(math.sin(pos / 10000 ** (2 * i / 8)), abs=1e-6)
    assert out[0, pos, 2 * i + 1].item() == pytest.approx(math.cos(pos / 10000 ** (2 * i / 8)), abs=1e-6)
    with pytest.raises(ValueError, match="max_len"):
        pe(torch.zeros(1, 51, 8))
    assert "pe" not in pe.state_dict()  # constant, not saved in checkpoints

    emb = TimestepEmbedder(16)
    y = emb(torch.tensor([0, 1, 999, 1]))
    assert y.shape == (4, 16) and torch.equal(y[1], y[3]) and not torch.allclose(y[1], y[2])
    with pytest.raises(ValueError, match="even"):
        TimestepEmbedder(15)


def test_presets_match_the_hydra_model_configs():
    from pathlib import Path

    import yaml

    conf = Path(__file__).resolve().parents[3] / "conf" / "model"
    for name, arch in PRESETS.items():
        spec = yaml.safe_load((conf / f"{name}.yaml").read_text())
        assert {k: spec[k] for k in arch} == arch, name
