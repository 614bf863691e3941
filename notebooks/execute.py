"""Run the notebooks top to bottom and save them with their outputs as a reader should see them (`make notebooks`):
every figure kept; stderr streams (progress bars, library warnings) dropped; this machine's paths replaced by
<repo> and <tmp>; no execution times. tests/unit/test_saved_notebooks.py checks the saved files."""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path

import nbformat
from nbclient import NotebookClient

REPO = Path(__file__).resolve().parents[1]
TEMP = re.compile(re.escape(tempfile.gettempdir().rstrip("/")) + r"/[^/\s'\"]+")


def scrub(text: str) -> str:
    return TEMP.sub("<tmp>", text.replace(str(REPO), "<repo>"))


def clean(nb) -> None:
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        cell.metadata.pop("execution", None)
        kept = []
        for out in cell.outputs:
            if out.output_type == "stream" and out.name == "stderr":
                continue
            if "text" in out:
                out.text = scrub(out.text)
            for key in list(out.get("data", {})):
                if key.startswith("text/"):
                    out.data[key] = scrub(out.data[key])
            kept.append(out)
        cell.outputs = kept


def main(paths: list[str]) -> None:
    for path in paths:
        nb = nbformat.read(path, as_version=4)
        NotebookClient(
            nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(REPO / "notebooks")}}
        ).execute()
        clean(nb)
        nbformat.write(nb, path)
        print(f"ran and saved {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
