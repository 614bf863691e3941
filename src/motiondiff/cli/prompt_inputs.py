"""What a user asks `sample.py` for, checked as text before any model loads: one source of prompts (text=, prompts=,
prompts_file= or action=), a readable UTF-8 prompts file with prompts in it, non-empty prompts, and timed prompts
(``a person walks:4``) parsed. Nothing heavy is imported here, so `motiondiff-sample` refuses these in a second."""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path

from omegaconf import DictConfig, ListConfig

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.prompt_text import check_text
from motiondiff.runtime.scripting import literal

SOURCES = ("text", "prompts", "prompts_file", "action")
# "<text>:<seconds>", seconds a positive decimal, optionally "4s"; a colon not followed by a number is text
TIMED = re.compile(r"^(?P<text>.*?)\s*:\s*(?P<seconds>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*s?\s*$")


def check_one_source(cfg: DictConfig) -> None:
    if sum(cfg.get(key) is not None for key in SOURCES) > 1:
        raise UsageError("give only one of text=, prompts=, prompts_file= or action=")


def read_prompts_file(path: str | Path) -> list[str]:
    """The non-blank lines of a UTF-8 prompts file, or one clear error (missing, not UTF-8, no prompts)."""
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"prompts_file {path} not found")
    texts = [line for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    if not texts:
        raise UsageError(f"prompts_file {path} has no prompts (one per line)")
    return texts


def check_prompt_inputs(cfg: DictConfig) -> None:
    """Every check of the prompts that needs no model (the model's own checks follow once it is loaded)."""
    check_one_source(cfg)
    plain, _ = split_timed(cfg)
    if plain.get("prompts_file") is not None:
        texts = read_prompts_file(plain.prompts_file)
    elif plain.get("prompts") is not None:
        texts = list(plain.prompts) if isinstance(plain.prompts, ListConfig | list) else [plain.prompts]
    else:
        texts = [plain.text] if plain.get("text") is not None else []
    for text in texts:
        check_text(text)


def parse_timed_prompts(items: list[str]) -> list[tuple[str, float]] | None:
    """["a person walks:4", "a person waves:2.5"] -> [("a person walks", 4.0), ("a person waves", 2.5)]; None when
    no item ends in :<seconds> (separate samples, as before). Every item or none must be timed."""
    matches = [TIMED.match(str(item)) for item in items]
    if not any(matches):
        return None
    untimed = [str(item) for item, m in zip(items, matches, strict=True) if m is None]
    if untimed:
        raise UsageError(
            f"either every prompt ends in :<seconds> (one long motion through them) or none does (separate "
            f"samples); these have no time: {', '.join(repr(u) for u in untimed)}"
        )
    timed = []
    for m in matches:
        text, seconds = m["text"].strip(), float(m["seconds"])
        if not text:
            raise UsageError(f"{m.string!r} has a time but no prompt before the colon")
        if not (seconds > 0 and math.isfinite(seconds)):
            raise UsageError(f"{m.string!r}: the seconds after the colon must be positive")
        timed.append((text, seconds))
    return timed


def split_timed(cfg: DictConfig) -> tuple[DictConfig, list[float] | None]:
    """The config with timed prompts=/prompts_file=/action= items reduced to their texts, and their seconds (None:
    untimed, the config as given). text= is one prompt and never timed."""
    key = next((k for k in ("prompts", "prompts_file", "action") if cfg[k] is not None), None)
    if key is None or sum(cfg[k] is not None for k in SOURCES) > 1:
        return cfg, None  # nothing to parse, or a conflict that collect_prompts reports
    if key == "prompts_file":
        items = read_prompts_file(cfg.prompts_file)
    else:
        items = list(cfg[key]) if isinstance(cfg[key], ListConfig | list) else [cfg[key]]
    timed = parse_timed_prompts(items)
    if timed is None:
        return cfg, None
    plain = copy.deepcopy(cfg)
    plain.prompts_file = None
    plain["action" if key == "action" else "prompts"] = [literal(text) for text, _ in timed]  # data, not config
    return plain, [seconds for _, seconds in timed]
