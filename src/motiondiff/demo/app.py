"""The Gradio page of `motiondiff-demo`: a model, a prompt (or an action) with example prompts from the model's own
training vocabulary, the length, guidance, seed and sample controls, and four modes (tabs): Generate, Edit body
parts, In-between and Timeline. Results show side by side (3D viewer, video, downloads) with a zip of everything.

`build_demo(models)` returns the `gr.Blocks` app (library code: a script or a test can launch it without the CLI).
The tabs are in `demo.tabs`, the shared controls in `demo.controls`, the handlers in `demo.handlers`, the result area
in `demo.results_view`; the modes themselves have no web code (`demo.modes`).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import gradio as gr

from motiondiff.demo.controls import coverage_note, model_updates, named_slider
from motiondiff.demo.files import blender_note, download_kinds
from motiondiff.demo.handlers import Handlers
from motiondiff.demo.models import MAX_SAMPLES, DemoModels
from motiondiff.demo.results_view import result_slots
from motiondiff.demo.tabs import edit_tab, generate_tab, inbetween_tab, timeline_tab
from motiondiff.export.render import VIDEO_SIZE

VIDEO_SIZES = (360, 540, 720, 1080)  # the video size choices (pixels square); the default is the commands'


def build_demo(
    models: DemoModels,
    default: str | None = None,
    *,
    seconds: float = 4.0,
    steps: int = 50,
    video_size: int = VIDEO_SIZE,
    output_dir: str | Path | None = None,
) -> gr.Blocks:
    """The demo page for ``models``; ``default`` the model shown first (the first choice when None), loaded now so
    the page opens with its settings; ``seconds``/``steps``/``video_size`` the initial length, sampler steps and
    video size; ``output_dir`` where each request's files go (a temporary folder when None)."""
    default = default or models.choices[0].key
    first = models.info(default)
    root = Path(output_dir) if output_dir else Path(tempfile.mkdtemp(prefix="motiondiff-demo-"))
    root.mkdir(parents=True, exist_ok=True)  # a folder that does not exist yet is made, not failed on per request
    handlers = Handlers(models, root)

    with gr.Blocks(title="motiondiff demo") as demo:
        gr.Markdown("## motiondiff: text and action to human motion\nDescribe a motion (or pick an example), choose a "
                    "mode below and press its button. Each motion shows in a 3D viewer (drag to turn) and as a video, "
                    f"with {download_kinds(models.glb)} downloads and a zip of everything.")  # fmt: skip
        with gr.Row():
            with gr.Column(scale=3):
                model = gr.Dropdown([(c.label, c.key) for c in models.choices], value=default, label="model")
                text = gr.Textbox(label="prompt", value=(first.examples or ["a person walks forward"])[0], lines=1,
                                  elem_id="prompt", visible=first.kind != "action",
                                  placeholder="a person walks forward, then waves both hands")  # fmt: skip
                action = gr.Dropdown(first.actions, value=first.actions[0] if first.actions else None, label="action",
                                     visible=first.kind == "action", elem_id="action")  # fmt: skip
                weights = gr.Textbox(label="local action weights (GuidedMotion)", visible=first.kind == "guided",
                                     placeholder="one per action of the caption, e.g. 2, 0.5 (empty: 1 each)")  # fmt: skip
                note = gr.Markdown(coverage_note(first), elem_id="coverage-note")
            with gr.Column(scale=2):
                secs = named_slider(0.5, first.max_seconds, value=min(seconds, first.max_seconds), step=0.05,
                                    label="seconds", info=f"up to {first.max_seconds:g} s", elem_id="seconds")  # fmt: skip
                guidance = named_slider(0.0, 15.0, value=first.default_guidance, step=0.1, label="guidance",
                                        info="classifier-free guidance scale (the model's default at first)",
                                        elem_id="guidance")  # fmt: skip
                with gr.Row():
                    seed = gr.Number(0, precision=0, label="seed", minimum=0, elem_id="seed")
                    count = named_slider(1, MAX_SAMPLES, value=1, step=1, label="samples", elem_id="samples")
                with gr.Accordion("advanced", open=False):
                    n_steps = named_slider(1, 1000, value=steps, step=1, label="sampler steps (DDIM)", elem_id="steps")
                    size = gr.Dropdown(sorted({*VIDEO_SIZES, int(video_size)}), value=int(video_size),
                                       label="video size (pixels)", elem_id="video-size")  # fmt: skip
        examples = gr.Dataset(components=[text], samples=[[e] for e in first.examples], label="example prompts (from "
                              "the model's training actions)", elem_id="examples", samples_per_page=40,
                              visible=first.kind != "action" and bool(first.examples))  # fmt: skip
        with gr.Tabs():
            gen, edit, between, line = generate_tab(), edit_tab(first), inbetween_tab(), timeline_tab(first)
        with gr.Row():
            status = gr.Markdown(blender_note(models.glb), elem_id="status")
            everything = gr.File(label="everything (zip)", elem_id="zip", interactive=False, visible=False, scale=0,
                                 min_width=320)  # fmt: skip
        coverage = gr.HTML(visible=False, elem_id="coverage")
        bar = gr.HTML(visible=False, elem_id="timeline-bar")
        slots = result_slots(models.glb)
        last = gr.State(None)  # the motions on the page: what an edit or an in-between can start from

        def on_model(key):
            return model_updates(models.info(key), seconds)

        def on_example(row):
            return row[0]

        examples.click(on_example, examples, text)
        line.examples.click(on_example, line.examples, line.lines)
        model.change(on_model, model, [text, action, weights, secs, guidance, edit.parts, examples, line.examples,
                                       line.lines, note])  # fmt: skip
        outputs = [status, coverage, last, everything, bar, *slots]
        run = {"concurrency_limit": 1, "concurrency_id": "motion"}  # one request at a time: the CPU is the limit
        common = [guidance, seed, count, n_steps, size]
        generate_inputs = [model, text, action, secs, guidance, seed, count, n_steps, size, weights]
        gen.button.click(handlers.on_generate, generate_inputs, outputs, **run)
        text.submit(handlers.on_generate, generate_inputs, outputs, **run)
        edit_inputs = [model, last, edit.source, edit.sample, edit.upload, text, action, edit.parts, *common]
        edit.button.click(handlers.on_edit, edit_inputs, outputs, **run)
        between_inputs = [model, last, between.source, between.sample, between.upload, text, action,
                          between.keep_start, between.keep_end, *common]  # fmt: skip
        between.button.click(handlers.on_inbetween, between_inputs, outputs, **run)
        line.button.click(handlers.on_timeline, [model, line.lines, secs, *common], outputs, **run)
    return demo
