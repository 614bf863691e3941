"""One name for a released model on the command line and in the Python API (issue 40): `checkpoint=text` and
`checkpoint=action` work where `checkpoint=shipped` does, and `from_pretrained("shipped")` is the text model."""

from __future__ import annotations

from motiondiff.paths import SHIPPED_MODELS, find_checkpoint
from motiondiff.pipelines.motion import resolve_model


def test_shipped_and_the_api_names_resolve_to_the_same_files(tmp_path):
    assert resolve_model("shipped") == resolve_model("text") == SHIPPED_MODELS["text"]
    assert find_checkpoint("text", tmp_path) == find_checkpoint("shipped", tmp_path) == SHIPPED_MODELS["text"]
    assert find_checkpoint("action", tmp_path) == find_checkpoint("shipped", tmp_path, "action")
    assert find_checkpoint("action", tmp_path) == resolve_model("action") == SHIPPED_MODELS["action"]
