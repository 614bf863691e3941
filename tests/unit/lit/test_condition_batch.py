"""sample.condition_batch: training captions come from the module's text table (no encoder load), new prompts through
the encoder, and both give the same features for the same caption."""

from __future__ import annotations

import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.lit.conditions import condition_batch
from motiondiff.text.cache import TextEmbeddingCache
from motiondiff.text.encoders import MiniLMEncoder


def test_training_captions_need_no_encoder_and_match_it(tmp_path):
    dm = tiny_datamodule()
    module = tiny_module(dm, overrides=()).eval()  # a text model
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
