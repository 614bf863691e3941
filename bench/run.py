"""`make bench`: time training, the forward pass, sampling and text encoding on this machine, in one process.

    python bench/run.py [--quick] [--compile] [--model shipped|<ckpt>] [--official <path>] [--out bench/results/latest]

Writes <out>.json (medians in seconds; keys such as train_step_paper_bs64_s and sample_one_motion_default_s, and
every row with its repeats and peak memory) and <out>.md (the table with the machine description).
``--official <path>``: a local clone of the official MDM code (github.com/GuyTevet/motion-diffusion-model); the same
workloads run on it in the same process and the side-by-side table gets its column (motiondiff.bench.compare).
See motiondiff.bench.suite for what each row measures.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from motiondiff.bench.report import markdown
from motiondiff.bench.suite import run_suite
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.errors import UsageError

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "latest"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="tiny sizes and one repeat (a smoke test, not numbers)")
    parser.add_argument("--compile", action="store_true", help="add torch.compile vs eager rows (~30 s to compile)")
    parser.add_argument("--model", default="shipped", help="model to sample with: shipped, latest or a checkpoint")
    parser.add_argument("--official", metavar="PATH", help="local checkout of the official MDM code to compare with")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output prefix (.json and .md are written)")
    args = parser.parse_args(argv)
    command = "python bench/run.py " + " ".join(argv if argv is not None else sys.argv[1:])
    try:
        result = run_suite(quick=args.quick, model=args.model, command=command.strip(), compile=args.compile,
                           official=args.official)  # fmt: skip
    except UsageError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out.with_suffix(".json"), lambda tmp: Path(tmp).write_text(json.dumps(result, indent=1)))
    atomic_write(args.out.with_suffix(".md"), lambda tmp: Path(tmp).write_text(markdown(result)))
    print(markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
