"""The demo's request folders: a refused or failed request leaves none, and only the newest KEEP_REQUESTS stay."""

from __future__ import annotations

import os

import pytest

from motiondiff.demo.request_folders import KEEP_REQUESTS, prune, request_folder
from motiondiff.runtime.errors import UsageError


def test_a_refused_request_leaves_no_folder_and_a_done_one_stays(tmp_path):
    with pytest.raises(UsageError):
        with request_folder(tmp_path, "run") as folder:
            (folder / "half.bvh").write_text("HIERARCHY")
            raise UsageError("the text is empty")
    assert list(tmp_path.iterdir()) == []
    with request_folder(tmp_path, "edit") as folder:
        (folder / "a.bvh").write_text("HIERARCHY")
    assert [p.name for p in tmp_path.iterdir()] == [folder.name] and folder.name.startswith("edit-")


def test_only_the_newest_requests_stay_and_nothing_else_of_the_folder_is_touched(tmp_path):
    made = []
    for k in range(KEEP_REQUESTS + 5):
        with request_folder(tmp_path, "run") as folder:
            os.utime(folder, (1_000_000 + k, 1_000_000 + k))  # distinct ages, oldest first
        made.append(folder.name)
    (tmp_path / "run-notes.txt").write_text("a file, not a request")
    (tmp_path / "mine").mkdir()
    prune(tmp_path)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted([*made[-KEEP_REQUESTS:], "run-notes.txt", "mine"])
