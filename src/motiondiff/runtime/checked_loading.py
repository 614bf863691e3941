"""Model files a user names (training checkpoints, release weights) read with every failure as one UsageError.

torch's own messages for a refused or broken pickle advise passing ``weights_only=False`` (which would run the file's
code) and a truncated file fails deep inside torch: a user needs the file's name, what is wrong and the fix. Weights
must also be finite: one NaN makes every generated motion NaN.
"""

from __future__ import annotations

import contextlib
import pickle
import re
import zipfile
from pathlib import Path

from safetensors import SafetensorError

from motiondiff.runtime.errors import UsageError

CKPT_FIX = "give a checkpoint a motiondiff run wrote (its last.ckpt or best-fid-*.ckpt) or a release (.safetensors)"
# What reading or rebuilding from a broken or foreign file raises (a UsageError, a ValueError, passes unchanged).
LOAD_ERRORS = (pickle.UnpicklingError, EOFError, RuntimeError, KeyError, TypeError, ValueError, AttributeError,
               IndexError, zipfile.BadZipFile, AssertionError, SafetensorError)  # fmt: skip


def reason(err: BaseException) -> str:
    """A short, safe account of why a file did not load (never torch's weights_only=False advice)."""
    text = str(err)
    refused = re.search(r"Unsupported global: GLOBAL ([\w.]+)", text)
    if isinstance(err, pickle.UnpicklingError) and refused:
        return f"it would import {refused.group(1)} while loading (code, not saved weights); nothing was run"
    if "weights_only" in text or "Weights only load failed" in text:
        return "it is not a plain-data checkpoint (refused by the safe loader; nothing was run)"
    if isinstance(err, EOFError | zipfile.BadZipFile) or "PytorchStreamReader" in text or "central directory" in text:
        return "the file is truncated or corrupt"
    first = text.splitlines()[0][:160] if text else type(err).__name__
    return f"{type(err).__name__}: {first}"


@contextlib.contextmanager
def reading(path: str | Path, what: str = "checkpoint", fix: str = CKPT_FIX):
    """Turn a failure to read or rebuild from ``path`` into one UsageError naming it, what went wrong and ``fix``."""
    try:
        yield
    except UsageError:
        raise
    except OSError as err:  # torch reading a cut zip: EINVAL with no file name; a missing or locked file has one
        if err.filename is not None:
            raise
        raise UsageError(f"{what} {path} cannot be loaded: the file is truncated or corrupt ({err}); {fix}") from None
    except LOAD_ERRORS as err:
        raise UsageError(f"{what} {path} cannot be loaded: {reason(err)}; {fix}") from None


def torch_load(path: str | Path, what: str = "checkpoint", fix: str = CKPT_FIX) -> dict:
    """``torch.load(path, weights_only=True)`` on the CPU, its failures as one UsageError; a dict or refused."""
    import torch  # here, not at the top: `reading` serves the checks that run before torch is imported

    with reading(path, what, fix):
        state = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(state, dict):
        raise UsageError(f"{what} {path} holds a {type(state).__name__}, not a checkpoint; {fix}")
    return state


def check_finite_state(state: dict, source: str | Path, fix: str = CKPT_FIX) -> None:
    """Refuse weights with a NaN or infinity (one bad value makes every generated motion NaN)."""
    import torch

    bad = [k for k, v in state.items() if torch.is_tensor(v) and v.is_floating_point() and not bool(v.isfinite().all())]
    if bad:
        raise UsageError(f"{source} holds NaN or infinite weights ({len(bad)} tensor(s), first {bad[0]!r}): the "
                         f"weights are corrupt or diverged; {fix}")  # fmt: skip


def check_same_shapes(state: dict, own: dict, source: str | Path, fix: str, model: str = "its model") -> None:
    """Refuse weights whose names, shapes or dtypes differ from ``model``'s own (another architecture)."""
    import torch

    missing = [k for k in own if k not in state]
    unexpected = [k for k in state if k not in own]
    shapes = [f"{k} {tuple(state[k].shape)} vs {tuple(own[k].shape)}" for k in state
              if k in own and (not torch.is_tensor(state[k]) or state[k].shape != own[k].shape)]  # fmt: skip
    dtypes = [f"{k} {state[k].dtype} vs {own[k].dtype}" for k in state
              if k in own and torch.is_tensor(state[k]) and state[k].shape == own[k].shape
              and state[k].dtype != own[k].dtype]  # fmt: skip
    if missing or unexpected or shapes or dtypes:
        found = [f"{len(x)} {name} (first {x[0]})" for name, x in (("missing", missing), ("unexpected", unexpected),
                 ("of another shape", shapes), ("of another dtype", dtypes)) if x]  # fmt: skip
        raise UsageError(f"{source} does not fit {model}: tensors {'; '.join(found)}; {fix}")
