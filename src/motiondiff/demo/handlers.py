"""The page's event handlers: each reads its inputs, runs one mode as a request (`requests.run_request`) and returns
the page's new state, in the order `OUTPUTS` names: the status line, the coverage warning, the motions on the page
(what an edit starts from), the zip, the timeline bar, then the result slots. A mistake the user can fix is a
warning and a "Please fix" status line; any other failure one status line (its traceback goes to the server log);
either way the page shows no stale result.
"""

from __future__ import annotations

import html
import logging
from collections.abc import Callable
from pathlib import Path

import gradio as gr

from motiondiff.demo.files import blender_note
from motiondiff.demo.inputs import Sampling
from motiondiff.demo.models import DemoModels
from motiondiff.demo.modes.edit import edit_parts
from motiondiff.demo.modes.generate import generate
from motiondiff.demo.modes.inbetween import inbetween
from motiondiff.demo.modes.source import UPLOADED, motion_source
from motiondiff.demo.modes.timeline import segments, timeline
from motiondiff.demo.requests import Result, run_request
from motiondiff.demo.results_view import hidden_slots, slot_updates, timeline_bar
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError

log = logging.getLogger(__name__)
OUTPUTS = ("status", "coverage", "last", "zip", "bar", "slots")
WARNING_STYLE = "background:#fff7e6;border:1px solid #f0b429;border-radius:6px;padding:8px 12px;color:#5c3c00"


def settings_line(out: MotionOutput) -> str:
    """How the motions were made, from the output's info: sampler, steps, guidance, seed."""
    return ", ".join(f"{k} {out.info[k]}" for k in ("sampler", "steps", "guidance", "seed") if k in out.info)


def coverage_box(lines: list[str]):
    """The coverage warning: shown only when a prompt was far from the model's training captions."""
    items = "".join(f"<li>{html.escape(line)}.</li>" for line in lines)
    box = (f'<div class="coverage-warning" role="alert" style="{WARNING_STYLE}"><b>&#9888; Prompt coverage '
           f'warning</b><ul style="margin:4px 0 0 18px;padding:0">{items}</ul></div>')  # fmt: skip
    return gr.update(value=box if lines else "", visible=bool(lines))


def prompt_of(models: DemoModels, key: str, text: str | None, action: str | None) -> str | None:
    """The prompt box of a text model, or the chosen action of an action model."""
    return action if models.info(key).kind == "action" else text


class Handlers:
    """The handlers of one page: ``models``, the folder ``root`` each request's files go under."""

    def __init__(self, models: DemoModels, root: Path):
        self.models, self.root = models, root

    def respond(self, kind: str, make: Callable[[], MotionOutput], video_size, describe: Callable[[Result], str]):
        try:
            result = run_request(self.models, self.root, kind, make, video_size=int(video_size))
        except UsageError as err:
            gr.Warning(str(err))
            return self.failed(f"**Please fix:** {err}")
        except Exception as err:  # the page shows one line; the server log keeps the traceback
            log.exception("%s request failed", kind)
            return self.failed(f"**That did not work:** {type(err).__name__}: {err}")
        bar = timeline_bar(segments(result.out))
        status = f"{describe(result)} {blender_note(self.models.glb, result.blender_error)}"
        bar_update = gr.update(value=bar, visible=bool(bar))
        zip_update = gr.update(value=str(result.zip), visible=True)
        return [status, coverage_box(result.coverage), result.out, zip_update, bar_update,
                *slot_updates(result.samples)]  # fmt: skip

    @staticmethod
    def failed(status: str) -> list:
        hidden = gr.update(value=None, visible=False)
        return [status, coverage_box([]), None, hidden, gr.update(value="", visible=False), *hidden_slots()]

    def on_generate(self, key, text, action, secs, guidance, seed, count, n_steps, video_size, weights):
        prompt = prompt_of(self.models, key, text, action)

        def make():
            sampling = Sampling.from_page(seed, n_steps, guidance, count)
            return generate(self.models, key, prompt, seconds=secs, sampling=sampling, weights=weights)

        def describe(r: Result) -> str:
            line = f"Generated {len(r.samples)} motion(s) of {prompt!r} with `{key}` ({settings_line(r.out)})."
            local = r.out.info.get("local_actions")
            if local:
                line += " Local actions: " + ", ".join(f"{a['text']} (weight {a['weight']:g})" for a in local) + "."
            return line

        return self.respond("run", make, video_size, describe)

    def on_edit(self, key, last, source, sample, upload, text, action, parts, guidance, seed, count, n_steps,
                video_size):  # fmt: skip
        prompt = prompt_of(self.models, key, text, action)

        def make():
            motion = motion_source(source, last, sample, upload)
            sampling = Sampling.from_page(seed, n_steps, guidance, count)
            return edit_parts(self.models, key, motion, prompt, parts, sampling=sampling)

        def describe(r: Result) -> str:
            named = parts if isinstance(parts, str) else ", ".join(parts)
            return (f"Regenerated **{named}** of {_source_name(source, sample, upload)} from "
                    f"{prompt!r}; the rest of the body is kept ({settings_line(r.out)}).")  # fmt: skip

        return self.respond("edit", make, video_size, describe)

    def on_inbetween(self, key, last, source, sample, upload, text, action, keep_start, keep_end, guidance, seed,
                     count, n_steps, video_size):  # fmt: skip
        prompt = prompt_of(self.models, key, text, action)

        def make():
            motion = motion_source(source, last, sample, upload)
            sampling = Sampling.from_page(seed, n_steps, guidance, count)
            return inbetween(self.models, key, motion, prompt, keep_start=keep_start, keep_end=keep_end,
                             sampling=sampling)  # fmt: skip

        def describe(r: Result) -> str:
            info, frames = r.out.info, len(r.out.joints[0])
            first, last_ = (info.get("prefix_frames") or [0])[0], (info.get("suffix_frames") or [0])[0]
            return (f"Kept the first {first} and the last {last_} of {frames} frames of "
                    f"{_source_name(source, sample, upload)} and generated the {frames - first - last_} between from "
                    f"{prompt!r} ({settings_line(r.out)}).")  # fmt: skip

        return self.respond("inbetween", make, video_size, describe)

    def on_timeline(self, key, lines, secs, guidance, seed, count, n_steps, video_size):
        def make():
            sampling = Sampling.from_page(seed, n_steps, guidance, count)
            return timeline(self.models, key, lines, seconds=secs, sampling=sampling)

        def describe(r: Result) -> str:
            parts = segments(r.out)
            return (f"Made {len(r.samples)} motion(s) of {r.out.seconds():.1f} s through {len(parts)} timed prompts "
                    f"with `{key}` ({settings_line(r.out)}).")  # fmt: skip

        return self.respond("timeline", make, video_size, describe)


def _source_name(source: str, sample, upload: str | None) -> str:
    return f"the upload {Path(upload).name}" if source == UPLOADED and upload else f"sample {int(sample)} on the page"
