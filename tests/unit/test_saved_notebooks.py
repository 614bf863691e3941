"""The notebooks are saved as a reader should see them (`make notebooks`, notebooks/execute.py): every cell that
draws has its figure, and no output holds this machine's paths, stderr noise (progress bars, warnings) or W&B lines."""

from __future__ import annotations

import re
from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "notebooks").glob("*.ipynb"))
DRAWS = re.compile(r"plt\.show\(|\.gif\(|\.show\(|display\(")
MACHINE = re.compile(r"/(?:work|root|home|tmp|Users)/|[A-Z]:\\\\")
NOISE = ("IProgress", "TqdmWarning", "wandb:", "Warning:")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_saved_notebook_has_its_figures_and_no_machine_paths(path):
    nb = nbformat.read(path, as_version=4)
    for k, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
        shown = [key for out in cell.outputs for key in out.get("data", {})]
        if DRAWS.search(cell.source):
            assert any(key.startswith("image/") or key == "text/html" for key in shown), f"cell {k} lost its figure"
        assert not [out for out in cell.outputs if out.get("name") == "stderr"], f"cell {k} saved stderr"
        texts = [out.get("text", "") for out in cell.outputs] + [
            value for out in cell.outputs for key, value in out.get("data", {}).items() if key.startswith("text/")
        ]
        for text in texts:
            text = "".join(text) if isinstance(text, list) else text
            assert not MACHINE.search(text), f"cell {k} holds a machine path: {MACHINE.search(text).group(0)!r}"
            assert not any(n in text for n in NOISE), f"cell {k} holds noise: {text[:200]!r}"
