"""What a user asks `sample.py` for, checked as text before any model loads: one source of prompts (text=, prompts=,
prompts_file= or action=), a readable UTF-8 prompts file with prompts in it, non-empty prompts, and timed prompts
(``a person walks:4``) parsed. Nothing heavy is imported here, so `motiondiff-sample` refuses these in a second."""

from __future__ import annotations

import copy
from pathlib import Path

from omegaconf import DictConfig, ListConfig

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.file_kinds import file_problem
from motiondiff.runtime.prompt_text import check_long_seconds, check_text, split_time
from motiondiff.runtime.scripting import literal
from motiondiff.runtime.settings import MAX_PROMPTS, MAX_PROMPTS_FILE_BYTES, MAX_SEGMENTS, check_count

SOURCES = ("text", "prompts", "prompts_file", "action")


def check_one_source(cfg: DictConfig) -> None:
    if sum(cfg.get(key) is not None for key in SOURCES) > 1:
        raise UsageError("give only one of text=, prompts=, prompts_file= or action=")


def read_prompts_file(path: str | Path) -> list[str]:
    """The non-blank lines of a UTF-8 prompts file, or one clear error (missing, not a file, over
    MAX_PROMPTS_FILE_BYTES (refused unread), not UTF-8, no prompts)."""
    path = Path(path)
    problem = file_problem(path, allow_empty=True)
    if problem is not None:
        raise UsageError(f"prompts_file {path} {problem}: give a UTF-8 text file, one prompt a line")
    size = path.stat().st_size
    if size > MAX_PROMPTS_FILE_BYTES:
        raise UsageError(f"prompts_file {path} has {size:,} bytes; at most {MAX_PROMPTS_FILE_BYTES:,} (one prompt a "
                         "line): split it into several runs")  # fmt: skip
    texts = [line for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    if not texts:
        raise UsageError(f"prompts_file {path} has no prompts (one per line)")
    check_count("prompts", len(texts), MAX_PROMPTS, "split them into several runs")
    return texts


def check_prompt_inputs(cfg: DictConfig) -> None:
    """Every check of the prompts that needs no model (the model's own checks follow once it is loaded)."""
    check_one_source(cfg)
    for key in ("prompts", "action"):
        value = cfg.get(key)
        if isinstance(value, ListConfig | list):
            if not value:
                raise UsageError(f"{key}=[] holds nothing to generate: give at least one, e.g. {key}=[...] or drop it")
            check_count(key, len(value), MAX_PROMPTS, "split them into several runs")
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
    parsed = [split_time(str(item)) for item in items]
    if all(seconds is None for _, seconds in parsed):
        return None
    untimed = [str(item) for item, (_, seconds) in zip(items, parsed, strict=True) if seconds is None]
    if untimed:
        raise UsageError(
            f"either every prompt ends in :<seconds> (one long motion through them) or none does (separate "
            f"samples); these have no time: {', '.join(repr(u) for u in untimed)}"
        )
    check_count("timed prompts", len(parsed), MAX_SEGMENTS, "make several long motions")
    check_long_seconds([seconds for _, seconds in parsed])
    return parsed


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
