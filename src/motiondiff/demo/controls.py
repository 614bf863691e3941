"""The page's input controls that more than one place uses or updates: sliders that name their field when a value
is refused, the "start from" inputs of the edit and in-between tabs, and what a model switch changes."""

from __future__ import annotations

import gradio as gr

from motiondiff.demo.models import MAX_SAMPLES, ModelInfo
from motiondiff.demo.modes.source import SOURCES

UPLOAD_TYPES = [".bvh", ".npy", ".npz"]


def named_slider(*args, **kwargs) -> gr.Slider:
    """A `gr.Slider` whose out-of-range refusal names its field: Gradio's own says only "Value 1e9 is greater than
    maximum value 6.0." (the page cannot send such a value; a client of the demo's API can). The method is wrapped
    on the instance, not in a subclass: Gradio writes a .pyi stub beside the source of every Component subclass."""
    slider = gr.Slider(*args, **kwargs)
    plain = slider.preprocess

    def preprocess(payload: float) -> float:
        try:
            return plain(payload)
        except gr.Error as err:
            raise gr.Error(f"Please fix {slider.label}: {err.message}") from None

    slider.preprocess = preprocess
    return slider


def motion_source_inputs(prefix: str, default: str) -> tuple:
    """Where an edit starts: a sample on the page (which one) or an uploaded file; (source, sample, upload)."""
    with gr.Column(scale=2, min_width=280):
        source = gr.Radio(list(SOURCES), value=default, label="start from", elem_id=f"{prefix}-source")
        sample = named_slider(1, MAX_SAMPLES, value=1, step=1, label="sample on the page", elem_id=f"{prefix}-sample")
    upload = gr.File(label="motion file (.bvh, or joints .npy/.npz)", file_types=UPLOAD_TYPES, type="filepath",
                     height=140, scale=2, min_width=240, elem_id=f"{prefix}-upload")  # fmt: skip
    return source, sample, upload


def coverage_note(info: ModelInfo) -> str:
    """Whether the model's prompts are checked against its training captions (text models only)."""
    if info.kind != "text":
        return ""
    if info.checks_coverage:
        return "This model checks each prompt against its training captions and warns when one is far from them."
    return "This model carries no coverage bank: prompts far from its training captions are not flagged."


def model_updates(info: ModelInfo, seconds: float) -> list:
    """What a model switch changes, in the order of `build_demo`'s model.change outputs: the prompt or action box,
    GuidedMotion's weights, the length limit, the guidance, the body parts, the examples, the example timelines, the
    timeline box and the coverage note."""
    is_action = info.kind == "action"
    return [
        gr.update(visible=not is_action),
        gr.update(visible=is_action, choices=info.actions, value=info.actions[0] if info.actions else None),
        gr.update(visible=info.kind == "guided"),
        gr.update(maximum=info.max_seconds, value=min(info.max_seconds, seconds), info=f"up to {info.max_seconds:g} s"),
        gr.update(value=info.default_guidance),
        gr.update(choices=info.parts, value=["upper_body"] if "upper_body" in info.parts else None),
        gr.Dataset(samples=[[e] for e in info.examples], visible=not is_action and bool(info.examples)),
        gr.Dataset(samples=[[t] for t in info.timelines], visible=bool(info.timelines)),
        gr.update(value=info.timelines[0] if info.timelines else ""),
        gr.update(value=coverage_note(info)),
    ]
