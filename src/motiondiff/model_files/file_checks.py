"""A model file checked before a command imports Lightning and the text encoder (about 7 s of CPU on a 2-core
machine), so a missing, corrupt, tampered or NaN file is refused at once. A release is checked without torch; a
training checkpoint goes through torch's safe loader only. Loading (`lit.loading.load_model`) checks it all again
and builds the model."""

from __future__ import annotations

from pathlib import Path

from motiondiff.model_files.release_checks import check_release_files
from motiondiff.model_files.resolve import RELEASE_SUFFIXES
from motiondiff.runtime.checked_loading import CKPT_FIX, check_finite_state, torch_load
from motiondiff.runtime.errors import UsageError


def check_model_file(path: str | Path) -> None:
    path = Path(path)
    if path.suffix in RELEASE_SUFFIXES:
        check_release_files(path)
    else:
        checkpoint_state(path)


def checkpoint_state(path: str | Path, what: str = "checkpoint", fix: str = CKPT_FIX) -> dict:
    """A model's training checkpoint read safely: its hyper_parameters and finite state_dict, or one UsageError
    naming `what` and `fix` (what `model_files.loading` builds the model from)."""
    state = torch_load(path, what, fix)
    if not isinstance(state.get("hyper_parameters"), dict) or not isinstance(state.get("state_dict"), dict):
        raise UsageError(f"{what} {path} has no hyper_parameters or state_dict: it is not a model's training "
                         f"checkpoint; {fix}")  # fmt: skip
    check_finite_state(state["state_dict"], f"{what} {path}", fix)
    return state
