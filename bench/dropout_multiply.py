"""CPU training step of the small denoiser with FastDropout's mask applied by ``torch.where`` (before) and by a
multiply with a 0/1 mask in the activation's dtype (now), the same weights, draws and numbers.

    python bench/dropout_multiply.py [--batch 64] [--repeats 7] [--out FILE]

The CPU preset (d 128, 4 layers: the ablation cells' and the shipped text model's network) with the trans_enc and
trans_dec backbones, one training step as train.py runs it (x0 loss, backward, clipping, AdamW) on a random batch
of ``--batch`` clips padded to 120 frames with valid lengths over 40-120 (the full-Bandai recipe's windows), in bf16
autocast where the CPU has native bf16, else fp32. Before and after alternate step by step in one process (medians
after a warm-up); each row also gives the step's FLOP rate as a share of a 4096x2048x2048 matmul in the same dtype
measured in the same run (issue 39's "share of the matmul peak"). Prints markdown rows with the machine.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
from pathlib import Path
from unittest import mock

import torch

from motiondiff.bench.flops import count_flops, matmul_flops_per_s
from motiondiff.bench.report import machine
from motiondiff.bench.workloads import COND_DIM, FEATURE_DIM, batch_step, window_batch
from motiondiff.models import fast_dropout as fd
from motiondiff.models.denoiser import MDMDenoiser


class _WhereScale(torch.autograd.Function):
    """The mask application before this change: select with a bool mask, then scale."""

    @staticmethod
    def forward(ctx, x, mask, scale):
        ctx.save_for_backward(mask)
        ctx.scale = scale
        return torch.where(mask, x, 0.0).mul_(scale)

    @staticmethod
    def backward(ctx, grad):
        (mask,) = ctx.saved_tensors
        return torch.where(mask, grad, 0.0).mul_(ctx.scale), None, None


def _selecting_dropout(x, p, training=True):
    if not training or p == 0:
        return x
    mask, keep = fd.keep_mask(tuple(x.shape), p, x.device)  # bool, the same draws
    return _WhereScale.apply(x, mask, 1.0 / keep)


def before():
    """Every FastDropout (and the written-out attention's weight dropout) selecting with ``torch.where``."""
    stack = contextlib.ExitStack()
    stack.enter_context(mock.patch.object(fd, "fast_dropout", _selecting_dropout))
    stack.enter_context(mock.patch("motiondiff.models.backbones.cpu_attention.fast_dropout", _selecting_dropout))
    return stack


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    info = machine()
    bf16 = bool(info.get("native_bf16"))
    dtype = torch.bfloat16 if bf16 else torch.float32
    x0, mask, cond = window_batch(args.batch)
    peak = matmul_flops_per_s(4096, 2048, 2048, dtype=dtype, repeats=5)["flops_per_s"]
    rows, record = [], {"machine": info, "dtype": str(dtype), "matmul_peak_flops_per_s": peak, "backbones": {}}
    for backbone in ("trans_enc", "trans_dec"):
        torch.manual_seed(0)
        model = MDMDenoiser.from_config(FEATURE_DIM, preset="cpu", backbone=backbone, cond_dim=COND_DIM)
        step = batch_step("cpu", bf16=bf16, model=model)
        flops = count_flops(lambda step=step: step(x0, mask, cond))
        times: dict[str, list[float]] = {"before": [], "now": []}
        for i in range(args.repeats + 1):  # the first round warms up
            for name in times:
                with before() if name == "before" else contextlib.nullcontext():
                    start = time.perf_counter()
                    step(x0, mask, cond)
                    if i:
                        times[name].append(time.perf_counter() - start)
        med = {name: sorted(t)[len(t) // 2] for name, t in times.items()}
        share = {name: flops / s / peak for name, s in med.items()}
        record["backbones"][backbone] = {"flops": flops, "median_s": med, "times_s": times, "peak_share": share}
        rows.append(f"| {backbone} (cpu preset), batch {args.batch}, 40-120 frames, {'bf16 autocast' if bf16 else 'fp32'} "
                    f"| {med['before']:.3f} ({share['before']:.0%}) | {med['now']:.3f} ({share['now']:.0%}) | "
                    f"{med['before'] / med['now']:.2f}x |")  # fmt: skip
    print(
        f"{info['cpu']}, {info['cores']} cores, {torch.get_num_threads()} torch threads, torch {info['torch']}; "
        f"`python bench/dropout_multiply.py --batch {args.batch}`; medians of {args.repeats}, alternating; "
        f"{str(dtype).removeprefix('torch.')} matmul peak {peak / 1e9:.1f} GFLOP/s\n\n"
        "| training step | torch.where (s, share of peak) | multiply (s, share of peak) | speed-up |\n|---|---:|---:|---:|\n"
        + "\n".join(rows)
    )
    if args.out:
        args.out.write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
