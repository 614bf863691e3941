"""MDM's geometric losses against their equations (MDM eq. 3-5), by hand and on real clips for every representation."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.representations import REPRESENTATIONS
from motiondiff.lit.geometric_losses import GeometricLoss

REPS = [r for r in REPRESENTATIONS if r != "kit251"]


@pytest.fixture(scope="module", params=REPS)
def batch(request):
    dm = PreparedDataModule(embedded_data_root(), batch_size=4, max_frames=40, representation=request.param)
    dm.setup("validate")
    ds = dm.dataset("val")
    b = next(iter(dm.val_dataloader()))
    mean, std = torch.as_tensor(ds.mean), torch.as_tensor(ds.std)
    return dm.representation, b["motion"].double(), b["mask"], mean.double(), std.double()


def test_zero_when_prediction_is_exact(batch):
    rep, x0, mask, mean, std = batch
    total, terms = GeometricLoss(rep)(x0.clone(), x0, mask, mean, std)
    assert set(terms) == {"pos", "vel", "foot"}
    assert float(terms["pos"]) == 0.0 and float(terms["vel"]) == 0.0
    # foot: x̂0 = x0, so the term is the real clip's own sliding while in contact, small but not forced to 0
    assert 0.0 <= float(terms["foot"]) < 1e-3


@pytest.mark.parametrize("reduction", ["equation", "mean"])
def test_terms_match_the_formulas(batch, reduction):
    rep, x0, mask, mean, std = batch
    x_hat = x0 + 0.05 * torch.randn(x0.shape, generator=torch.Generator().manual_seed(0), dtype=x0.dtype)
    terms = GeometricLoss(rep, reduction=reduction).terms(x_hat, x0, mask, mean, std)
    p, p_hat = rep.decode(x0 * std + mean), rep.decode(x_hat * std + mean)
    contacts = rep.foot_contacts(x0 * std + mean)
    for i in range(x0.shape[0]):
        n = int(mask[i].sum())
        dv = (x0[i, 1:n] - x0[i, : n - 1]) - (x_hat[i, 1:n] - x_hat[i, : n - 1])
        feet = p_hat[i, :n, list(rep.contact_joints)]
        slide = ((feet[1:] - feet[:-1]) ** 2).sum(-1) * contacts[i, : n - 1]
        if reduction == "equation":  # eq. 3-5: squared norm of the whole frame, mean over frames
            want_pos = ((p[i, :n] - p_hat[i, :n]) ** 2).sum((-1, -2)).mean()
            want_vel, want_foot = (dv**2).sum(-1).mean(), slide.sum(-1).mean()
        else:  # also averaged over joints / features
            want_pos = ((p[i, :n] - p_hat[i, :n]) ** 2).sum(-1).mean()
            want_vel, want_foot = (dv**2).mean(), slide.mean()
        torch.testing.assert_close(terms["pos"][i], want_pos)
        torch.testing.assert_close(terms["vel"][i], want_vel)
        torch.testing.assert_close(terms["foot"][i], want_foot)
    assert float(terms["pos"].min()) > 0


def test_equations_by_hand():
    """MDM eq. 3-5 on a 3-frame motion of joint positions (FK = identity), numbers worked out on paper:
    x0 stands still at 0; x̂0 moves joint 5 by (0.3, 0, 0.4) at frame 1 only and the left foot by 0.2 m in z at
    frame 2. Contacts (rule: <= 1 cm per frame): every foot joint of x0, at every frame.
      L_pos  = (0 + (0.3² + 0.4² + 0) + 0.2²) / 3 = (0.25 + 0.04) / 3
      L_vel  = (‖(0.3, 0.4) and the left foot still‖² + ‖−(0.3, 0.4) and +0.2‖²) / 2 = (0.25 + 0.29) / 2
      L_foot = (0 + 0.2²) / 2 (only the moved foot slides)"""
    from motiondiff.data.representations import get_representation
    from motiondiff.geometry.skeleton import SMPL22

    rep = get_representation("jp", SMPL22)
    x0 = torch.zeros(1, 3, 66, dtype=torch.float64)
    x_hat = x0.clone()
    x_hat[0, 1, 3 * 5] = 0.3
    x_hat[0, 1, 3 * 5 + 2] = 0.4
    foot = rep.contact_joints[1]
    x_hat[0, 2, 3 * foot + 2] = 0.2
    mask = torch.ones(1, 3, dtype=torch.bool)
    zero, one = torch.zeros(66, dtype=torch.float64), torch.ones(66, dtype=torch.float64)
    terms = GeometricLoss(rep, contact_threshold=0.01, reduction="equation").terms(x_hat, x0, mask, zero, one)
    assert float(terms["pos"]) == pytest.approx((0.25 + 0.04) / 3)
    assert float(terms["vel"]) == pytest.approx((0.25 + 0.29) / 2)
    assert float(terms["foot"]) == pytest.approx(0.04 / 2)
    mean_terms = GeometricLoss(rep, contact_threshold=0.01).terms(x_hat, x0, mask, zero, one)  # the default
    assert float(mean_terms["pos"]) == pytest.approx((0.25 + 0.04) / 3 / 22)  # MDM's code: 1/J of eq. 3
    assert float(mean_terms["vel"]) == pytest.approx((0.25 + 0.29) / 2 / 66)  # 1/D of eq. 5
    with pytest.raises(ValueError, match="reduction"):
        GeometricLoss(rep, reduction="sum")


def test_padding_and_weights(batch):
    rep, x0, mask, mean, std = batch
    x_hat = x0 + 0.05
    loss = GeometricLoss(rep, lambda_pos=2.0, lambda_vel=0.5, lambda_foot=0.0)
    total, terms = loss(x_hat, x0, mask, mean, std)
    assert "foot" not in terms
    torch.testing.assert_close(total, 2.0 * terms["pos"] + 0.5 * terms["vel"])
    # what lies past each clip's length does not change the loss
    junk = torch.where(mask[..., None], x_hat, torch.full_like(x_hat, 50.0))
    torch.testing.assert_close(loss(junk, x0, mask, mean, std)[0], total)


def test_gradients_reach_the_prediction(batch):
    rep, x0, mask, mean, std = batch
    x_hat = (x0 + 0.1).requires_grad_(True)
    total, _ = GeometricLoss(rep)(x_hat, x0, mask, mean, std)
    total.backward()
    g = x_hat.grad
    assert torch.isfinite(g).all() and g[mask].abs().sum() > 0 and not g[~mask].any()


def test_contact_source_of_hml_is_its_channels():
    dm = PreparedDataModule(embedded_data_root(), batch_size=2, representation="hml263")
    dm.setup("validate")
    rec = dm.dataset("val").records[0]
    feats = torch.as_tensor(rec.motion, dtype=torch.float64)
    np.testing.assert_array_equal(dm.representation.foot_contacts(feats).numpy(), rec.motion[:, -4:] > 0.5)


def test_mdm_contact_rule_by_hand():
    """contact_threshold=0.01: a foot joint is in contact at frame i where its true position moves at most 1 cm to
    frame i+1 (MDM's a2m rule), whatever the representation's own rule says."""
    from motiondiff.data.representations import get_representation
    from motiondiff.geometry.skeleton import SMPL22

    rep = get_representation("jp", SMPL22)
    n, j = 4, rep.skeleton.num_joints
    pos = torch.zeros(1, n, j, 3, dtype=torch.float64)
    foot = rep.contact_joints[0]
    pos[0, 1, foot, 0] = 0.009  # 0.9 cm: contact at frame 0
    pos[0, 2, foot, 0] = 0.009 + 0.011  # 1.1 cm: no contact at frame 1
    pos[0, 3, foot, 2] = 0.02  # 2.0 cm (the x step back and z step): no contact at frame 2
    contacts = GeometricLoss(rep, contact_threshold=0.01).contacts(pos, None)
    assert contacts.shape == (1, n - 1, len(rep.contact_joints))
    assert contacts[0, :, 0].tolist() == [1.0, 0.0, 0.0]
    assert bool((contacts[0, :, 1:] == 1).all())  # the other contact joints stand still


def test_alpha_bar_time_weighting_scales_each_samples_terms_and_bounds_an_eps_models_x0_error(batch):
    """time_weighting="alpha_bar": each sample's terms times its ᾱ_t (an ε model's x̂0 error at t = 999 of the cosine
    schedule is ~2e4 × its ε error; weighted, the terms stay of the ε error's size); "none" ignores ᾱ."""
    from motiondiff.diffusion import GaussianDiffusion

    rep, x0, mask, mean, std = batch
    x_hat = x0 + 0.05 * torch.randn(x0.shape, generator=torch.Generator().manual_seed(1), dtype=x0.dtype)
    alpha_bar = torch.tensor([1.0, 0.5, 0.1, 0.0], dtype=x0.dtype)[: x0.shape[0]]
    plain = GeometricLoss(rep).terms(x_hat, x0, mask, mean, std)
    total, weighted = GeometricLoss(rep, time_weighting="alpha_bar")(x_hat, x0, mask, mean, std, alpha_bar=alpha_bar)
    for k, v in plain.items():
        torch.testing.assert_close(weighted[k], (v * alpha_bar).mean())
    torch.testing.assert_close(total, sum(weighted.values()))
    same, _ = GeometricLoss(rep)(x_hat, x0, mask, mean, std, alpha_bar=alpha_bar)
    torch.testing.assert_close(same, sum(v.mean() for v in plain.values()))
    with pytest.raises(ValueError, match="needs each sample's alpha_bar"):
        GeometricLoss(rep, time_weighting="alpha_bar")(x_hat, x0, mask, mean, std)
    with pytest.raises(ValueError, match="loss.time_weighting='snr': choose from none, alpha_bar"):
        GeometricLoss(rep, time_weighting="snr")
    # an ε network off by 0.01 at t = 999: unweighted velocity term ~(0.01 · 2e4)², weighted back to ~0.01²
    diff = GaussianDiffusion.create("cosine", 1000, prediction="eps")
    t = torch.full((x0.shape[0],), 999)
    x_t = diff.q_sample(x0.float(), t, torch.zeros_like(x0.float()))
    eps_hat = 0.01 * torch.randn(x0.shape, generator=torch.Generator().manual_seed(2))
    x0_eps = diff.to_x0(eps_hat, x_t, t).double()
    ab = diff.alphas_cumprod[t].double()
    loose = GeometricLoss(rep, lambda_pos=0, lambda_foot=0).terms(x0_eps, x0, mask, mean, std)["vel"]
    _, bounded = GeometricLoss(rep, lambda_pos=0, lambda_foot=0, time_weighting="alpha_bar")(
        x0_eps, x0, mask, mean, std, alpha_bar=ab
    )
    assert float(loose.min()) > 1e3 and float(bounded["vel"]) < 1e-2
