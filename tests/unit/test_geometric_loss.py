"""MDM's geometric losses against their formulas (MDM eq. 2-4), on real clips, for every representation."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.representations import REPRESENTATIONS
from motiondiff.losses import GeometricLoss

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


def test_terms_match_the_formulas(batch):
    rep, x0, mask, mean, std = batch
    x_hat = x0 + 0.05 * torch.randn(x0.shape, generator=torch.Generator().manual_seed(0), dtype=x0.dtype)
    terms = GeometricLoss(rep).terms(x_hat, x0, mask, mean, std)
    p, p_hat = rep.decode(x0 * std + mean), rep.decode(x_hat * std + mean)
    contacts = rep.foot_contacts(x0 * std + mean)
    for i in range(x0.shape[0]):
        n = int(mask[i].sum())
        want_pos = ((p[i, :n] - p_hat[i, :n]) ** 2).sum(-1).mean()  # mean over frames and joints of ‖Δp‖²
        dv = (x0[i, 1:n] - x0[i, : n - 1]) - (x_hat[i, 1:n] - x_hat[i, : n - 1])
        want_vel = (dv**2).mean()
        feet = p_hat[i, :n, list(rep.contact_joints)]
        want_foot = (((feet[1:] - feet[:-1]) ** 2).sum(-1) * contacts[i, : n - 1]).mean()
        torch.testing.assert_close(terms["pos"][i], want_pos)
        torch.testing.assert_close(terms["vel"][i], want_vel)
        torch.testing.assert_close(terms["foot"][i], want_foot)
    assert float(terms["pos"].min()) > 0


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
    from motiondiff.skeleton import SMPL22

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
