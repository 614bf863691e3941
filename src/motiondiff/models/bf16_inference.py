"""bf16 sampling without re-casting weights at every step.

Under bf16 autocast every matmul casts its float32 weight to bf16 on each call; in a sampling loop that is the same
cast at every step (about 10% of a paper-size DPM-Solver++-7 motion on 2 cores; autocast's own weight cache does not
serve inference mode). `bf16_inference` casts the parameters of the layers autocast runs in bf16 (Linear, attention,
Conv1d) once, runs the block under autocast, and puts the float32 tensors back. The weights are rounded as autocast
rounds them, so the numbers are autocast's, bit for bit for the encoder, GRU and U-net backbones. The decoder's
self-attention picks its kernel by the weights' dtype and takes the unfused one: same bf16 error against float32,
and 4x faster than autocast's path (docs/results/bf16_sampling.md).
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass, field

import torch
from torch import nn

_CAST_LAYERS = (nn.Linear, nn.MultiheadAttention, nn.Conv1d)
_changed = threading.Condition()  # guards _states; notified whenever a model's weights go back to float32


@dataclass
class _Uses:
    """One model's blocks in progress: its float32 tensors while its weights are cast, the threads whose enabled
    blocks share that cast (thread id -> depth), and the full-precision blocks that need float32 weights."""

    saved: list | None = None
    bf16_depth: dict[int, int] = field(default_factory=dict)
    full_precision: int = 0


_states: dict[int, _Uses] = {}  # id(model) -> its uses


def _cast(model: nn.Module) -> list[tuple[nn.Parameter, torch.Tensor]]:
    saved = []
    for layer in model.modules():
        if isinstance(layer, _CAST_LAYERS):
            for p in layer.parameters(recurse=False):
                if p.dtype == torch.float32:
                    saved.append((p, p.data))
                    p.data = p.data.to(torch.bfloat16)
    return saved


def _distributed_training() -> bool:
    """Whether a process group is up (DDP training): changing a parameter's dtype through ``.data`` resets its
    gradient accumulator, and with it the hooks DDP registered there, so its next backward would not reduce."""
    return torch.distributed.is_available() and torch.distributed.is_initialized()


@contextlib.contextmanager
def bf16_inference(model: nn.Module, device_type: str, enabled: bool = True):
    """bf16 autocast on ``device_type`` with ``model``'s matmul weights held in bf16 for the duration (nested and
    concurrent uses of one model share one cast; the last to leave restores float32). Disabled: full precision,
    except inside an enabled block of the same model in the same thread, whose weights are bf16 until it ends: there
    the block's bf16 goes on (a pipeline samples its edits in bf16 around library calls that default to full
    precision). Across threads (a demo serving requests) a full-precision block waits for another thread's cast to
    end, and an enabled block that starts while a full-precision one runs leaves the weights float32 (autocast casts
    them per call), so neither meets weights of the other's dtype."""
    if _distributed_training():  # a dtype change of .data drops the gradient hooks DDP put on the weights
        with torch.autocast(device_type, dtype=torch.bfloat16, enabled=enabled):
            yield
        return
    key, me = id(model), threading.get_ident()
    with _changed:
        uses = _states.setdefault(key, _Uses())
        if not enabled and uses.bf16_depth.get(me):
            mode = "inside bf16"
        elif not enabled:  # another thread's cast ends (and may drop its record) before float32 is needed here
            _changed.wait_for(lambda: key not in _states or _states[key].saved is None)
            uses = _states.setdefault(key, _Uses())
            uses.full_precision += 1
            mode = "full"
        elif uses.saved is None and uses.full_precision:
            mode = "autocast only"
        else:
            if uses.saved is None:
                uses.saved = _cast(model)
            uses.bf16_depth[me] = uses.bf16_depth.get(me, 0) + 1
            mode = "cast"
    try:
        if mode == "inside bf16":
            yield
        else:
            with torch.autocast(device_type, dtype=torch.bfloat16, enabled=mode != "full"):
                yield
    finally:
        with _changed:
            if mode == "full":
                uses.full_precision -= 1
            elif mode == "cast":
                uses.bf16_depth[me] -= 1
                if not uses.bf16_depth[me]:
                    del uses.bf16_depth[me]
                if not uses.bf16_depth:
                    for p, data in uses.saved:
                        p.data = data
                    uses.saved = None
            if uses.saved is None and not uses.full_precision and _states.get(key) is uses:
                del _states[key]
            _changed.notify_all()
