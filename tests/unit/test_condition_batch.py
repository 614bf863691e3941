"""sample.condition_batch: training captions come from the module's text table (no encoder load), new prompts through
the encoder, and both give the same features for the same caption."""

from __future__ import annotations

import torch
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.cli.sample import condition_batch
from motiondiff.cli.train import build_module
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.text.cache import TextEmbeddingCache
from motiondiff.text.encoders import MiniLMEncoder

register_resolvers()
TINY = ["model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64"]


def test_training_captions_need_no_encoder_and_match_it(tmp_path):
    dm = PreparedDataModule(embedded_data_root(), batch_size=8, max_frames=40)
    dm.setup("fit")
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=TINY)
    module = build_module(cfg, dm).eval()
    captions = sorted({t for rec in dm.dataset("val").records for t in rec.texts})[:5]
    encoder = MiniLMEncoder()
    module.set_text_table(*TextEmbeddingCache(encoder, tmp_path).table(captions))
    assert encoder._model is not None  # the table was encoded once

    from_table = condition_batch(module, [captions[2], captions[0], captions[2]])
    assert not hasattr(module, "_encoder")  # looked up, nothing loaded
    prompt = "a person raises both hands and turns around slowly"
    mixed = condition_batch(module, [captions[0], prompt])  # one unseen prompt: the encoder path for the batch
    assert hasattr(module, "_encoder")
    torch.testing.assert_close(mixed[0], from_table[1], atol=1e-5, rtol=0)
    torch.testing.assert_close(from_table[0], from_table[2])
    assert not torch.allclose(mixed[1], mixed[0], atol=1e-2)
