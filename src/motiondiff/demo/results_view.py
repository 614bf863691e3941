"""The page's result area: one column per motion, side by side (title, the 3D viewer, the video, the downloads),
the zip of everything, and the timeline bar of a multi-prompt motion. `result_slots` builds the components inside
the current Gradio layout; `slot_updates` / `hidden_slots` fill or clear them, in that order."""

from __future__ import annotations

import html
from pathlib import Path

import gradio as gr

from motiondiff.demo.files import Sample, download_kinds
from motiondiff.demo.models import MAX_SAMPLES

VIEWER_HEIGHT = 320  # px; the viewer page fills it (scene and play bar)
MIN_PANEL = 340  # px: narrower than two of these, a sample's viewer and video stack


def viewer_iframe(page: Path, title: str) -> str:
    """The self-contained HTML viewer in an iframe (``srcdoc``: nothing is served or fetched)."""
    doc = html.escape(page.read_text(encoding="utf-8"), quote=True)
    return (f'<iframe class="motion-viewer" title="3D viewer: {html.escape(title, quote=True)}" srcdoc="{doc}" '
            f'style="width:100%;height:{VIEWER_HEIGHT}px;border:0" loading="eager"></iframe>')  # fmt: skip


def result_slots(blender: bool) -> list:
    """MAX_SAMPLES hidden columns in one row (a request shows as many as it made, side by side)."""
    slots = []
    with gr.Row(equal_height=False):
        for i in range(MAX_SAMPLES):
            with gr.Column(visible=False, min_width=240, elem_id=f"sample-{i}") as column:
                title = gr.Markdown()
                with gr.Row():  # the viewer and the video side by side where there is room, else one above the other
                    with gr.Column(min_width=MIN_PANEL):  # (gr.HTML alone does not keep its min_width in a row)
                        viewer = gr.HTML(elem_id=f"viewer-{i}")
                    video = gr.Video(label="video", elem_id=f"video-{i}", interactive=False, height=VIEWER_HEIGHT - 40,
                                     min_width=MIN_PANEL)  # fmt: skip
                files = gr.File(label=f"downloads ({download_kinds(blender)})", file_count="multiple",
                                elem_id=f"files-{i}", interactive=False)  # fmt: skip
            slots += [column, title, viewer, video, files]
    return slots


def slot_updates(samples: list[Sample]) -> list:
    updates = []
    for i in range(MAX_SAMPLES):
        if i < len(samples):
            s = samples[i]
            updates += [gr.update(visible=True), gr.update(value=f"**{s.title}**"),
                        gr.update(value=viewer_iframe(s.html, s.title)), str(s.mp4), [str(p) for p in s.downloads()]]  # fmt: skip
        else:
            updates += [gr.update(visible=False), gr.update(value=""), gr.update(value=""), None, None]
    return updates


def hidden_slots() -> list:
    return [gr.update(visible=False), gr.update(value=""), gr.update(value=""), None, None] * MAX_SAMPLES


def timeline_bar(segments: list[tuple[str, float, float]]) -> str:
    """The timed prompts of a timeline's motion as a bar: one block per prompt, as wide as its share of the time."""
    if not segments:
        return ""
    total = max(end for _, _, end in segments) or 1.0
    colours = ("#dbeafe", "#fee2e2", "#dcfce7", "#fef9c3", "#ede9fe", "#ffedd5")
    blocks = "".join(
        f'<div class="segment" title="{html.escape(label, quote=True)}" style="flex:{(end - start) / total:.4f};'
        f"background:{colours[k % len(colours)]};padding:6px 8px;border-right:1px solid #fff;overflow:hidden;"
        f'white-space:nowrap;text-overflow:ellipsis">{html.escape(label)} <small>{start:.1f}-{end:.1f} s</small></div>'
        for k, (label, start, end) in enumerate(segments)
    )
    style = "display:flex;width:100%;font-size:13px;border-radius:6px;overflow:hidden"
    return f'<div class="timeline-bar" style="{style}">{blocks}</div>'
