"""`motiondiff-demo`: the web demo on this machine (Gradio). Local only by default: 127.0.0.1, no share link.

    motiondiff-demo                                  # http://127.0.0.1:7860
    motiondiff-demo --port 8000 --host 0.0.0.0       # reachable from the network
    motiondiff-demo guided=outputs/latent/<run>/checkpoints/last.ckpt   # also offer your own GuidedMotion model

Options are `--name value` or, like the other commands, `name=value`. `--share` asks Gradio for a public link (it
needs internet and is off by default).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

from motiondiff.demo import DemoModels, build_demo
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.scripting import quiet_tool_caches, user_errors
from motiondiff.runtime.settings import check_settings


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="motiondiff-demo", description="The motiondiff web demo (Gradio).")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=7860, help="port (default 7860)")
    p.add_argument("--share", action="store_true", help="a public gradio.live link (needs internet; off by default)")
    p.add_argument("--guided", default=None, help="a GuidedMotion checkpoint (train_latent.py) to offer as well")
    p.add_argument("--local-model", default="text", help="the text model that makes GuidedMotion's local actions")
    p.add_argument("--model", default=None, help="the model shown first (default: text)")
    p.add_argument("--seconds", type=float, default=4.0, help="the initial length in seconds")
    p.add_argument("--steps", type=int, default=50, help="the initial sampler steps")
    p.add_argument("--output-dir", default=None, help="where generated files go (default: a temporary folder)")
    return p


def parse_args(argv: list[str]) -> argparse.Namespace:
    """``--name value`` and ``name=value`` (``local_model=`` as ``--local-model``) alike."""
    args = []
    for a in argv:
        key, eq, value = a.partition("=")
        if eq and not a.startswith("-"):
            args += [f"--{key.replace('_', '-')}", value] if key != "share" else (["--share"] if _yes(value) else [])
        else:
            args.append(a)
    return parser().parse_args(args)


def check_args(args: argparse.Namespace) -> None:
    """The port, the initial settings and the output folder (created if missing), refused before any model loads."""
    if not 1 <= args.port <= 65535:
        raise UsageError(f"--port {args.port}: must be a port number from 1 to 65535 (e.g. 7860)")
    check_settings(seconds=args.seconds, steps=args.steps)
    if args.output_dir is not None:
        out = Path(args.output_dir)
        if out.exists() and not out.is_dir():
            raise UsageError(f"--output-dir {out} is a file, not a folder: give a folder (it is created if missing)")
        out.mkdir(parents=True, exist_ok=True)


def _yes(value: str) -> bool:
    return value.strip().lower() in ("1", "true", "yes", "on")


@user_errors
def main(argv: list[str] | None = None) -> None:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    if importlib.util.find_spec("gradio") is None:  # an install without the [demo] extra
        print("error: the web demo needs Gradio, which this install lacks: pip install 'motiondiff[demo]' (from a "
              "checkout: pip install -e '.[demo]')", file=sys.stderr)  # fmt: skip
        sys.exit(2)
    check_args(args)  # before the models load (seconds of CPU)
    quiet_tool_caches()

    models = DemoModels(guided=args.guided, local_model=args.local_model)
    demo = build_demo(models, args.model, seconds=args.seconds, steps=args.steps, output_dir=args.output_dir)
    demo.queue().launch(server_name=args.host, server_port=args.port, share=args.share)
