"""CPU training step of the trans_dec denoiser: PyTorch's ``nn.TransformerDecoderLayer`` (dropout masks from
``bernoulli_``, self-attention dropout inside its kernel) against ``FastDropoutDecoderLayer`` (``FastDropout``,
attention written out), the same weights.

    python bench/decoder_training.py [--batch 64] [--repeats 7] [--input-token] [--out FILE]

The CPU preset (d 128, 4 layers, the ablation cells' and run H's network) with the trans_dec backbone, one training
step as train.py runs it (x0 loss, backward, clipping, AdamW) on a random batch of ``--batch`` clips padded to 120
frames with valid lengths spread over 40-120 (the full-Bandai recipe's windows). The two models alternate step by
step in one process; medians after a warm-up. Prints a markdown row with the machine.
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from pathlib import Path

import torch

from motiondiff.bench.report import machine
from motiondiff.bench.workloads import COND_DIM, FEATURE_DIM, batch_step, window_batch
from motiondiff.models.backbones.decoder_layer import FastDropoutDecoderLayer
from motiondiff.models.denoiser import MDMDenoiser


def with_pytorch_layers(model: MDMDenoiser) -> MDMDenoiser:
    """A copy of ``model`` whose decoder layers are PyTorch's own class, with the same parameters."""
    ref = copy.deepcopy(model)
    layers = ref.backbone.decoder.layers
    for i, layer in enumerate(layers):
        plain = torch.nn.TransformerDecoderLayer(layer.self_attn.embed_dim, layer.self_attn.num_heads,
                                                 layer.linear1.out_features, layer.dropout1.p, activation="gelu",
                                                 batch_first=True, norm_first=layer.norm_first)  # fmt: skip
        plain.load_state_dict(layer.state_dict())
        layers[i] = plain
    return ref


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--input-token", action="store_true", help="trans_dec + input token (MDM's variant)")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    torch.manual_seed(0)
    ours = MDMDenoiser.from_config(FEATURE_DIM, preset="cpu", backbone="trans_dec", cond_dim=COND_DIM,
                                   input_token=args.input_token)  # fmt: skip
    assert all(isinstance(layer, FastDropoutDecoderLayer) for layer in ours.backbone.decoder.layers)
    steps = {"pytorch": batch_step("cpu", model=with_pytorch_layers(ours)), "fast": batch_step("cpu", model=ours)}
    x0, mask, cond = window_batch(args.batch)
    times: dict[str, list[float]] = {name: [] for name in steps}
    for i in range(args.repeats + 1):  # the first round warms up
        for name, step in steps.items():
            start = time.perf_counter()
            step(x0, mask, cond)
            if i:
                times[name].append(time.perf_counter() - start)
    med = {name: sorted(t)[len(t) // 2] for name, t in times.items()}
    info = machine()
    variant = "trans_dec + input token" if args.input_token else "trans_dec"
    print(
        f"{info['cpu']}, {info['cores']} cores, {torch.get_num_threads()} torch threads, torch {info['torch']}; "
        f"`python bench/decoder_training.py --batch {args.batch}{' --input-token' if args.input_token else ''}`; "
        f"medians of {args.repeats}, alternating\n\n"
        "| workload | PyTorch's decoder layer (s) | FastDropoutDecoderLayer (s) | speed-up |\n|---|---:|---:|---:|\n"
        f"| {variant} (cpu preset) training step, batch {args.batch}, 40-120 frames | {med['pytorch']:.3f} | "
        f"{med['fast']:.3f} | {med['pytorch'] / med['fast']:.2f}x |"
    )
    if args.out:
        args.out.write_text(json.dumps({"machine": info, "variant": variant, "median_s": med, "times_s": times}))


if __name__ == "__main__":
    main()
