"""The best-val-FID checkpoint of a cell: `python best_checkpoint.py <condition>_<cell>`.

The lowest val FID saved in the cell's best-fid-step*.ckpt files (`motiondiff.runtime.best_checkpoints.best_of`, as
`checkpoint=best` chooses): a run folder can hold a stale best file from a sitting resumed before the callback
rebuilt its list on resume (commit c898a47), so neither the first nor the newest name is safely the best.
"""

from __future__ import annotations

import sys

from report import RUNS

from motiondiff.runtime.best_checkpoints import best_of


def best_checkpoint(cell: str) -> str:
    path = best_of(sorted((RUNS / cell / "checkpoints").glob("best-fid-*.ckpt")), "val/fid")
    if path is None:
        raise SystemExit(f"{cell}: no best-fid checkpoint with a saved val/fid in {RUNS / cell / 'checkpoints'}")
    return str(path.relative_to(RUNS.parents[1]))


if __name__ == "__main__":
    print(best_checkpoint(sys.argv[1]))
