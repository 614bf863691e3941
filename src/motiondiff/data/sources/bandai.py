"""The Bandai Namco Research Motion Dataset (1 and 2) as distributed: zip or folder with
`data/<name>.bvh`, `data/<name>.json` ({"content": i, "style": j}), `cfg/content_label.txt`, `cfg/style_label.txt`.

Labels are read from the JSON files (indices into the cfg lists) and cross-checked with the file name
`dataset-N_<content>_<style>_<NNN>`; a disagreement skips the clip with the reason named.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import PurePosixPath

from motiondiff.data.formats.archive import Source

ATTRIBUTION = "Bandai Namco Research Motion Dataset, Bandai Namco Research Inc., CC BY-NC 4.0"
NAME_PATTERN = re.compile(r"^(dataset-\d+)_(.+)_([a-z-]+)_(\d+)$")


class BandaiLayoutError(ValueError):
    """The source is not laid out like a Bandai Namco release."""


@dataclass
class BandaiClip:
    name: str  # file stem, e.g. dataset-2_walk_active_001
    source: Source
    bvh_name: str
    dataset: str  # "dataset-1" | "dataset-2"
    content: str  # label without the dataset prefix, e.g. "walk-turn-left"
    style: str


@dataclass
class Skipped:
    name: str
    reason: str


def _labels(source: Source, kind: str) -> list[str]:
    name = f"cfg/{kind}_label.txt"
    if not source.exists(name):
        raise BandaiLayoutError(
            f"{source.path}: no {name}. A Bandai Namco release has data/*.bvh, data/*.json, cfg/content_label.txt and "
            "cfg/style_label.txt; pass the original zip (or its unzipped folder). For BVH files without these labels "
            "use the generic `bvh` dataset instead."
        )
    return [line.strip() for line in source.read_text(name).splitlines() if line.strip()]


def _strip_prefix(label: str) -> str:
    return re.sub(r"^dataset-\d+_", "", label)


def list_clips(source: Source) -> tuple[list[BandaiClip], list[Skipped]]:
    """All labelled clips of one release, and every clip that cannot be used with its reason."""
    contents = _labels(source, "content")
    styles = _labels(source, "style")
    clips, skipped = [], []
    bvhs = [n for n in source.names() if n.startswith("data/") and n.lower().endswith(".bvh")]
    if not bvhs:
        raise BandaiLayoutError(f"{source.path}: no data/*.bvh files; is this a Bandai Namco release?")
    for bvh in bvhs:
        stem = PurePosixPath(bvh).stem
        label_file = f"data/{stem}.json"
        if not source.exists(label_file):
            skipped.append(Skipped(stem, f"no labels file {label_file}"))
            continue
        try:
            spec = json.loads(source.read_text(label_file))
            content, style = _strip_prefix(contents[spec["content"]]), _strip_prefix(styles[spec["style"]])
        except (ValueError, KeyError, IndexError, TypeError) as err:
            skipped.append(Skipped(stem, f"unreadable labels in {label_file}: {err!r}"))
            continue
        m = NAME_PATTERN.match(stem)
        if m is None or (m.group(2), m.group(3)) != (content, style):
            skipped.append(Skipped(stem, f"labels {content}/{style} in {label_file} disagree with the file name"))
            continue
        clips.append(BandaiClip(stem, source, bvh, m.group(1), content, style))
    return clips, skipped
