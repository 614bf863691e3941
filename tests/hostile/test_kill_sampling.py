"""SIGKILL at three random points (while it writes) of sampling several prompts: every run folder is complete, or
marked as a run in progress and removed by the next start."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from kill_runs import HYDRA_START, kill_points, killed, timed

PROMPTS = "a person walks forward\na person jumps\na person waves\n"
SAMPLE = ("checkpoint=shipped", "prompts_file=prompts.txt", "num_samples=2", "length=1", "export=none")


def check_sample_folders(root: Path) -> tuple[int, int]:
    """(complete, incomplete) run folders; a complete one has results.json and every file it lists, an
    incomplete one nothing but what a run writes at its start and its sample files, and is still locked."""
    complete = incomplete = 0
    for run in sorted(p for p in root.glob("*") if p.is_dir()):
        results = run / "results.json"
        if results.is_file():
            rows = json.loads(results.read_text())["samples"]
            assert len(rows) == 6, f"{run.name}: {len(rows)} samples listed"
            for row in rows:
                assert (
                    np.load(row["joints"]).ndim == 3
                    and np.load(row["joints"].replace("_joints", "_features")).ndim == 2
                )
            complete += 1
        else:
            names = {p.name for p in run.iterdir()}
            assert ".motiondiff.lock" in names or names <= HYDRA_START | {"sample.log"}, (
                f"{run.name} has results but is neither complete nor marked as a run in progress: {sorted(names)}"
            )
            incomplete += 1
    return complete, incomplete


def test_sampling_several_prompts_killed_anywhere_leaves_no_mixed_folder(tmp_path):
    (tmp_path / "prompts.txt").write_text(PROMPTS)
    times = timed(tmp_path, "sample", *SAMPLE)
    root = tmp_path / "outputs" / "sample"
    for at in kill_points(times, seed=2):
        killed(tmp_path, "sample", *SAMPLE, after=at)
        check_sample_folders(root)
    timed(tmp_path, "sample", *SAMPLE)
    complete, _ = check_sample_folders(root)
    leftovers = [p for p in root.iterdir() if not (p / "results.json").exists() and any(
        f.name not in HYDRA_START | {"sample.log"} for f in p.iterdir())]  # fmt: skip
    assert leftovers == [], f"the next start did not clear the killed runs' partial samples: {leftovers}"
    assert complete >= 2
