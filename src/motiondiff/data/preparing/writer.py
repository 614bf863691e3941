"""Writing a prepared dataset (see motiondiff.data.formats.prepared for the format), shared by every source's preparation
(motiondiff.data.preparing.prepare for Bandai Namco, prepare_bvh for BVH folders, compositional for joined clips).

Clips are processed in worker processes, split, captioned and written into the folder being built, a temporary
sibling of the output that replaces it in one swap (motiondiff.data.preparing.staging), so an interrupted run leaves
either the previous dataset or the new one, never a mixture.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from collections.abc import Mapping
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
from tqdm import tqdm

from motiondiff.data.formats.archive import Source, SourceError
from motiondiff.data.formats.bvh import BVHError, parse_bvh
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import SPLITS, fill_derived, save_split
from motiondiff.data.formats.up_axis import FORCE_HINT, bvh_up_axis
from motiondiff.data.preparing.captions import GENERATED_NOTE, generate_captions, normalise_caption
from motiondiff.data.preparing.processing import (
    TARGET_FPS,
    ClipError,
    ProcessedClip,
    most_active_window,
    process_motion,
)
from motiondiff.data.preparing.splits import rare_to_train, stratified_split, stratified_subset
from motiondiff.data.representations.hml_features import mean_std
from motiondiff.data.sources import bandai
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.file_kinds import NAME_MAX, over_long_name


class PrepareError(ValueError):
    """A problem with the command's inputs or output folder, found before any work is done."""


@dataclass(frozen=True)
class PrepareOptions:
    """The options every source's preparation takes (the ``**options`` of prepare_bandai and prepare_bvh), declared
    once. `per_group`: keep at most N clips per dataset x content x style (a subset); `max_frames`: crop longer
    clips to their most active N frames (20 fps); `compact`: leave out derived arrays (recomputed on load); `seed`:
    of the subset, split and captions; `workers`: processes (None: up to 4); `force`: replace a prepared dataset
    already in the output; `progress`: show a progress bar."""

    per_group: int | None = None
    max_frames: int | None = None
    compact: bool = False
    seed: int = 0
    workers: int | None = None
    force: bool = False
    progress: bool = True

    @classmethod
    def of(cls, caller: str, options: Mapping) -> PrepareOptions:
        """The `options` given to `caller`; TypeError naming any it does not take."""
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(options) - set(names))
        if unknown:
            raise TypeError(f"{caller}() got unexpected keyword argument(s) {', '.join(unknown)}; its preparation "
                            f"options are {', '.join(names)}")  # fmt: skip
        return cls(**options)

    def __post_init__(self) -> None:
        for name, low in (("per_group", 1), ("max_frames", 2), ("workers", 1)):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < low):
                flag = "--" + name.replace("_", "-")
                raise PrepareError(f"{flag} {value!r}: must be a whole number >= {low} (or left out)")

    def saved(self) -> dict:
        """The ones that shape the data, saved in report.json (workers, force and progress do not)."""
        return {"compact": self.compact, "per_group": self.per_group, "max_frames": self.max_frames, "seed": self.seed}


@dataclass
class Job:
    source: str
    bvh_name: str
    name: str
    max_frames: int | None
    up_axis: str = "y"  # "auto": detected per clip (`bvh_up_axis`), else forced; Bandai's files are Y-up


# ---- per-clip work (runs in worker processes) ----------------------------------------------------------------
_SOURCES: dict[str, Source] = {}
_JOINT_MAP: JointMap | None = None


def _init_worker(joint_map: JointMap) -> None:
    """Each process opens its own sources: a forked worker must not read through a zip handle inherited from its
    parent (the file offset is shared, and two readers corrupt each other's inflating: "invalid distance")."""
    global _JOINT_MAP
    _JOINT_MAP = joint_map
    _SOURCES.clear()


