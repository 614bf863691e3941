"""One resolver for a model's name or path on the command line and in the Python API (issue 40): `checkpoint=`
and `from_pretrained` take the same names (shipped, text, action, a release's stem, latest, best, a path)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from motiondiff.model_files.resolve import MODELS_DIR, SHIPPED_MODELS, find_model
from motiondiff.runtime.errors import UsageError

SRC = Path(__file__).resolve().parents[2] / "src" / "motiondiff"


def test_shipped_and_the_api_names_resolve_to_the_same_files(tmp_path):
    assert find_model("shipped") == find_model("text") == SHIPPED_MODELS["text"]
    assert find_model("text", tmp_path) == find_model("shipped", tmp_path) == SHIPPED_MODELS["text"]
    assert find_model("action", tmp_path) == find_model("shipped", tmp_path, "action")
    assert find_model("action", tmp_path) == find_model("action") == SHIPPED_MODELS["action"]
    assert find_model("bandai_text_cpu") == MODELS_DIR / "bandai_text_cpu.safetensors"


def test_runs_and_unknown_names(tmp_path):
    with pytest.raises(UsageError, match="no trained checkpoint under"):
        find_model("latest", tmp_path)
    run = tmp_path / "train" / "r1" / "checkpoints"
    run.mkdir(parents=True)
    (run / "last.ckpt").write_bytes(b"x")
    assert find_model("latest", tmp_path) == run / "last.ckpt"
    with pytest.raises(UsageError, match="no best-FID checkpoint"):
        find_model("best", tmp_path)
    with pytest.raises(UsageError, match=r"no model 'nope': give a released model \(.*bandai_text_cpu"):
        find_model("nope", tmp_path)
    assert find_model("shipped", tmp_path, "guidedmotion") == SHIPPED_MODELS["guidedmotion"]  # a released one


def test_exactly_one_function_resolves_a_model_name():
    """No second resolver hides in the package: `find_model` is the only function that reads SHIPPED_MODELS."""
    readers = []
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and any(
                isinstance(n, ast.Name) and n.id == "SHIPPED_MODELS" for n in ast.walk(node)
            ):
                readers.append(f"{path.relative_to(SRC)}:{node.name}")
    assert set(readers) <= {"model_files/resolve.py:find_model", "model_files/resolve.py:released_names",
                            "demo/models.py:released_choices"}, readers  # fmt: skip
