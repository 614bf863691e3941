"""A model file checked before a command imports Lightning and the text encoder (about 7 s of CPU on a 2-core
machine), so a missing, corrupt, tampered or NaN file is refused at once. A release is checked without torch; a
training checkpoint goes through torch's safe loader only. Loading (`lit.loading.load_model`) checks it all again
and builds the model."""

from __future__ import annotations

from pathlib import Path

from motiondiff.checked_loading import check_finite_state, torch_load
from motiondiff.paths import RELEASE_SUFFIXES
from motiondiff.release_checks import check_release_files


def check_model_file(path: str | Path) -> None:
    path = Path(path)
    if path.suffix in RELEASE_SUFFIXES:
        check_release_files(path)
        return
    state = torch_load(path)
    weights = state.get("state_dict")
    if isinstance(weights, dict):
        check_finite_state(weights, f"checkpoint {path}")
