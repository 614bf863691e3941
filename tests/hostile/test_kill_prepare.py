"""SIGKILL at three random points (while it writes) of `prepare --force` over an existing dataset: the old dataset or
the new one."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
from kill_runs import BANDAI, PREPARE, kill_points, killed, timed


def dataset_fingerprint(out: Path) -> str:
    """One hash of everything a prepared dataset holds (the npz members by value: zip headers carry times)."""
    h = hashlib.sha256()
    for name in ("meta.json", "report.json", "Mean.npy", "Std.npy", "README.md", "LICENSE"):
        h.update((out / name).read_bytes())
    for split in ("train", "val", "test"):
        with np.load(out / f"{split}.npz") as z:
            for key in sorted(z.files):
                h.update(key.encode() + np.ascontiguousarray(z[key]).tobytes())
    return h.hexdigest()


@pytest.mark.skipif(not BANDAI.is_file(), reason=f"needs the Bandai Namco data at {BANDAI}")
def test_prepare_force_killed_anywhere_leaves_the_old_dataset_or_the_new_one(tmp_path):
    out = tmp_path / "data" / "ds"
    times = timed(tmp_path, "prepare", *PREPARE, "--seed", "0", "--out", str(out))
    old = dataset_fingerprint(out)
    seen = []
    for at in kill_points(times, seed=1):
        killed(tmp_path, "prepare", *PREPARE, "--seed", "1", "--force", "--out", str(out), after=at)
        seen.append(dataset_fingerprint(out))  # raises if a file is missing or unreadable
    timed(tmp_path, "prepare", *PREPARE, "--seed", "1", "--force", "--out", str(out))
    new = dataset_fingerprint(out)
    assert old != new, "the two seeds must give different datasets for the test to mean anything"
    assert set(seen) <= {old, new}, "a killed prepare left a dataset that is neither the old one nor the new one"
    assert sorted(p.name for p in out.parent.iterdir()) == ["ds"], "the next start did not clear the killed builds"