def _process(job: Job) -> ProcessedClip | str:
    """The processed clip, or the reason it cannot be used."""
    try:
        source = _SOURCES.get(job.source) or _SOURCES.setdefault(job.source, Source(job.source))
        motion = parse_bvh(source.read_text(job.bvh_name), source=job.bvh_name)
        lacking = sorted(_JOINT_MAP.source_joints() - set(motion.joint_names))
        if lacking:
            return f"its skeleton lacks {', '.join(lacking)}, which the joint map {_JOINT_MAP.source} reads"
        up = bvh_up_axis(motion, _JOINT_MAP, up_axis=job.up_axis, warn=False)
        if not up.decided:
            return f"cannot tell its up axis ({up.reason}); {FORCE_HINT.replace('up_axis=', '--up-axis ')}"
        turn = None if up.axis == "+y" else up.matrix
        clip = process_motion(motion, _JOINT_MAP, turn=turn)
        if job.max_frames is not None and len(clip.joints) > job.max_frames:
            window = most_active_window(clip.joints, job.max_frames)
            clip = process_motion(motion, _JOINT_MAP, window=window, turn=turn)
        clip.up_axis = up.axis
        return clip
    except (BVHError, ClipError, SourceError) as err:
        return str(err)


# ---- the command -------------------------------------------------------------------------------------------------
# what a prepared dataset folder holds: a user's files of these names are replaced only with --force
DATASET_FILES = ("meta.json", "report.json", "README.md", "LICENSE", "joint_map.json", "Mean.npy", "Std.npy",
                 *(f"{s}.npz" for s in SPLITS))  # fmt: skip


def check_output(out: Path, force: bool) -> None:
    """``out`` can take a new dataset: a folder (or a path to one) with names the file system takes, and without
    a dataset or files a dataset would replace, unless ``force``."""
    long = over_long_name(out)
    if long is not None:
        raise PrepareError(f"--out: the folder name {long[:24]}... has {len(os.fsencode(long))} bytes, more than the "
                           f"file system's {NAME_MAX}; choose a shorter name")  # fmt: skip
    if out.exists() and not out.is_dir():
        raise PrepareError(f"--out {out} is a file, not a folder; choose a folder path (it is created if missing)")
    if out.is_dir() and (out / "meta.json").exists() and not force:
        raise PrepareError(f"--out {out} already holds a prepared dataset; pass --force to replace it")
    clash = [name for name in DATASET_FILES if (out / name).exists()] if out.is_dir() and not force else []
    if clash:
        raise PrepareError(f"--out {out} holds {', '.join(clash)}, which the new dataset would replace: choose a new "
                           "or empty folder, or pass --force to replace them")  # fmt: skip
    probe = out if out.is_dir() else next((p for p in out.parents if p.exists()), Path("."))
    if not probe.is_dir():
        raise PrepareError(f"cannot create --out {out}: {probe} is a file; choose a folder path")
    if not os.access(probe, os.W_OK):
        raise PrepareError(f"cannot write to {probe}; choose an --out folder you can write to")


def process_and_write(
    clips, skipped, sources, out: Path, joint_map: JointMap, options: dict, meta: dict, workers=None, progress=True
) -> dict:
    """Shared by every source: subset, process in workers, split, write the npz files, Mean/Std, report.json and
    meta.json (`meta` adds to it). `clips` have name, dataset, content, style, source, bvh_name and optionally
    `captions` (human-written; None = generate). `options` holds compact, per_group, max_frames, seed and any
    source-specific settings, all saved in the report. Returns the report."""
    per_group, max_frames, compact, seed = (options[k] for k in ("per_group", "max_frames", "compact", "seed"))
    skipped = list(skipped)
    groups = [(c.dataset, c.content, c.style) for c in clips]
    if per_group is not None:
        keep = stratified_subset([c.name for c in clips], groups, per_group, seed)
        clips, groups = [clips[i] for i in keep], [groups[i] for i in keep]

    up_axis = str(options.get("up_axis") or "y")
    jobs = [Job(str(c.source.path), c.bvh_name, c.name, max_frames, up_axis) for c in clips]
    results = _run(jobs, joint_map, workers, progress)
    kept = []
    for clip, group, res in zip(clips, groups, results, strict=True):
        if isinstance(res, str):
            skipped.append((clip.name, res))
        else:
            kept.append((clip, group, res))
    kept, skipped = _same_skeleton(kept, skipped)
    if not kept:
        reasons = "; ".join(f"{n}: {r}" for n, r in skipped[:5])
        raise PrepareError(f"none of the {len(clips)} clip(s) could be used ({reasons})")
    split_of = stratified_split([c.name for c, _, _ in kept], [g for _, g, _ in kept], seed)
    split_of = rare_to_train(split_of, [c.content for c, _, _ in kept], int(options.get("rare_to_train") or 0))

    labels = {k: sorted({getattr(c, k) for c, _, _ in kept}) for k in ("dataset", "content", "style")}
    out.mkdir(parents=True, exist_ok=True)
    per_split = {s: [(c, r) for (c, _, r), sp in zip(kept, split_of, strict=True) if sp == s] for s in SPLITS}
    variants = int(options.get("caption_variants") or 0)
    held_out = load_held_out(options.get("held_out") or [])
    wording = options.get("caption_wording") or "plain"
    arrays = {s: _split_arrays(per_split[s], labels, seed, variants, held_out, wording) for s in SPLITS}
    mean, std = mean_std(arrays["train"]["features"])
    for s in SPLITS:
        save_split(out / f"{s}.npz", arrays[s], compact=compact)
    for name, arr in (("Mean.npy", mean), ("Std.npy", std)):
        atomic_write(out / name, lambda tmp, a=arr: np.save(tmp, a), suffix=".npy")
    report = _report(per_split, skipped, sources, joint_map, options)
    meta = {**{k: v for k, v in report.items() if k not in ("skipped",)}, "labels": labels, "fps": TARGET_FPS,
            **meta}  # fmt: skip
    # meta.json last: its presence marks a complete dataset (check_output, ensure_prepared_bvh)
    for name, obj in (("report.json", report), ("meta.json", meta)):
        atomic_write(out / name, lambda tmp, o=obj: Path(tmp).write_text(json.dumps(o, indent=1)), suffix=".json")
    return report


