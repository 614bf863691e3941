"""User text is data, never configuration: a prompt that looks like an OmegaConf interpolation reaches every output
as written, and no environment value leaks into results.json, the file names or the HTML viewer."""

from __future__ import annotations

import json
import os

from hostile_cli import files_under, run_in_process

SECRET = "motiondiff-hostile-secret-value"


def test_an_interpolation_in_the_text_is_written_literally_and_results_record_what_ran(tmp_path):
    text = "${oc.env:MOTIONDIFF_TEST_SECRET}"
    proc = run_in_process(tmp_path, "sample", "checkpoint=shipped", f"text='{text}'", "num_samples=1", "length=1",
                   "export=[bvh,html]", "sampler=ddim", "steps=3", env={"MOTIONDIFF_TEST_SECRET": SECRET})  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    (results,) = (tmp_path / "outputs").rglob("results.json")
    summary = json.loads(results.read_text())
    assert [row["prompt"] for row in summary["samples"]] == [text]
    assert summary["steps"] == 3 and summary["sampler"]["name"] == "ddim", "results.json must record what ran"
    written = files_under(tmp_path / "outputs")
    assert not any(SECRET in name for name in written), written
    for path in (tmp_path / "outputs").rglob("*"):
        if path.is_file() and path.suffix in (".json", ".html", ".bvh", ".yaml", ".log"):
            assert SECRET not in path.read_text(errors="replace"), f"the environment value leaked into {path.name}"
    (html,) = (tmp_path / "outputs").rglob("*.html")
    assert "oc.env:MOTIONDIFF_TEST_SECRET" in html.read_text()
    assert os.environ.get("MOTIONDIFF_TEST_SECRET") is None
