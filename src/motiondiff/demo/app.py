"""The Gradio page of `motiondiff-demo`: a prompt (or an action), length, guidance, seed and number of samples in;
per sample the project's 3D viewer, an MP4 and BVH/NPZ downloads out (and a GLB where Blender's bpy is
available).

`build_demo(models)` returns the `gr.Blocks` app (library code: a script or a test can launch it without the CLI).
A mistake the user can fix (empty text, a length the model cannot make, an unknown action) shows as a warning and
a status line in the page, never a traceback; other failures show one line too and are logged with their traceback
on the server.
"""

from __future__ import annotations

import html
import logging
import tempfile
from pathlib import Path

import gradio as gr

from motiondiff.demo.models import MAX_SAMPLES, DemoModels, Sample, download_kinds, edit_parts, generate, glb_note
from motiondiff.demo.request_folders import request_folder
from motiondiff.runtime.errors import UsageError

log = logging.getLogger(__name__)
VIEWER_HEIGHT = 600  # px; the viewer page fills it (plot and play bar)


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


def viewer_iframe(page: Path, title: str) -> str:
    """The self-contained HTML viewer in an iframe (``srcdoc``: nothing is served or fetched)."""
    doc = html.escape(page.read_text(encoding="utf-8"), quote=True)
    return (f'<iframe class="motion-viewer" title="3D viewer: {html.escape(title, quote=True)}" srcdoc="{doc}" '
            f'style="width:100%;height:{VIEWER_HEIGHT}px;border:0" loading="eager"></iframe>')  # fmt: skip


def _hidden_slots() -> list:
    return [gr.update(visible=False), gr.update(value=""), gr.update(value=""), None, None] * MAX_SAMPLES


def _slot_updates(samples: list[Sample]) -> list:
    updates = []
    for i in range(MAX_SAMPLES):
        if i < len(samples):
            s = samples[i]
            updates += [gr.update(visible=True), gr.update(value=f"**{s.title}**"),
                        gr.update(value=viewer_iframe(s.html, s.title)), str(s.mp4), [str(p) for p in s.downloads()]]  # fmt: skip
        else:
            updates += [gr.update(visible=False), gr.update(value=""), gr.update(value=""), None, None]
    return updates


