"""Padding of training batches with and without length bucketing, from a dataset's real clip lengths (no model runs).

    python bench/padding.py [--batch-size 64] [--chunk 64] [--epochs 3] [--out FILE] [train.py overrides ...]
    python bench/padding.py dataset=humanml3d dataset.root=/data/HumanML3D
    python bench/padding.py dataset=bandai_mini_compositional --batch-size 32

Loads the train split the way train.py does (same config, same max_frames cropping), then prints padded frames per
batch and real / computed frames for plain random batches and for bucketed ones (motiondiff.bench.padding). With
random training windows (window_min_frames) the lengths of epoch 0 are used.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from motiondiff.bench.padding import compare_batching, markdown
from motiondiff.cli.common import REPO_DIR, register_resolvers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batch-size", type=int, default=None, help="default: the config's batch_size")
    parser.add_argument("--chunk", type=int, default=64, help="batches sorted together (bucket_chunk)")
    parser.add_argument("--epochs", type=int, default=3, help="epochs of batches counted")
    parser.add_argument("--out", type=Path, default=None, help="also write the numbers as JSON here")
    parser.add_argument("overrides", nargs="*", help="train.py overrides, e.g. dataset=humanml3d dataset.root=DIR")
    args = parser.parse_args(argv)
    register_resolvers()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=args.overrides)
    dm = instantiate(cfg.dataset.datamodule)
    batch_size = args.batch_size or dm.batch_size
    lengths = dm.dataset("train").item_lengths(0)
    result = compare_batching(lengths, batch_size, chunk_batches=args.chunk, epochs=args.epochs)
    result["dataset"] = cfg.dataset.name
    print(f"dataset {cfg.dataset.name}: " + markdown(result))
    if args.out:
        args.out.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
