"""The fixture every case table of tests/hostile shares (the helpers are in hostile_cli.py)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from hostile_cli import run_collected


@pytest.fixture(scope="module")
def results(request, tmp_path_factory) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    """The requesting module's ``case`` parameters, each run once (see `run_collected`)."""
    return run_collected(request, tmp_path_factory)
