"""The web demo (`motiondiff-demo`): a Gradio page over the public pipelines. It sits above `motiondiff.pipelines`
and below the CLI: only `motiondiff.cli` imports it. `models`, `modes`, `files` and `requests` have no web code;
`app` builds the page, `handlers` answers it, `results_view` shows the results.

    from motiondiff.demo import DemoModels, build_demo
    build_demo(DemoModels()).launch()
"""

import os

from motiondiff.demo.models import DemoModels
from motiondiff.demo.modes.generate import generate


def build_demo(*args, **kwargs):
    """The Gradio app (see `motiondiff.demo.app.build_demo`); Gradio is imported only when a page is built, with its
    usage analytics off (the demo sends nothing off the machine unless asked to share)."""
    os.environ.setdefault("GRADIO_ANALYTICS_ENABLED", "False")
    from motiondiff.demo.app import build_demo as build  # lazy: gradio (+2.9 s to import)

    return build(*args, **kwargs)


__all__ = ["DemoModels", "build_demo", "generate"]
