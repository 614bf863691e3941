"""Compositional multi-action datasets built from a prepared dataset's real single-action clips.

    python -m motiondiff.data.compositional.dataset out=data/bandai_mini_compositional [src=data/bandai_mini] [seed=0]
        [train=64] [val=16] [test=64] [transition_s=0.4] [max_frames=196] [force=true]

Each sequence joins 2-3 real clips of ONE split (train with train, test with test) with `compositional_join`, and
joins their GENERATED captions ("a person walks, then waves both hands, and then bows."). Each sequence draws a
length (train/val: k x 1.5 s to `max_frames`; test: 150 frames to `max_frames`) and the longest clips are cropped to
their most active window to meet it; a cropped clip's caption is generated anew from its labels and what the window
measurably does (`motiondiff.data.preparing.captions`), an uncropped one keeps its own.
The test split is GuidedMotion's complex-motion subset: >= 3 local actions (action nodes of `parse_caption`) and
>= 150 frames. Every joined caption must parse to at least one action node inside each clip's part of the sentence;
one that does not is dropped (a sequence left without captions is drawn again). Output: the npz layout of
`motiondiff.data.formats.prepared` plus per-segment arrays (see SEGMENT_ARRAYS), Mean/Std, meta.json, report.json,
README.md and the source's LICENSE.
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.data.compositional.join import Part, join_captions, join_parts, place_canonically
from motiondiff.data.compositional.report import readme, seam_measures, split_report, summary
from motiondiff.data.formats.prepared import SPLITS, PreparedSplit, fill_derived, load_split, save_split
from motiondiff.data.preparing.captions import GENERATED_NOTE, generate_captions, measure
from motiondiff.data.preparing.processing import most_active_window
from motiondiff.data.preparing.staging import staged_folder
from motiondiff.data.preparing.writer import PrepareError, check_output
from motiondiff.data.representations.hml_features import canonicalize_joints, mean_std
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.paths import REPO_DIR as repo

COMPLEX_MIN_ACTIONS = 3  # GuidedMotion's complex-motion subset: >= 3 local actions ...
COMPLEX_MIN_FRAMES = 150  # ... and >= 150 frames
MIN_PART_FRAMES = 30  # 1.5 s: shorter windows of a wave or a bow no longer show the action
TURN_LABEL_MIN_DEGREES = 45  # a cropped walk-turn-* window must still turn that way, or its label would lie
# A transition may move no joint faster than this many times the joined clips' median fastest-joint speed: 0.4 s
# between very different poses (both hands up -> a bow) would otherwise swing a wrist at 4-5 m/s out of stillness.
MAX_SEAM_RATIO = 6.0
# A cross-fade cannot step: between two standing clips a change of stance slides the feet (a 0.75 m slash lunge ->
# a 0.25 m wave stance slides 38 cm in 0.4 s). Longer slides than this are refused.
MAX_STANDING_FOOT_SLIDE = 0.25  # metres
SEGMENT_ARRAYS = """segment_offsets (C+1) -> per segment: segment_source_ids, segment_source_frames [start, stop)
in the source clip, segment_frames [start, stop) in the sequence (neighbours share transition_frames),
segment_captions (the clip's caption that captions[0] joins), segment_content / segment_style (label ids);
content/style/action of a sequence = its first segment's (kept so the layout loads: the sets are for text
conditioning)."""


@dataclass(frozen=True)
class Rules:
    parts: tuple[int, ...]  # how many clips a sequence joins (drawn uniformly)
    min_frames: int | None  # None: k * MIN_PART_FRAMES - (k-1) * transition
    min_actions: int = 1  # action nodes of the first caption


RULES = {
    "train": Rules(parts=(2, 3), min_frames=None),
    "val": Rules(parts=(2, 3), min_frames=None),
    "test": Rules(parts=(3,), min_frames=COMPLEX_MIN_FRAMES, min_actions=COMPLEX_MIN_ACTIONS),
}


@dataclass
class Sequence:
    indices: list[int]  # source clips (indices into the split)
    windows: list[tuple[int, int]]  # [start, stop) of each source clip
    frames: list[tuple[int, int]]  # [start, stop) of each part in the sequence
    captions: list[str]  # joined captions, the labels-only phrasing first
    part_captions: list[str]  # each part's caption inside captions[0]
    actions: list[int]  # action nodes per part in captions[0]
    joints: np.ndarray
    rotations: np.ndarray
    root: np.ndarray
    seams: list[dict]  # compositional_report.seam_measures


# ---- planning: which clips, which windows ------------------------------------------------------------------------
def allocate(lengths: list[int], target: int, transition: int) -> list[int]:
    """Window lengths whose join has `target` frames (or all of each clip when they are too short): the longest
    windows are shortened first, so parts end up about equally long; none below MIN_PART_FRAMES."""
    sizes = list(lengths)
    excess = sum(sizes) - (len(sizes) - 1) * transition - target
    while excess > 0:
        k = int(np.argmax(sizes))
        if sizes[k] <= MIN_PART_FRAMES:
            break
        sizes[k] -= 1
        excess -= 1
    return sizes


def plan(rng: np.random.Generator, data: PreparedSplit, rules: Rules, transition: int, max_frames: int):
    """(clip indices, windows) of one random sequence, or which rule the draw breaks."""
    k = int(rng.choice(rules.parts))
    idx = [int(i) for i in rng.choice(data.num_clips, size=k, replace=False)]
    contents = [data.label("content", i) for i in idx]
    if any(a == b for a, b in zip(contents, contents[1:], strict=False)):
        return "the same action twice in a row"  # "walks, then walks" says nothing new
    lo = rules.min_frames or k * MIN_PART_FRAMES - (k - 1) * transition
    target = int(rng.integers(lo, max_frames + 1))
    sizes = allocate([int(data.arrays["lengths"][i]) for i in idx], target, transition)
    total = sum(sizes) - (k - 1) * transition
    if total < lo or total > max_frames or min(sizes) < 2 * transition + 1:
        return f"the clips are too short for {lo} frames"
    windows = []
    for i, n in zip(idx, sizes, strict=True):
        start, stop = most_active_window(data.arrays["joints"][data.clip_slice(i)], n)
        windows.append((start, stop))
    return idx, windows


# ---- captions ------------------------------------------------------------------------------------------------------
def part_captions(data: PreparedSplit, i: int, window: tuple[int, int], seed: int) -> list[str] | None:
    """The clip's own generated captions, or for a cropped window new ones of what that window does (None when a
    cropped walk-turn-* window no longer turns that way: its label phrase would be false)."""
    n = int(data.arrays["lengths"][i])
    if window == (0, n):
        return data.captions(i)
    joints = canonicalize_joints(data.arrays["joints"][data.clip_slice(i)][window[0] : window[1]])
    facts = measure(joints, float(data.arrays["fps"]))
    content = data.label("content", i)
    if content.startswith("walk-turn-"):
        side = 1 if content.endswith("left") else -1
        if side * facts.turn_degrees < TURN_LABEL_MIN_DEGREES:
            return None
    key = f"{seed}:{data.arrays['ids'][i]}:{window[0]}:{window[1]}".encode()
    rng = np.random.default_rng(list(key))
    return generate_captions(content, data.label("style", i), facts, rng)


def caption_variants(per_part: list[list[str]]) -> list[tuple[str, list[tuple[int, int]], list[str]]]:
    """Joined phrasings: labels only (each clip's first caption), with measured details (its second of three),
    measured only (its last). Returns (text, character span of each part, the parts), duplicates left out."""
    out, seen = [], set()
    for pick in (lambda c: c[0], lambda c: c[1] if len(c) == 3 else c[0], lambda c: c[-1]):
        parts = [pick(c) for c in per_part]
        text, spans = join_captions(parts)
        if text not in seen:
            seen.add(text)
            out.append((text, spans, parts))
    return out


def actions_per_part(text: str, spans: list[tuple[int, int]]) -> list[int]:
    """Action nodes of `parse_caption(text)` whose verb lies in each part's character span."""
    from motiondiff.text.parse import parse_caption  # spaCy loads only when captions are checked

    graph = parse_caption(text)
    starts = np.cumsum([0] + [len(w) + len(s) for w, s in zip(graph.words, graph.whitespace, strict=True)])
    heads = [int(starts[graph.nodes[a].head]) for a in graph.action_ids()]
    return [sum(s <= h < e for h in heads) for s, e in spans]


# ---- one sequence and one split --------------------------------------------------------------------------------
def compose(data: PreparedSplit, idx: list[int], windows, transition: int, seed: int) -> Sequence | str:
    """The joined, canonically placed sequence with its checked captions, or why it was not made."""
    per_part = [part_captions(data, i, w, seed) for i, w in zip(idx, windows, strict=True)]
    if any(c is None for c in per_part):
        return "a cropped walk-turn window does not turn"
    kept = []
    for text, spans, parts in caption_variants(per_part):
        counts = actions_per_part(text, spans)
        if min(counts) >= 1:
            kept.append((text, parts, counts))
    if not kept:
        return "no joined caption has an action node in every clip's part"
    a = data.arrays
    parts = []
    for i, (s, e) in zip(idx, windows, strict=True):
        sl = data.clip_slice(i)
        parts.append(Part(a["joints"][sl][s:e], a["native_rotations"][sl][s:e], a["native_root"][sl][s:e]))
    offsets = a["native_offsets"][idx[0]].astype(np.float64)
    joined = place_canonically(join_parts(parts, transition), offsets, data.rig().with_offsets(offsets))
    seams = seam_measures(joined.joints, [p.joints for p in parts], joined.frames, transition, float(a["fps"]))
    if max(m["to_median"] for m in seams) > MAX_SEAM_RATIO:
        return f"a transition moves a joint faster than {MAX_SEAM_RATIO:g}x the clips' median speed"
    if any(m["standing"] and m["foot_slide"] > MAX_STANDING_FOOT_SLIDE for m in seams):
        return f"a foot slides more than {MAX_STANDING_FOOT_SLIDE:g} m between standing clips"
    return Sequence(idx, list(windows), joined.frames, [t for t, _, _ in kept], kept[0][1], kept[0][2],
                    joined.joints, joined.rotations, joined.root, seams)  # fmt: skip


def build_split(data: PreparedSplit, count: int, rules: Rules, transition: int, max_frames: int, seed: int,
                split_index: int) -> tuple[list[Sequence], Counter]:  # fmt: skip
    """`count` distinct sequences of one split's clips, and how many draws were refused for what reason; the same
    arguments give the same sequences."""
    rng = np.random.default_rng([seed, split_index])
    out, used, refused = [], set(), Counter()
    for _ in range(200 * count):
        if len(out) == count:
            return out, refused
        drawn = plan(rng, data, rules, transition, max_frames)
        if isinstance(drawn, str) or tuple(drawn[0]) in used:
            refused[drawn if isinstance(drawn, str) else "the same clips in the same order again"] += 1
            continue
        seq = compose(data, drawn[0], drawn[1], transition, seed)
        if isinstance(seq, str) or sum(seq.actions) < rules.min_actions:
            refused[seq if isinstance(seq, str) else f"fewer than {rules.min_actions} action nodes"] += 1
            continue
        used.add(tuple(drawn[0]))
        out.append(seq)
    raise ValueError(f"only {len(out)} of {count} sequences could be drawn from {data.num_clips} clips; ask for fewer")


def split_arrays(seqs: list[Sequence], data: PreparedSplit, split: str, transition: int) -> dict[str, np.ndarray]:
    """The prepared npz layout (motiondiff.data.formats.prepared), labels as the source's, plus SEGMENT_ARRAYS."""
    a = data.arrays
    lengths = np.array([len(s.joints) for s in seqs])
    first = [s.indices[0] for s in seqs]
    seg_idx = [i for s in seqs for i in s.indices]
    arrays = {
        "ids": np.array([f"compositional_{split}_{k:03d}" for k in range(len(seqs))]),
        "lengths": lengths,
        "frame_offsets": np.concatenate([[0], np.cumsum(lengths)]),
        "joints": np.concatenate([s.joints for s in seqs]).astype(np.float32),
        "native_rotations": np.concatenate([s.rotations for s in seqs]).astype(np.float32),
        "native_root": np.concatenate([s.root for s in seqs]).astype(np.float32),
        "native_joint_names": a["native_joint_names"],
        "native_parents": a["native_parents"],
        "native_offsets": a["native_offsets"][first],
        "captions": np.array([t for s in seqs for t in s.captions]),
        "caption_offsets": np.concatenate([[0], np.cumsum([len(s.captions) for s in seqs])]),
        "captions_generated": np.array(True),
        "fps": a["fps"],
        "segment_offsets": np.concatenate([[0], np.cumsum([len(s.indices) for s in seqs])]),
        "segment_source_ids": a["ids"][seg_idx],
        "segment_source_frames": np.array([w for s in seqs for w in s.windows]),
        "segment_frames": np.array([f for s in seqs for f in s.frames]),
        "segment_captions": np.array([c for s in seqs for c in s.part_captions]),
        "segment_content": a["content"][seg_idx],
        "segment_style": a["style"][seg_idx],
        "transition_frames": np.array(transition),
    }
    for kind in ("dataset", "content", "style", "action"):
        arrays[kind], arrays[f"{kind}_names"] = a[kind][first], a[f"{kind}_names"]
    fill_derived(arrays)
    return arrays


# ---- the dataset folder ------------------------------------------------------------------------------------------
def build(src: str | Path, out: str | Path, counts: dict[str, int], seed: int = 0, transition_s: float = 0.4,
          max_frames: int = 196, force: bool = False) -> dict:  # fmt: skip
    """Write the compositional dataset into `out`; returns its report (also saved as report.json)."""
    src, out = Path(src), Path(out)
    check_output(out, force)
    sources = {s: load_split(src, s) for s in SPLITS}
    fps = float(sources["train"].arrays["fps"])
    transition = int(round(transition_s * fps))
    arrays, report = {}, {"splits": {}}
    for k, split in enumerate(SPLITS):
        seqs, refused = build_split(sources[split], counts[split], RULES[split], transition, max_frames, seed, k)
        arrays[split] = split_arrays(seqs, sources[split], split, transition)
        report["splits"][split] = split_report(seqs, sources[split], arrays[split], transition, fps)
        report["splits"][split]["draws_refused"] = dict(refused.most_common())
    # the dataset config trains on the source's single clips and these sequences together: statistics of both
    mean, std = mean_std(np.concatenate([sources["train"].arrays["features"], arrays["train"]["features"]]))
    with staged_folder(out, force) as build:  # a killed run leaves the old dataset or the new one, never a mixture
        for split in SPLITS:
            save_split(build / f"{split}.npz", arrays[split], compact=True)
        report["npz_bytes"] = {s: (build / f"{s}.npz").stat().st_size for s in SPLITS}
        for name, arr in (("Mean.npy", mean), ("Std.npy", std)):
            atomic_write(build / name, lambda tmp, a=arr: np.save(tmp, a), suffix=".npy")
        options = {"src": src.name, "seed": seed, "transition_s": transition_s, "transition_frames": transition,
                   "max_frames": max_frames, "max_seam_ratio": MAX_SEAM_RATIO,
                   "max_standing_foot_slide_m": MAX_STANDING_FOOT_SLIDE, "counts": counts}  # fmt: skip
        command = "python -m motiondiff.data.compositional.dataset " + " ".join(
            [f"src=data/{src.name}", f"out=data/{out.name}", f"seed={seed}", f"transition_s={transition_s}",
             f"max_frames={max_frames}"] + [f"{s}={counts[s]}" for s in SPLITS])  # fmt: skip
        src_meta = sources["train"].meta
        report.update(options=options, command=command)
        meta = {
            "clips": {s: len(arrays[s]["ids"]) for s in SPLITS},
            "frames": {s: int(arrays[s]["lengths"].sum()) for s in SPLITS},
            "labels": src_meta["labels"],
            "fps": fps,
            "joint_map": src_meta.get("joint_map", "bandai->smpl22"),
            "captions": f"{GENERATED_NOTE}; clips' generated captions joined with ', then' / ', and then'",
            "license": src_meta.get("license", ""),
            "compositional": {**options, "command": command, "segments": SEGMENT_ARRAYS.replace("\n", " "),
                              "mean_std": f"train features of {src.name} and of this dataset together",
                              "test": f">= {COMPLEX_MIN_ACTIONS} local actions, >= {COMPLEX_MIN_FRAMES} frames"},
        }  # fmt: skip
        if (src / "LICENSE").is_file():
            text = (src / "LICENSE").read_text()
            atomic_write(build / "LICENSE", lambda tmp: Path(tmp).write_text(text), suffix="")
        atomic_write(
            build / "README.md", lambda tmp: Path(tmp).write_text(readme(out.name, report, meta)), suffix=".md"
        )
        # meta.json last: its presence marks a complete dataset (check_output)
        for name, obj in (("report.json", report), ("meta.json", meta)):
            atomic_write(build / name, lambda tmp, o=obj: Path(tmp).write_text(json.dumps(o, indent=1)), suffix=".json")
    return report


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    bad = [a for a in argv if "=" not in a]
    args = dict(a.split("=", 1) for a in argv if "=" in a)
    known = {"out", "src", "seed", "train", "val", "test", "transition_s", "max_frames", "force", "summary"}
    if bad or "out" not in args or set(args) - known:
        usage = "\n".join(__doc__.strip().splitlines()[2:4])
        print(
            f"usage:\n{usage}\nnot understood: {bad + sorted(set(args) - known) or 'out= is missing'}", file=sys.stderr
        )
        return 2
    counts = {"train": int(args.get("train", 64)), "val": int(args.get("val", 16)), "test": int(args.get("test", 64))}

    try:
        report = build(args.get("src", repo / "data" / "bandai_mini"), args["out"], counts, int(args.get("seed", 0)),
                       float(args.get("transition_s", 0.4)), int(args.get("max_frames", 196)),
                       args.get("force", "false").lower() in ("1", "true", "yes"))  # fmt: skip
    except (PrepareError, ValueError) as err:  # an existing dataset without force=true, too many sequences asked
        print("error: " + str(err).replace("--out ", "out=").replace("--force", "force=true"), file=sys.stderr)
        return 2
    text = summary(report)
    if "summary" in args:
        Path(args["summary"]).parent.mkdir(parents=True, exist_ok=True)
        atomic_write(args["summary"], lambda tmp: Path(tmp).write_text(text), suffix=".md")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
