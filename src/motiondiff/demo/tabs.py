"""The four mode tabs of the page, each with its own inputs and button (the prompt, length, guidance, seed and
samples above the tabs are shared). Each function builds one tab inside the current `gr.Tabs` and returns its
components by name."""

from __future__ import annotations

import contextlib
from types import SimpleNamespace

import gradio as gr

from motiondiff.demo.controls import motion_source_inputs, named_slider
from motiondiff.demo.models import ModelInfo
from motiondiff.demo.modes.source import ON_PAGE, UPLOADED


def generate_tab() -> SimpleNamespace:
    with gr.Tab("Generate", elem_id="tab-generate"):
        with gr.Row():
            gr.Markdown("Samples of the prompt side by side: the same prompt, each from its own noise (set how many "
                        "with **samples** above).")  # fmt: skip
            button = gr.Button("Generate", variant="primary", elem_id="generate", scale=0, min_width=200)
    return SimpleNamespace(button=button)


@contextlib.contextmanager
def source_tab(title: str, prefix: str, default_source: str, note: str):
    """A tab (``tab-<prefix>``) that starts from a motion: its ``note``, the "start from" inputs, and a column the
    block fills with the mode's own inputs; yields the tab's components by name, for the block to add to."""
    with gr.Tab(title, elem_id=f"tab-{prefix}"):
        gr.Markdown(note)
        with gr.Row():
            source, sample, upload = motion_source_inputs(prefix, default_source)
            with gr.Column(scale=2, min_width=240):
                yield SimpleNamespace(source=source, sample=sample, upload=upload)


def edit_tab(info: ModelInfo) -> SimpleNamespace:
    note = ("Regenerate the chosen body parts from the prompt and keep the rest of the body as it was, over every "
            "frame (as `edit.py kind=parts parts=...`).")  # fmt: skip
    with source_tab("Edit body parts", "edit", ON_PAGE, note) as tab:
        tab.parts = gr.Dropdown(info.parts, value=["upper_body"] if "upper_body" in info.parts else None,
                                multiselect=True, label="parts to regenerate (the rest of the body is kept)",
                                elem_id="parts")  # fmt: skip
        tab.button = gr.Button("Regenerate these parts", variant="primary", elem_id="edit")
    return tab


def inbetween_tab() -> SimpleNamespace:
    note = ("Keep the start and the end of a motion (your BVH) and generate the frames between from the prompt; the "
            "result is as long as the motion.")  # fmt: skip
    with source_tab("In-between", "inbetween", UPLOADED, note) as tab:
        tab.keep_start = named_slider(0, 50, value=25, step=1, label="kept start (% of frames)", elem_id="keep-start")
        tab.keep_end = named_slider(0, 50, value=25, step=1, label="kept end (% of frames)", elem_id="keep-end")
        tab.button = gr.Button("Generate the frames between", variant="primary", elem_id="inbetween")
    return tab


def timeline_tab(info: ModelInfo) -> SimpleNamespace:
    with gr.Tab("Timeline", elem_id="tab-timeline"):
        gr.Markdown("One motion through several prompts in order, one `prompt : seconds` per line (a line without "
                    "seconds lasts the **seconds** above); each part continues from the one before.")  # fmt: skip
        with gr.Row():
            with gr.Column(scale=3):
                lines = gr.Textbox(label="timeline", value=info.timelines[0] if info.timelines else "", lines=3,
                                   elem_id="timeline")  # fmt: skip
                button = gr.Button("Make the timeline", variant="primary", elem_id="make-timeline")
            examples = gr.Dataset(components=[lines], samples=[[t] for t in info.timelines], label="example timelines",
                                  elem_id="timeline-examples", visible=bool(info.timelines), scale=2)  # fmt: skip
    return SimpleNamespace(lines=lines, examples=examples, button=button)
