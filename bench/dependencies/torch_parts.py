"""Two small training parts written by hand although an installed library has them: the warm-up + cosine learning
rate of motiondiff.lit.diffusion against transformers' get_cosine_schedule_with_warmup, and FastDropout
(motiondiff.models.fast_dropout) against torch's own dropout.

    /tmp/depvenv/bin/python bench/dependencies/torch_parts.py

Learning rate: both schedulers on one AdamW, 200 warm-up steps of 10 000, the factor at every step (and 1000 steps
past the end, where a resumed or extended run lands). Dropout: forward + backward on CPU, p = 0.1, a (64, 196, 512)
activation (the paper preset's width at batch 64), and the kept fraction. transformers is already a dependency, so
size is not a question. Writes docs/results/dependencies/torch_parts.json.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import import_seconds, speed, write  # noqa: E402

from motiondiff.models.fast_dropout import fast_dropout  # noqa: E402

TOTAL, WARMUP = 10_000, 200


def project_factor(step: int) -> float:
    """The factor motiondiff.lit.diffusion.configure_optimizers gives LambdaLR (copied here: it is a closure)."""
    if step < WARMUP:
        return (step + 1) / WARMUP
    progress = min(1.0, (step - WARMUP) / max(1, TOTAL - WARMUP))
    return 0.5 * (1.0 + math.cos(math.pi * progress))


def learning_rate() -> dict:
    from transformers import get_cosine_schedule_with_warmup

    opt = torch.optim.AdamW([torch.nn.Parameter(torch.zeros(1))], lr=1.0)
    sched = get_cosine_schedule_with_warmup(opt, WARMUP, TOTAL)
    theirs = []
    for _ in range(TOTAL + 1000):
        theirs.append(opt.param_groups[0]["lr"])
        opt.step()
        sched.step()
    ours = [project_factor(s) for s in range(TOTAL + 1000)]
    diff = [abs(a - b) for a, b in zip(ours, theirs, strict=True)]
    return {
        "max_abs_difference_during_warmup": max(diff[:WARMUP]),
        "max_abs_difference_after_warmup_to_end": max(diff[WARMUP:TOTAL]),
        "max_abs_difference_past_the_end": max(diff[TOTAL:]),
        "transformers_first_step_lr_factor": theirs[0],
        "project_first_step_lr_factor": ours[0],
        "transformers_factor_1000_steps_past_end": theirs[-1],
        "transformers_optimization_import_s": import_seconds("transformers.optimization"),
    }


def dropout() -> dict:
    x = torch.randn(64, 196, 512, requires_grad=True)

    def run(fn):
        def go():
            y = fn(x)
            y.sum().backward()
            x.grad = None
            return y

        return go

    ours = run(lambda t: fast_dropout(t, 0.1, True))
    theirs = run(lambda t: torch.nn.functional.dropout(t, 0.1, True))
    with torch.no_grad():
        kept_ours = float((fast_dropout(x.detach(), 0.1, True) != 0).float().mean())
        kept_torch = float((torch.nn.functional.dropout(x.detach(), 0.1, True) != 0).float().mean())
    return {
        "forward_backward": speed(ours, theirs),
        "kept_fraction_project": kept_ours,
        "kept_fraction_torch": kept_torch,
    }


def main() -> int:
    result = {"learning_rate_warmup_cosine": learning_rate(), "dropout_cpu": dropout()}
    write("torch_parts", result)
    print(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
