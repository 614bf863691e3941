"""bf16 sampling: autocast alone against `bf16_inference` (weights cast once), per backbone, paper preset.

    python bench/bf16_sampling.py [--steps 7] [--frames 196] [--repeats 5] [--out FILE]

One guided DPM-Solver++ motion (batch 1, random weights and caption features, as `make bench`'s comparison rows) in
float32, under bf16 autocast (every matmul casts its float32 weight at every step), and under `bf16_inference`; the
largest difference of the bf16 results from float32 and from each other. Prints a markdown table with the machine.
"""

from __future__ import annotations

import argparse
import contextlib
import json
from pathlib import Path

import torch

from motiondiff.bench.report import machine
from motiondiff.bench.timing import median_seconds
from motiondiff.bench.workloads import COND_DIM, FEATURE_DIM, GUIDANCE, random_batch
from motiondiff.diffusion import GaussianDiffusion, make_betas
from motiondiff.diffusion.dpm_solver import dpmpp_sample
from motiondiff.diffusion.guidance import guided_model_fn
from motiondiff.models.bf16_inference import bf16_inference
from motiondiff.models.denoiser import MDMDenoiser

BACKBONES = ("trans_enc", "trans_dec", "gru", "unet")


def measure(backbone: str, steps: int, frames: int, repeats: int) -> dict:
    torch.manual_seed(0)
    model = MDMDenoiser.from_config(FEATURE_DIM, preset="paper", backbone=backbone, cond_dim=COND_DIM).eval()
    diffusion = GaussianDiffusion(make_betas("cosine", 1000), prediction="x0")
    data = random_batch(1, frames)
    fn = guided_model_fn(model, data["cond"], GUIDANCE, mask=data["mask"])
    contexts = {
        "fp32": contextlib.nullcontext,
        "autocast": lambda: torch.autocast("cpu", dtype=torch.bfloat16),
        "bf16_inference": lambda: bf16_inference(model, "cpu"),
    }
    row, outputs = {"backbone": backbone}, {}
    for name, context in contexts.items():

        def run(context=context):
            with context():
                return dpmpp_sample(diffusion, fn, (1, frames, FEATURE_DIM), steps=steps,
                                    generator=torch.Generator().manual_seed(0))  # fmt: skip

        row[f"{name}_s"] = median_seconds(run, repeats=repeats)["median_s"]
        outputs[name] = run().float()
    row["autocast_error"] = float((outputs["autocast"] - outputs["fp32"]).abs().max())
    row["bf16_inference_error"] = float((outputs["bf16_inference"] - outputs["fp32"]).abs().max())
    row["bitwise_equal"] = bool(torch.equal(outputs["autocast"], outputs["bf16_inference"]))
    return row


def markdown(rows: list[dict], info: dict, args) -> str:
    lines = [f"{info['cpu']}, {info['cores']} cores, torch {info['torch']} (native bf16: {info['native_bf16']}); "
             f"`python bench/bf16_sampling.py --steps {args.steps} --frames {args.frames}`; medians of "
             f"{args.repeats}.", "",
             "| backbone | fp32 | bf16 autocast | bf16_inference | autocast ÷ bf16_inference | max error vs fp32 "
             "(autocast / bf16_inference) | bit-identical |", "|---|---:|---:|---:|---:|---:|---|"]  # fmt: skip
    for r in rows:
        lines.append(f"| {r['backbone']} | {r['fp32_s']:.3f} s | {r['autocast_s']:.3f} s | {r['bf16_inference_s']:.3f}"
                     f" s | {r['autocast_s'] / r['bf16_inference_s']:.2f}x | {r['autocast_error']:.3f} / "
                     f"{r['bf16_inference_error']:.3f} | {'yes' if r['bitwise_equal'] else 'no'} |")  # fmt: skip
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=7)
    parser.add_argument("--frames", type=int, default=196)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--backbones", nargs="*", default=list(BACKBONES))
    parser.add_argument("--out", type=Path, default=None, help="also write the numbers as JSON here")
    args = parser.parse_args(argv)
    rows = []
    for backbone in args.backbones:
        rows.append(measure(backbone, args.steps, args.frames, args.repeats))
        print(f"{backbone}: done", flush=True)
    info = machine()
    print(markdown(rows, info, args))
    if args.out:
        args.out.write_text(json.dumps({"machine": info, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