def build_demo(
    models: DemoModels,
    default: str | None = None,
    *,
    seconds: float = 4.0,
    steps: int = 50,
    output_dir: str | Path | None = None,
) -> gr.Blocks:
    """The demo page for ``models``; ``default`` the model shown first (the first choice when None), loaded now so
    the page opens with its settings; ``seconds``/``steps`` the initial length and sampler steps; ``output_dir``
    where each request's files go (a temporary folder when None)."""
    default = default or models.choices[0].key
    first = models.info(default)
    root = Path(output_dir) if output_dir else Path(tempfile.mkdtemp(prefix="motiondiff-demo-"))
    root.mkdir(parents=True, exist_ok=True)  # a folder that does not exist yet is made, not failed on per request

    def on_model(key):
        info = models.info(key)
        is_action = info.kind == "action"
        limit = f"up to {info.max_seconds:g} s"
        return (gr.update(visible=not is_action),
                gr.update(visible=is_action, choices=info.actions, value=info.actions[0] if info.actions else None),
                gr.update(visible=info.kind == "guided"),
                gr.update(maximum=info.max_seconds, value=min(info.max_seconds, seconds), info=limit),
                gr.update(value=info.default_guidance),
                gr.update(choices=info.parts, value=["upper_body"] if "upper_body" in info.parts else None))  # fmt: skip

    def on_generate(key, text, action, secs, guidance, seed, count, n_steps, weights, progress=gr.Progress()):  # noqa: B008 (Gradio's progress hook)
        kind = models.info(key).kind
        prompt = action if kind == "action" else text
        progress(0.1, desc="sampling")
        try:
            with request_folder(root, "run") as folder:
                out, samples = generate(models, key, prompt, folder, seconds=secs, guidance=guidance, seed=seed,
                                        num_samples=count, steps=n_steps, weights=weights)  # fmt: skip
        except UsageError as err:
            gr.Warning(str(err))
            return [f"**Please fix:** {err}", None, *_hidden_slots()]
        except Exception as err:  # the page shows one line; the server log keeps the traceback
            log.exception("generation failed")
            return [f"**Generation failed:** {type(err).__name__}: {err}", None, *_hidden_slots()]
        settings = ", ".join(f"{k} {out.info[k]}" for k in ("sampler", "steps", "guidance", "seed") if k in out.info)
        local = out.info.get("local_actions")
        if local:
            settings += "; local actions: " + ", ".join(f"{a['text']} (weight {a['weight']:g})" for a in local)
        note = glb_note(models.glb, next((s.glb_error for s in samples if s.glb_error), None))
        far = "".join(f"**Warning:** {line}. " for line in out.info.get("coverage_warnings") or [])
        return [f"{far}Generated {len(samples)} motion(s) with **{key}** ({settings}). {note}", out,
                *_slot_updates(samples)]  # fmt: skip

    def on_edit(key, last, text, action, parts, guidance, seed, n_steps):
        kind = models.info(key).kind
        prompt = action if kind == "action" else text
        try:
            with request_folder(root, "edit") as folder:
                out, samples = edit_parts(models, key, last, prompt, parts, folder, seed=seed, steps=n_steps,
                                          guidance=guidance)  # fmt: skip
        except UsageError as err:
            gr.Warning(str(err))
            return [f"**Please fix:** {err}", last, *_hidden_slots()]
        except Exception as err:
            log.exception("edit failed")
            return [f"**Edit failed:** {type(err).__name__}: {err}", last, *_hidden_slots()]
        regenerated = ", ".join(parts if isinstance(parts, list) else [parts])
        return [f"Regenerated **{regenerated}** of sample 1 from {prompt!r}; the rest of the body is kept.", out,
                *_slot_updates(samples)]  # fmt: skip

    with gr.Blocks(title="motiondiff demo") as demo:
        gr.Markdown("# motiondiff: text and action to human motion\nDescribe a motion (or pick an action), then "
                    "**Generate**. Each sample shows in a 3D viewer (drag to turn, play/pause below it) and as a "
                    f"video, with {download_kinds(models.glb)} downloads.")  # fmt: skip
        with gr.Row():
            with gr.Column(scale=3):
                model = gr.Dropdown([(c.label, c.key) for c in models.choices], value=default, label="model")
                text = gr.Textbox(label="prompt", value="a person walks forward", lines=2, elem_id="prompt",
                                  visible=first.kind != "action",
                                  placeholder="a person walks forward, then waves both hands")  # fmt: skip
                action = gr.Dropdown(first.actions, value=first.actions[0] if first.actions else None, label="action",
                                     visible=first.kind == "action", elem_id="action")  # fmt: skip
                weights = gr.Textbox(label="local action weights (GuidedMotion)", visible=first.kind == "guided",
                                     placeholder="one per action of the caption, e.g. 2, 0.5 (empty: 1 each)")  # fmt: skip
            with gr.Column(scale=2):
                secs = named_slider(0.5, first.max_seconds, value=min(seconds, first.max_seconds), step=0.05,
                                 label="seconds", info=f"up to {first.max_seconds:g} s")  # fmt: skip
                guidance = named_slider(0.0, 15.0, value=first.default_guidance, step=0.1, label="guidance",
                                     info="classifier-free guidance scale (the model's default at first)")  # fmt: skip
                with gr.Row():
                    seed = gr.Number(0, precision=0, label="seed", minimum=0)
                    count = named_slider(1, MAX_SAMPLES, value=1, step=1, label="samples")
                with gr.Accordion("advanced", open=False):
                    n_steps = named_slider(1, 1000, value=steps, step=1, label="sampler steps (DDIM)", elem_id="steps")
        button = gr.Button("Generate", variant="primary", elem_id="generate")
        last = gr.State(None)  # the motions on the page: what an edit starts from
        with gr.Accordion("edit body parts of sample 1", open=False):
            part_names = (
                sorted(models.get(default).model.representation.skeleton.parts) if first.kind != "guided" else []
            )
            parts = gr.Dropdown(part_names, value=["upper_body"] if "upper_body" in part_names else None,
                                multiselect=True, label="parts to regenerate (the rest of the body is kept)",
                                elem_id="parts")  # fmt: skip
            edit_button = gr.Button("Regenerate these parts from the prompt", elem_id="edit")
        status = gr.Markdown(glb_note(models.glb), elem_id="status")
        slots = []
        for i in range(MAX_SAMPLES):
            with gr.Column(visible=False, elem_id=f"sample-{i}") as column:
                title = gr.Markdown()
                viewer = gr.HTML(elem_id=f"viewer-{i}")
                with gr.Row():
                    video = gr.Video(label="video", elem_id=f"video-{i}", interactive=False)
                    files = gr.File(label=f"downloads ({download_kinds(models.glb)})", file_count="multiple",
                                    elem_id=f"files-{i}", interactive=False)  # fmt: skip
            slots += [column, title, viewer, video, files]
        model.change(on_model, model, [text, action, weights, secs, guidance, parts])
        inputs = [model, text, action, secs, guidance, seed, count, n_steps, weights]
        button.click(on_generate, inputs, [status, last, *slots], concurrency_limit=1)
        text.submit(on_generate, inputs, [status, last, *slots], concurrency_limit=1)
        edit_inputs = [model, last, text, action, parts, guidance, seed, n_steps]
        edit_button.click(on_edit, edit_inputs, [status, last, *slots], concurrency_limit=1)
    return demo
