"""Real frames trained per second with random batches and with length-bucketed ones, at the paper preset.

    python bench/bucketing_speed.py [--steps 6] [--batch-size 64] [train.py overrides, default dataset=bandai]

Builds the train loader as train.py does (with dataset.datamodule.bucketing off, then on), then times the same
training step as `make bench` (random caption features, bf16 autocast where the CPU runs it natively) on the first
batches after a warm-up, and prints real frames per second for each and their ratio. Needs the dataset prepared
(`make data-full` for the Bandai set).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time

import torch
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from motiondiff.bench import workloads
from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.runtime.hardware import cpu_has_fast_bf16, cpu_model


def real_frames_per_second(overrides: list[str], bucketing: bool, steps: int, batch_size: int, bf16: bool) -> dict:
    with initialize_config_dir(str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=[*overrides, f"batch_size={batch_size}",
                                          f"dataset.datamodule.bucketing={str(bucketing).lower()}"])  # fmt: skip
    dm = instantiate(cfg.dataset.datamodule, batch_size=batch_size)
    dm.setup("fit")
    batches = list(itertools.islice(iter(dm.train_dataloader()), steps + 1))
    on_batch = workloads.batch_step("paper", bf16)

    def step(batch: dict) -> None:
        on_batch(batch["motion"], batch["mask"], torch.randn(batch["motion"].shape[0], workloads.COND_DIM))

    step(batches[0])  # warm-up
    start = time.perf_counter()
    for batch in batches[1:]:
        step(batch)
    seconds = time.perf_counter() - start
    real = sum(int(b["mask"].sum()) for b in batches[1:])
    computed = sum(b["mask"].numel() for b in batches[1:])
    return {"seconds": seconds, "real": real, "computed": computed, "real_per_s": real / seconds}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=6, help="timed training steps per batching (after a warm-up)")
    parser.add_argument("--batch-size", type=int, default=64)
    args, overrides = parser.parse_known_args(argv)
    register_resolvers()
    bf16 = cpu_has_fast_bf16()
    print(f"{cpu_model()}, {torch.get_num_threads()} threads, {'bf16 autocast' if bf16 else 'fp32'}, paper preset")
    rates = {}
    for bucketing in (False, True):
        r = real_frames_per_second(overrides or ["dataset=bandai"], bucketing, args.steps, args.batch_size, bf16)
        rates[bucketing] = r["real_per_s"]
        print(f"{'bucketed' if bucketing else 'random'}: {args.steps} steps in {r['seconds']:.1f} s, real frames "
              f"{r['real']} of {r['computed']} computed ({r['real'] / r['computed']:.3f}), "
              f"{r['real_per_s']:.0f} real frames/s")  # fmt: skip
    print(f"bucketed / random real frames per second: {rates[True] / rates[False]:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
