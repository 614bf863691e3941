"""The motion-VAE LightningModule on real embedded clips: it learns, its helpers have the right shapes, its MPJPE is
in metres, and a checkpoint decodes alone (no dataset)."""

from __future__ import annotations

import lightning as L
import pytest
import torch
from torch.utils.data import DataLoader, Subset

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.datasets import collate_motion
from motiondiff.lit.vae import MotionVAEModule, mpjpe

TINY = {"tokens": 2, "latent_dim": 16, "d_model": 32, "num_layers": 3, "num_heads": 2, "ff_size": 64, "dropout": 0.0}


@pytest.fixture(autouse=True, scope="module")
def _one_thread():
    # A tiny model's matrices are too small to share out: one thread is faster, and it does not stall for minutes
    # when another job keeps the other core busy.
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@pytest.fixture(scope="module")
def dm():
    dm = PreparedDataModule(embedded_data_root(), batch_size=16, max_frames=40, seed=0)
    dm.setup("fit")
    return dm


def make_module(dm, lr: float = 3e-3, **vae) -> MotionVAEModule:
    ds = dm.dataset("train")
    return MotionVAEModule(
        feature_dim=dm.feature_dim, vae={**TINY, **vae}, optim={"lr": lr}, mean=ds.mean.tolist(), std=ds.std.tolist(),
        max_frames=dm.max_frames, fps=dm.fps, num_joints=dm.num_joints, level="motion", dataset="bandai_mini",
        representation=dm.representation_spec(),
    )  # fmt: skip


def trainer(steps: int, **kw) -> L.Trainer:
    return L.Trainer(max_steps=steps, logger=False, enable_checkpointing=False, enable_progress_bar=False,
                     enable_model_summary=False, accelerator="cpu", **kw)  # fmt: skip


@torch.no_grad()
def recon_error(module: MotionVAEModule, batch: dict) -> float:
    """Masked MSE of the posterior-mean reconstruction, in normalised feature units."""
    module.eval()
    x, mask = batch["motion"], batch["mask"]
    err = (module.reconstruct(x, mask) - x).pow(2).mean(-1)
    module.train()
    return float((err * mask).sum() / mask.sum())


def test_training_steps_lower_the_reconstruction_error_on_real_clips(dm):
    torch.manual_seed(0)
    module = make_module(dm)
    loader = DataLoader(Subset(dm.dataset("val"), range(8)), batch_size=8, collate_fn=collate_motion)
    batch = next(iter(loader))
    x, mask = batch["motion"], batch["mask"]
    mean_motion = float((x.pow(2).mean(-1) * mask).sum() / mask.sum())  # error of always decoding the mean motion
    before = recon_error(module, batch)
    t = trainer(60, check_val_every_n_epoch=60)
    t.fit(module, train_dataloaders=loader, val_dataloaders=loader)  # 60 steps on 8 real clips, validated once
    after = recon_error(module, batch)
    print(f"\nreconstruction MSE: mean motion {mean_motion:.3f}, before {before:.3f}, after {after:.3f}")
    assert after < 0.75 * mean_motion and after < 0.75 * before  # it reconstructs these clips, not just the mean
    logged = t.callback_metrics
    for key in ("train/loss", "train/recon", "train/kl", "val/loss", "val/recon", "val/kl", "val/mpjpe"):
        assert torch.isfinite(logged[key]), key
    assert 0.0 < float(logged["val/mpjpe"]) < 3.0  # metres: a 1.7 m body, not centimetres or normalised units


def test_encode_decode_shapes_and_padding(dm):
    module = make_module(dm, tokens=4).eval()
    batch = next(iter(dm.val_dataloader()))
    x, mask = batch["motion"], batch["mask"]
    mean, log_var = module.encode(x, mask)
    assert mean.shape == log_var.shape == (x.shape[0], 4, 16)
    out = module.decode(mean, mask)
    assert out.shape == x.shape
    assert (~mask).any() and out[~mask].abs().max() == 0  # padded frames stay zero
    joints = module.joints(module.denormalise(out))
    assert joints.shape == (*x.shape[:2], dm.num_joints, 3)


def test_mpjpe_is_the_mean_joint_distance_over_valid_frames():
    true = torch.randn(2, 5, 3, 3)
    pred = true + torch.tensor([0.0, 0.3, 0.4])  # every joint 0.5 m off
    pred[:, 3:] += 10.0  # padded frames must not count
    mask = torch.arange(5)[None].expand(2, -1) < 3
    torch.testing.assert_close(mpjpe(pred, true, mask), torch.full((2,), 0.5))
    # the same offset on every joint is a root translation: nothing is left once both are root-aligned
    assert mpjpe(pred, true, mask, root_aligned=True).abs().max() < 1e-6


def test_checkpoint_round_trip_decodes_without_the_dataset(dm, tmp_path):
    torch.manual_seed(1)
    module = make_module(dm, tokens=8)
    t = trainer(2, limit_val_batches=0)
    t.fit(module, datamodule=dm)
    path = tmp_path / "vae.ckpt"
    t.save_checkpoint(path)
    loaded = MotionVAEModule.load_from_checkpoint(path, map_location="cpu", weights_only=True).eval()
    hp = loaded.hparams
    assert hp.vae["tokens"] == loaded.tokens == 8 and hp.max_frames == 40 and hp.fps == dm.fps
    assert len(hp.mean) == len(hp.std) == hp.feature_dim == 263 and hp.representation["name"] == "hml263"
    batch = next(iter(dm.val_dataloader()))
    module.eval()
    with torch.no_grad():
        z = torch.randn(3, 8, 16)
        mask = batch["mask"][:3]
        torch.testing.assert_close(loaded.decode(z, mask), module.decode(z, mask))
        torch.testing.assert_close(loaded.joints(loaded.denormalise(loaded.reconstruct(batch["motion"], batch["mask"]))),
                                   module.joints(module.denormalise(module.reconstruct(batch["motion"], batch["mask"]))))  # fmt: skip


def test_module_needs_a_resolved_token_count(dm):
    with pytest.raises(ValueError, match="tokens"):
        make_module(dm, tokens=None)
