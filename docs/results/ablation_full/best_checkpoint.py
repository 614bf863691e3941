"""The best-val-FID checkpoint of a cell, by its logged curve: `python best_checkpoint.py <condition>_<cell>`.

Lightning's best-FID callback can leave a stale best-fid-step*.ckpt behind when a sitting resumes from a last.ckpt
written just before the best one of the same step (the resumed callback then compares against the older best), so
neither the first nor the newest such file is safely the best. The lowest logged val FID is; its checkpoint is never
removed (the callback only removes a file it has beaten). A logged step is one short of its checkpoint's.
"""

from __future__ import annotations

import sys

from report import RUNS, column, curve


def best_checkpoint(cell: str) -> str:
    fid = column(curve(cell), "val/fid")
    if not fid:
        raise SystemExit(f"{cell}: no val/fid logged yet")
    step = min(fid, key=lambda x: x[1])[0] + 1
    path = RUNS / cell / "checkpoints" / f"best-fid-step{step:07d}.ckpt"
    if not path.is_file():
        raise SystemExit(f"{cell}: the lowest val FID is at step {step:,}, but {path} is missing")
    return str(path.relative_to(RUNS.parents[1]))


if __name__ == "__main__":
    print(best_checkpoint(sys.argv[1]))