def copy_license(out: Path | None, sources) -> str | None:
    """The data's license travels with every copy of it (CC BY-NC 4.0 requires the attribution): the first
    LICENSE file at the top of a source is copied into `out` (None: only looked for); returns where it was."""
    for path in sources:
        src = Source(path)
        for name in ("LICENSE", "LICENSE.txt", "LICENSE.md", "license.txt"):
            if src.exists(name):
                if out is not None:
                    text = src.read_text(name)
                    atomic_write(out / "LICENSE", lambda tmp, t=text: Path(tmp).write_text(t), suffix="")
                return f"{Path(path).name}/{name}"
    return None


def _write_license_and_readme(out: Path, sources, report: dict, name: str) -> None:
    """LICENSE and README.md into ``out`` (the folder being built) for the dataset called ``name``."""
    copy_license(out, sources)
    opts = report["options"]
    cmd = "python -m motiondiff.data.preparing.prepare bandai " + " ".join(f"--src {Path(p).name}" for p in sources)
    cmd += f" --out {name}"
    cmd += "".join(f" --{k.replace('_', '-')} {opts[k]}" for k in ("per_group", "max_frames") if opts[k] is not None)
    cmd += " --compact" * bool(opts["compact"]) + f" --seed {opts['seed']}"
    clips = report["clips"]
    text = f"""# {name}

Real motion capture prepared by motiondiff from the Bandai Namco Research Motion Dataset 1 and 2.

**Attribution:** {bandai.ATTRIBUTION}. The license is in [LICENSE](LICENSE) (non-commercial use only).

- clips: {sum(clips.values())} (train {clips["train"]}, val {clips["val"]}, test {clips["test"]}), 20 fps, metres, y up
- captions: **generated** from the labels and from what each motion measurably does; {GENERATED_NOTE}
- format: see `motiondiff.data.formats.prepared`; counts per label and every skipped clip: report.json

Rebuilt with (from the folder holding the zips; in a motiondiff checkout `make data` runs it):

    {cmd}
"""
    atomic_write(out / "README.md", lambda tmp: Path(tmp).write_text(text), suffix=".md")


def _run(jobs: list[Job], joint_map: JointMap, workers: int | None, progress: bool) -> list:
    workers = workers if workers is not None else min(4, os.cpu_count() or 1)
    # the bar is closed however the work ends (Ctrl-C, SIGTERM): its line is finished before any error line
    with tqdm(total=len(jobs), desc="prepare", unit="clip", disable=not progress) as bar:
        if workers <= 1:
            _init_worker(joint_map)
            try:
                return [_tick(bar, _process(j)) for j in jobs]
            finally:
                _SOURCES.clear()  # no zip stays open in this process (a later pool would fork it)
        with ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(joint_map,)) as pool:
            return [_tick(bar, r) for r in pool.map(_process, jobs, chunksize=8)]


def _tick(bar, result):
    bar.update()
    return result


