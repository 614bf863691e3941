"""CPU inference of the Transformer layers: PyTorch's own (fused encoder layer, MultiheadAttention's native path)
against this project's layers written out around ``scaled_dot_product_attention`` (``models.backbones.cpu_attention``).

    python bench/cpu_attention.py [--motions 64] [--steps 10] [--repeats 3] [--out FILE]

Encoder: the shipped text model (trans_enc) samples one evaluation-like batch (``--motions`` captions at lengths
spread over 124-196 frames, so the batch is padded, and the same batch at one length), DDIM with guidance 2.
Decoder: a 4-layer trans_dec stack of the same size (random weights) on a guided batch (2 x ``--motions``) of the
spread lengths. Both ways in one process (median of ``--repeats``), with the largest difference of the outputs.
Prints a markdown table with the machine.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from motiondiff.bench.report import machine
from motiondiff.bench.timing import median_seconds
from motiondiff.lit.generation import generate_features
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.models.backbones.decoder_layer import FastDropoutDecoderLayer
from motiondiff.models.backbones.encoder_layer import FastDropoutEncoderLayer

CAPTIONS = ("a person walks forward", "a person waves the right hand", "a person bows", "a person runs")


def both_ways(layer_class, run, repeats: int) -> tuple[dict, dict]:
    """Median seconds of ``run`` with ``layer_class``'s CPU inference in PyTorch's layer ("fused", first) and in
    scaled_dot_product_attention ("sdpa"), in this process; and one output of each."""
    row, outputs = {}, {}
    try:
        for name in ("fused", "sdpa"):
            layer_class.fused_inference = name == "fused"
            row[f"{name}_s"] = median_seconds(run, repeats=repeats, warmup=1)["median_s"]
            outputs[name] = run()
    finally:
        layer_class.fused_inference = False
    row["speedup"] = row["fused_s"] / row["sdpa_s"]
    return row, outputs


def measure(module, lengths: torch.Tensor, steps: int, repeats: int) -> dict:
    captions = [CAPTIONS[i % len(CAPTIONS)] for i in range(len(lengths))]

    def run():
        gen = torch.Generator().manual_seed(0)
        return generate_features(module, captions, lengths, len(lengths), gen, sampler="ddim", steps=steps,
                                 guidance=2.0)  # fmt: skip

    row, out = both_ways(FastDropoutEncoderLayer, run, repeats)
    row["max_difference"] = float(max(np.abs(a - b).max() for a, b in zip(out["fused"], out["sdpa"], strict=True)))
    return row


def measure_decoder(lengths: torch.Tensor, repeats: int) -> dict:
    """A trans_dec stack of the shipped model's size (d 128, 4 heads, ff 256, 4 layers) on a padded guided batch."""
    torch.manual_seed(0)
    layer = FastDropoutDecoderLayer(128, 4, 256, 0.1, activation="gelu", batch_first=True)
    stack = torch.nn.TransformerDecoder(layer, num_layers=4).eval()
    frames = int(lengths.max())
    x, memory = torch.randn(2 * len(lengths), frames, 128), torch.randn(2 * len(lengths), 1, 128)
    pad = torch.arange(frames)[None] >= lengths.repeat(2)[:, None]

    def run():
        with torch.inference_mode():
            return stack(x, memory, tgt_key_padding_mask=pad)

    row, out = both_ways(FastDropoutDecoderLayer, run, repeats)
    row["max_difference"] = float((out["fused"] - out["sdpa"])[~pad].abs().max())
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--motions", type=int, default=64)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    module = load_model(find_model("shipped")).eval()
    spread = torch.linspace(196, 124, args.motions).round().long()
    rows = {"padded (124-196 frames)": measure(module, spread, args.steps, args.repeats),
            "one length (196 frames)": measure(module, torch.full((args.motions,), 196), args.steps, args.repeats),
            "trans_dec stack, one forward, padded": measure_decoder(spread, args.repeats)}  # fmt: skip
    info = machine()
    lines = [f"{info['cpu']}, {info['cores']} cores, {torch.get_num_threads()} torch threads, torch {info['torch']}; "
             f"`python bench/cpu_attention.py --motions {args.motions} --steps {args.steps}`; medians of "
             f"{args.repeats}; sampling: DDIM-{args.steps} with guidance 2 on the shipped text model", "",
             "| workload | PyTorch's layer (s) | scaled_dot_product_attention (s) | speed-up | max difference |",
             "|---|---:|---:|---:|---:|"]  # fmt: skip
    for name, r in rows.items():
        lines.append(f"| {name} | {r['fused_s']:.2f} | {r['sdpa_s']:.2f} | {r['speedup']:.2f}x | "
                     f"{r['max_difference']:.1e} |")  # fmt: skip
    print("\n".join(lines))
    if args.out:
        args.out.write_text(json.dumps({"machine": info, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
