"""The wheel carries what an installed motiondiff needs to run from any folder: configs, the released models and
evaluators, the embedded data, and the console scripts."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from motiondiff.model_files.resolve import SHIPPED_MODELS

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_wheel_bundles_configs_models_data_and_commands(tmp_path):
    source = tmp_path / "source"  # a copy: building in place would leave build/ and egg-info in the checkout
    for name in ("src", "conf", "checkpoints", "data", "pyproject.toml", "setup.py", "README.md"):
        copy = shutil.copytree if (REPO / name).is_dir() else shutil.copy
        copy(REPO / name, source / name, **({"ignore": shutil.ignore_patterns("bandai", "*.egg-info", "__pycache__")}
                                           if (REPO / name).is_dir() else {}))  # fmt: skip
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(tmp_path), str(source)], check=True, cwd=tmp_path, capture_output=True)  # fmt: skip
    wheel = next(tmp_path.glob("motiondiff-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    bundled = "motiondiff/_bundled/"
    for needed in (
        "conf/sample.yaml",
        "conf/paths/default.yaml",
        f"checkpoints/models/{SHIPPED_MODELS['text'].name}",
        f"checkpoints/models/{SHIPPED_MODELS['text'].stem}.coverage.safetensors",
        "checkpoints/evaluators/bandai_mini/text_motion.safetensors",
        "data/bandai_mini/meta.json",
    ):
        assert bundled + needed in names, needed
    assert "motiondiff/pipelines/__init__.py" in names and not any(
        n.startswith(bundled + "data/bandai/") for n in names
    )
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    text = zipfile.ZipFile(wheel).read(entry_points).decode()
    for command in (
        "motiondiff-train",
        "motiondiff-sample",
        "motiondiff-edit",
        "motiondiff-evaluate",
        "motiondiff-prepare",
        "motiondiff-demo",
    ):
        assert command in text
