"""sample.py render=body (in process, the released text model): without a video it is one clear error before any
sampling. What it writes is checked through MotionOutput.save (tests/unit/export/test_body_render.py), the path the
command takes."""

from __future__ import annotations

from fixtures.in_process import files_under, user_error

SAMPLE = ["checkpoint=shipped", "num_samples=1", "steps=3", "length=2", "text=a person walks"]


def test_render_body_without_a_video_is_one_error_before_sampling(tmp_path):
    error = user_error("sample", tmp_path / "case", *SAMPLE, "render=body", "export=[bvh]")
    assert "render=body draws the mannequin" in error and "add mp4 or gif to export=" in error and "\n" not in error
    assert not files_under(tmp_path / "case" / "run")