def _same_skeleton(kept, skipped):
    """One joint hierarchy per dataset (bone lengths are stored per clip): clips with another one are skipped."""
    if not kept:
        return kept, skipped
    ref = kept[0][2].native
    same = [k for k in kept if k[2].native.same_topology(ref)]
    skipped += [
        (c.name, f"its joints/hierarchy differ from {kept[0][0].name}'s")
        for c, _, r in kept
        if not r.native.same_topology(ref)
    ]
    return same, skipped


def caption_seed(seed: int, name: str, variants: int) -> int:
    """The caption generator's seed for one clip. Without variants: the first 8 bytes of "seed:name", the seed the
    embedded dataset was prepared with (it is the same for every clip; kept so `make data` rebuilds that data as
    committed); with variants: a hash of the whole string, so clips of one action and style get different words."""
    key = f"{seed}:{name}".encode()
    if not variants:
        return int.from_bytes(key[:8].ljust(8, b"\0"), "little")
    return int.from_bytes(hashlib.sha256(key).digest()[:8], "little")


def load_held_out(paths: list[str | Path]) -> frozenset[str]:
    """Normalised texts of held-out description files, which generated captions must not repeat."""
    texts = set()
    for path in paths:
        try:
            items = json.loads(Path(path).read_text())["descriptions"]
            texts |= {normalise_caption(d["text"]) for d in items}
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise PrepareError(f"--held-out {path}: not a descriptions file ({err!r}); it needs "
                               '{"descriptions": [{"text": ...}, ...]}') from None  # fmt: skip
    return frozenset(texts)


def _split_arrays(
    items: list[tuple[bandai.BandaiClip, ProcessedClip]],
    labels: dict,
    seed: int,
    variants: int = 0,
    held_out: frozenset[str] = frozenset(),
    wording: str = "plain",
) -> dict:
    if not items:
        raise PrepareError("a split came out empty: too few clips were selected (raise --per-group)")
    lengths = np.array([len(r.joints) for _, r in items])
    captions, generated = [], []
    for c, r in items:
        given = getattr(c, "captions", None)  # human-written captions of a labels file
        generated.append(not given)
        if given:
            captions.append(list(given))
            continue
        rng = np.random.default_rng(caption_seed(seed, c.name, variants))
        captions.append(generate_captions(c.content, c.style, r.facts, rng, variants, held_out, wording))
    native = items[0][1].native
    arrays = {
        "ids": np.array([c.name for c, _ in items]),
        "lengths": lengths,
        "frame_offsets": np.concatenate([[0], np.cumsum(lengths)]),
        "joints": np.concatenate([r.joints for _, r in items]),
        "native_rotations": np.concatenate([r.native_rotations for _, r in items]),
        "native_root": np.concatenate([r.native_root for _, r in items]),
        "native_joint_names": np.array(native.joint_names),
        "native_parents": native.parents,
        "native_offsets": np.stack([r.native.offsets for _, r in items]).astype(np.float32),
        "captions": np.array([t for caps in captions for t in caps]),
        "caption_offsets": np.concatenate([[0], np.cumsum([len(caps) for caps in captions])]),
        # one flag while all clips agree (the Bandai files), else one per clip
        "captions_generated": np.array(generated[0] if len(set(generated)) == 1 else generated),
        "fps": np.array(TARGET_FPS),
    }
    for kind in ("dataset", "content", "style"):
        arrays[kind] = np.array([labels[kind].index(getattr(c, kind)) for c, _ in items])
        arrays[f"{kind}_names"] = np.array(labels[kind])
    arrays["action"], arrays["action_names"] = arrays["content"], arrays["content_names"]
    fill_derived(arrays)  # features and native positions, exactly as loading a compact file recomputes them
    return arrays


def _report(per_split, skipped, sources, joint_map, options: dict) -> dict:
    def count(kind):
        return {s: dict(sorted(Counter(getattr(c, kind) for c, _ in per_split[s]).items())) for s in SPLITS}

    return {
        "sources": [str(s) for s in sources],
        "clips": {s: len(per_split[s]) for s in SPLITS},
        "frames": {s: int(sum(len(r.joints) for _, r in per_split[s])) for s in SPLITS},
        "per_dataset": count("dataset"),
        "per_content": count("content"),
        "per_style": count("style"),
        "skipped": [{"clip": n, "reason": r} for n, r in skipped],
        "up_axes": dict(sorted(Counter(r.up_axis for s in SPLITS for _, r in per_split[s]).items())),
        "joint_map": f"{joint_map.source}->{joint_map.target}",
        "options": dict(options),
    }
