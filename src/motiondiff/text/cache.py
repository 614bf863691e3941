"""Caption -> feature cache, so the frozen text encoder runs once per caption and never inside a training step.

On disk (optional): `<cache_dir>/<encoder.name>.safetensors` holds the (K, dim) float32 tensor "embeddings" and
`<encoder.name>.json` the K captions in row order plus the encoder name and dim (the tensor file's metadata holds them
too, so features and captions are replaced together). Each file is written to a temporary file and renamed, so a
crash never leaves a half-written file, and runs sharing the cache only ever lose entries to each other, never mix them.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from pathlib import Path

import torch
from safetensors import SafetensorError, safe_open
from safetensors.torch import save_file
from torch import Tensor

from motiondiff.runtime.atomic import atomic_write
from motiondiff.text.encoders import TextEncoder, check_texts

_TENSOR_KEY = "embeddings"


class TextEmbeddingCache:
    """embed(texts) -> (B, dim): looks captions up, encodes only unseen ones (in one batched call), remembers them."""

    def __init__(self, encoder: TextEncoder, cache_dir: str | Path | None = None, batch_size: int = 64):
        self.encoder = encoder
        self.batch_size = batch_size
        self.cache_dir = None if cache_dir is None else Path(cache_dir)
        self._index: dict[str, int] = {}
        self._matrix = torch.zeros(0, encoder.dim)
        if self.cache_dir is not None and self.tensor_path.exists():
            self._load()

    # -- paths -------------------------------------------------------------------------------------------------
    @property
    def tensor_path(self) -> Path:
        return self._dir() / f"{self.encoder.name}.safetensors"

    @property
    def texts_path(self) -> Path:
        return self._dir() / f"{self.encoder.name}.json"

    def _dir(self) -> Path:
        if self.cache_dir is None:
            raise ValueError("this cache has no cache_dir, so nothing is stored on disk")
        return self.cache_dir

    # -- lookups -----------------------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self._index)

    def __contains__(self, text: object) -> bool:
        return text in self._index

    def precompute(self, texts: Iterable[str]) -> int:
        """Encode every caption not yet cached (one batched call) and persist. Returns how many were new."""
        texts = check_texts(list(texts))
        new = list(dict.fromkeys(t for t in texts if t not in self._index))  # unique, first-seen order
        if not new:
            return 0
        feats = self.encoder.encode(new, batch_size=self.batch_size)
        if feats.shape != (len(new), self.encoder.dim):
            raise ValueError(
                f"{self.encoder.name} returned {tuple(feats.shape)} for {len(new)} texts, expected (…, {self.encoder.dim})"
            )
        start = len(self._index)
        self._matrix = torch.cat([self._matrix, feats.detach().float().cpu()])
        self._index.update((t, start + i) for i, t in enumerate(new))
        if self.cache_dir is not None:
            self.save()
        return len(new)

    def embed(self, texts: Sequence[str]) -> Tensor:
        """(B, dim) float32 CPU features for texts (duplicates allowed), encoding only the unseen ones."""
        texts = check_texts(texts)
        self.precompute(texts)
        return self._matrix[torch.tensor([self._index[t] for t in texts], dtype=torch.long)]

    def table(self, texts: Iterable[str]) -> tuple[Tensor, dict[str, int]]:
        """(K, dim) tensor for the K unique texts + {text: row}: a training step then needs only dict lookups."""
        unique = list(dict.fromkeys(check_texts(list(texts))))
        self.precompute(unique)
        rows = torch.tensor([self._index[t] for t in unique], dtype=torch.long)
        return self._matrix[rows].clone(), {t: i for i, t in enumerate(unique)}

    # -- disk --------------------------------------------------------------------------------------------------
    def save(self) -> None:
        directory = self._dir()
        directory.mkdir(parents=True, exist_ok=True)
        texts = sorted(self._index, key=self._index.__getitem__)
        meta = {"encoder": self.encoder.name, "dim": self.encoder.dim, "texts": texts}
        # The captions ride in the tensor file's own metadata, so one atomic rename replaces features and captions
        # together: runs sharing a cache (two trainings at once) never read one run's features with another's
        # captions. The JSON beside it is the same list, for people.
        atomic_write(
            self.tensor_path,
            lambda tmp: save_file(
                {_TENSOR_KEY: self._matrix.contiguous()},
                tmp,
                metadata={"encoder": self.encoder.name, "dim": str(self.encoder.dim), "texts": json.dumps(texts)},
            ),
        )
        atomic_write(self.texts_path, lambda tmp: Path(tmp).write_text(json.dumps(meta, ensure_ascii=False)))

    def _load(self) -> None:
        fix = f"delete {self.tensor_path} and {self.texts_path} to rebuild the cache"
        try:
            with safe_open(str(self.tensor_path), framework="pt") as f:
                matrix, meta = f.get_tensor(_TENSOR_KEY), dict(f.metadata() or {})
            if "texts" in meta:  # one file: features and captions from the same write
                meta = {
                    "encoder": meta.get("encoder"),
                    "dim": int(meta.get("dim", -1)),
                    "texts": json.loads(meta["texts"]),
                }
            else:  # written before the captions moved into the tensor file
                meta = json.loads(self.texts_path.read_text())
            texts = meta["texts"]
        except (
            OSError,
            KeyError,
            ValueError,
            TypeError,
            SafetensorError,
        ) as err:  # missing json, bad json, bad safetensors
            raise ValueError(f"text cache is unreadable ({type(err).__name__}: {err}); {fix}") from err
        if meta.get("encoder") != self.encoder.name or meta.get("dim") != self.encoder.dim:
            raise ValueError(
                f"text cache {self.texts_path} was written by {meta.get('encoder')!r} (dim {meta.get('dim')}), "
                f"not {self.encoder.name!r} (dim {self.encoder.dim}); {fix}, or use another cache_dir"
            )
        if matrix.ndim != 2 or matrix.shape != (len(texts), self.encoder.dim) or len(set(texts)) != len(texts):
            raise ValueError(f"text cache holds {tuple(matrix.shape)} features for {len(texts)} texts; {fix}")
        self._matrix = matrix.float()
        self._index = {t: i for i, t in enumerate(texts)}
