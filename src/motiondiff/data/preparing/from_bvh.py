"""Any folder or zip of BVH files (100STYLE, Bandai, CMU, Mixamo exports, ...) -> a prepared dataset folder.

    python -m motiondiff.data.preparing.prepare bvh --src 100STYLE.zip --out data/100style
    python -m motiondiff.data.preparing.prepare bvh --src mocap/ --labels labels.csv --joint-map auto --out data/mocap

Labels file (optional): a CSV with a header row. `file` is required: the path relative to the source root
("Walks/walk_01.bvh", after the one top folder a zip may wrap everything in) or the bare file name when that is
unique. Optional columns: `action`, `style`, `caption` (human-written captions, several separated by "|").
Unknown columns, rows naming no file or several files, and files listed twice are one error before any work.

Files the labels file does not label (or leaves a cell empty for) get labels from their path:
- 100STYLE layout `<Style>/<Style>_<Code>.bvh` (or `<Style>_<Code>.bvh` with a 100STYLE code): style = Style,
  action = the code (FW walk, FR run, BW walk-back, BR run-back, SW sidestep-walk, SR sidestep-run, ID idle,
  TR1-3 transition; other codes as written);
- files in sub-folders: action = the parent folder's name, when the source has more than one such folder (a
  folder that holds every file, as Bandai's data/, says nothing about any of them);
- otherwise action and style "unlabelled".
Labels are normalised to lower-case-with-hyphens ("ArmsAboveHead" -> "arms-above-head"). Captions of a labels
file are human-written (captions_generated False for those clips); every other clip gets GENERATED captions from
its labels and measured motion (motiondiff.data.preparing.captions), flagged True.

Joint map: `auto` reads the first file's joint names (JointMap.infer; units guessed from the leg length, or
--units-to-metres) and saves the result as joint_map.json in the output; or a shipped map name / a JSON file.
Clips whose joints/hierarchy differ from the first usable clip's are skipped with the reason.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import re
from dataclasses import asdict, dataclass, replace
from pathlib import Path, PurePosixPath

from motiondiff.data.formats.archive import Source, SourceError
from motiondiff.data.formats.bvh import BVHError, parse_bvh
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.up_axis import parse_up_axis
from motiondiff.data.preparing.captions import GENERATED_NOTE
from motiondiff.data.preparing.staging import staged_folder
from motiondiff.data.preparing.writer import PrepareError, PrepareOptions, check_output, copy_license, process_and_write
from motiondiff.runtime.atomic import atomic_write

COLUMNS = ("file", "action", "style", "caption")
UNLABELLED = "unlabelled"
STYLE100_CODES = {"FW": "walk", "FR": "run", "BW": "walk-back", "BR": "run-back", "SW": "sidestep-walk",
                  "SR": "sidestep-run", "ID": "idle", "TR1": "transition", "TR2": "transition",
                  "TR3": "transition"}  # fmt: skip


@dataclass
class BVHClip:
    name: str  # unique id: the path without .bvh (prefixed by the source's name when there are several)
    source: Source
    bvh_name: str
    dataset: str  # the source's name (zip or folder without extension)
    content: str  # the action
    style: str
    captions: tuple[str, ...] | None = None  # human-written ones from the labels file


def normal_label(text: str) -> str:
    text = re.sub(r"([a-z0-9])([A-Z])", r"\1-\2", text.strip())
    return re.sub(r"[\s_\-]+", "-", text).strip("-").lower()


def path_labels(rel: str, folder_says: bool) -> tuple[str, str]:
    """(action, style) read from a file's path (see the module docstring)."""
    path = PurePosixPath(rel)
    parent = path.parent.name
    if parent and path.stem.lower().startswith(parent.lower() + "_"):
        code = path.stem[len(parent) + 1 :]
        return STYLE100_CODES.get(code.upper(), normal_label(code)), normal_label(parent)
    m = re.fullmatch(r"(.+)_(" + "|".join(STYLE100_CODES) + ")", path.stem, re.I)
    if not parent and m:
        return STYLE100_CODES[m.group(2).upper()], normal_label(m.group(1))
    if parent and folder_says:
        return normal_label(parent), UNLABELLED
    return UNLABELLED, UNLABELLED


def list_files(sources: list[Source]) -> list[tuple[Source, str, str]]:
    """(source, bvh name, clip id) of every .bvh file, in a stable order. Raises PrepareError when there is none."""
    datasets = [s.path.name[: -len(s.path.suffix)] if s.path.suffix else s.path.name for s in sources]
    if len(set(datasets)) < len(datasets):
        raise PrepareError(f"two sources have the same name ({', '.join(datasets)}); rename one")
    files = []
    for src, dataset in zip(sources, datasets, strict=True):
        bvhs = [n for n in src.names() if n.lower().endswith(".bvh") and not _hidden(n)]
        if not bvhs:
            raise PrepareError(f"{src.path}: no .bvh files in it; pass a folder or zip that holds BVH files")
        for n in bvhs:
            clip_id = n[:-4] if len(sources) == 1 else f"{dataset}/{n[:-4]}"
            files.append((src, n, clip_id))
    return files


def _hidden(name: str) -> bool:
    return any(p.startswith((".", "__MACOSX")) for p in PurePosixPath(name).parts)


def read_labels(path: str | Path, files: list[tuple[Source, str, str]]) -> dict[str, dict]:
    """Clip id -> {action, style, captions} from a labels CSV; every problem at once in one PrepareError."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as err:
        raise PrepareError(f"--labels {path}: cannot read it ({err.strerror or err})") from None
    reader = csv.DictReader(io.StringIO(text))
    header = [(h or "").strip().lower() for h in (reader.fieldnames or [])]
    unknown = [h for h in header if h not in COLUMNS]
    if "file" not in header or unknown:
        raise PrepareError(
            f"--labels {path}: the header must name a `file` column and may add {', '.join(COLUMNS[1:])}; "
            + (f"unknown column(s): {', '.join(unknown)}" if unknown else f"found: {', '.join(header) or 'none'}")
        )
    reader.fieldnames = header
    by_path = {n.lower(): cid for _, n, cid in files} | {cid.lower(): cid for _, _, cid in files}
    by_name: dict[str, list[str]] = {}
    for _, n, cid in files:
        by_name.setdefault(PurePosixPath(n).name.lower(), []).append(cid)
    labels, errors = {}, []
    for row_no, row in enumerate(reader, start=2):
        given = (row.get("file") or "").strip().replace("\\", "/").removeprefix("./")
        key = given.lower()
        hits = [by_path[key]] if key in by_path else by_name.get(key, [])
        if not hits and "/" in key:  # a path that includes the top folder the source strips
            hits = [by_path[k] for k in (key.split("/", 1)[1],) if k in by_path]
        if not given:
            errors.append(f"row {row_no}: empty `file`")
        elif not hits:
            errors.append(f"row {row_no}: no BVH file {given!r} in the sources")
        elif len(hits) > 1:
            errors.append(f"row {row_no}: {given!r} matches {', '.join(hits)}; give the path from the source root")
        elif hits[0] in labels:
            errors.append(f"row {row_no}: {given!r} is labelled twice")
        else:
            caps = tuple(c.strip() for c in (row.get("caption") or "").split("|") if c.strip())
            labels[hits[0]] = {"action": normal_label(row.get("action") or ""),
                               "style": normal_label(row.get("style") or ""), "captions": caps or None}  # fmt: skip
    if errors:
        shown = "\n  ".join(errors[:20]) + (f"\n  ... and {len(errors) - 20} more" if len(errors) > 20 else "")
        raise PrepareError(f"--labels {path}: {len(errors)} bad row(s), nothing was prepared:\n  {shown}")
    return labels


def make_clips(files, labels: dict[str, dict]) -> list[BVHClip]:
    folders: dict[Source, set[str]] = {}
    for src, n, _ in files:
        folders.setdefault(src, set()).add(str(PurePosixPath(n).parent))
    clips = []
    for src, n, cid in files:
        action, style = path_labels(n, len(folders[src] - {"."}) > 1)
        given = labels.get(cid, {})
        dataset = src.path.name[: -len(src.path.suffix)] if src.path.suffix else src.path.name
        clips.append(BVHClip(cid, src, n, dataset, given.get("action") or action, given.get("style") or style,
                             given.get("captions")))  # fmt: skip
    return clips


def resolve_joint_map(spec: str, files, units_to_metres: float | None) -> JointMap:
    """The map named by --joint-map; `auto` infers it from the first file that parses."""
    if spec != "auto":
        try:
            jm = JointMap.load(spec)
        except (FileNotFoundError, ValueError, KeyError) as err:
            raise PrepareError(f"--joint-map {spec}: {err}") from None
        return jm if units_to_metres is None else replace(jm, units_to_metres=float(units_to_metres))
    first_error = None
    for src, n, _ in files:
        try:
            motion = parse_bvh(src.read_text(n), source=n)
        except (BVHError, SourceError) as err:
            first_error = first_error or err
            continue  # the worker reports it with the reason
        try:
            return JointMap.infer(motion.joint_names, motion.parents, units_to_metres, offsets=motion.offsets,
                                  source=f"auto({n})")  # fmt: skip
        except ValueError as err:
            raise PrepareError(f"--joint-map auto on {src.path}/{n}: {err}") from None
    raise PrepareError(f"no BVH file could be read to infer the joint map; the first: {first_error}")


def bvh_options(labels, joint_map: str, units_to_metres, per_group, max_frames, compact, seed, up_axis="auto") -> dict:
    """What a prepared folder was made with (saved in report.json; ensure_prepared_bvh compares it)."""
    labels_path = None if labels is None else Path(labels).resolve()
    digest = None if labels_path is None or not labels_path.is_file() else _sha256(labels_path)
    jm = joint_map if joint_map == "auto" or Path(joint_map).suffix != ".json" else str(Path(joint_map).resolve())
    options = {"source_type": "bvh", "compact": compact, "per_group": per_group, "max_frames": max_frames,
               "seed": seed, "labels": None if labels_path is None else str(labels_path), "labels_sha256": digest,
               "joint_map": jm, "units_to_metres": units_to_metres, "up_axis": str(up_axis)}  # fmt: skip
    return json.loads(json.dumps(options))


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def prepare_bvh(
    sources: list[str | Path],
    out: str | Path,
    labels: str | Path | None = None,
    joint_map: str = "auto",
    units_to_metres: float | None = None,
    *,
    up_axis: str = "auto",
    **options,
) -> dict:
    """Prepare BVH folders/zips into `out`; returns the report (also saved as report.json). `up_axis`: "auto" (each
    file's own, `motiondiff.data.formats.up_axis`; files it cannot decide are skipped with the reason) or a forced
    "y", "z", ... for every file; Z-up files are turned to Y-up. `options`: those every source takes
    (`writer.PrepareOptions`: per_group, max_frames, compact, seed, workers, force, progress)."""
    opts = PrepareOptions.of("prepare_bvh", options)
    out = Path(out)
    check_output(out, opts.force)
    try:
        parse_up_axis(up_axis)
    except ValueError as err:
        raise PrepareError(f"--up-axis: {err}".replace("up_axis=", "")) from None
    if not sources:
        raise PrepareError("no --src given")
    if units_to_metres is not None and not (math.isfinite(units_to_metres) and units_to_metres > 0):
        raise PrepareError(f"--units-to-metres {units_to_metres}: must be a positive number (0.01 for centimetres)")
    srcs = [Source(p) for p in sources]
    files = list_files(srcs)
    clips = make_clips(files, {} if labels is None else read_labels(labels, files))
    jm = resolve_joint_map(joint_map, files, units_to_metres)
    saved = bvh_options(labels, joint_map, units_to_metres, opts.per_group, opts.max_frames, opts.compact, opts.seed,
                        up_axis)  # fmt: skip
    human = sum(c.captions is not None for c in clips)
    note = (
        f"{human} of {len(clips)} file(s) with human-written captions from the labels file, the others "
        if human
        else ""
    )
    meta = {"captions": f"{note}{GENERATED_NOTE} (per-clip flags: captions_generated)", "joint_map_used": jm.to_json()}
    meta["license"] = copy_license(None, sources) or "unknown: no LICENSE file in the sources; check their terms"
    resolved = [Path(p).resolve() for p in sources]
    with staged_folder(out, opts.force) as build:  # a killed run leaves the old dataset or the new one, never a mixture
        report = process_and_write(clips, [], resolved, build, jm, saved, meta, opts.workers, opts.progress)
        copy_license(build, sources)
        atomic_write(build / "joint_map.json", lambda tmp: Path(tmp).write_text(json.dumps(jm.to_json(), indent=1)))
        _write_readme(build, sources, report, meta, out.name)
    return report


def _write_readme(out: Path, sources, report: dict, meta: dict, name: str) -> None:
    o = report["options"]
    cmd = "python -m motiondiff.data.preparing.prepare bvh " + " ".join(f"--src {Path(p).name}" for p in sources)
    cmd += f" --labels {Path(o['labels']).name}" if o["labels"] else ""
    cmd += f" --joint-map {o['joint_map']}"
    cmd += "".join(f" --{k.replace('_', '-')} {o[k]}" for k in ("units_to_metres", "per_group", "max_frames", "up_axis")
                   if o[k] is not None)  # fmt: skip
    cmd += " --compact" * bool(o["compact"]) + f" --seed {o['seed']} --out {name}"
    clips = report["clips"]
    text = f"""# {name}

Motion capture prepared by motiondiff from BVH files: {", ".join(Path(p).name for p in sources)}.

- clips: {sum(clips.values())} (train {clips["train"]}, val {clips["val"]}, test {clips["test"]}), 20 fps, metres, y up
- captions: {meta["captions"]}
- joint map: {report["joint_map"]}, saved as joint_map.json (edit it and pass `--joint-map joint_map.json`)
- license: {meta["license"]}
- format: see `motiondiff.data.formats.prepared`; counts per label and every skipped file: report.json

Rebuilt with:

    {cmd}
"""
    atomic_write(out / "README.md", lambda tmp: Path(tmp).write_text(text), suffix=".md")


def ensure_prepared_bvh(
    src: str | Path | list[str | Path],
    out: str | Path,
    labels: str | Path | None = None,
    joint_map: str = "auto",
    **opts,
) -> Path:
    """`out`, prepared from `src` unless it already holds a dataset prepared from the same sources with the same
    options (labels file content included), which is reused. A stale `bvh` dataset there is replaced; a folder
    holding anything else prepared is left alone (PrepareError). `opts`: prepare_bvh's keyword arguments."""
    sources = [src] if isinstance(src, str | Path) else list(src)
    out = Path(out)
    keys = ("units_to_metres", "per_group", "max_frames", "compact", "seed", "up_axis")
    defaults = {"units_to_metres": None, "up_axis": "auto", **asdict(PrepareOptions())}
    wanted = bvh_options(labels, joint_map, *({**defaults, **opts}[k] for k in keys))
    report_path = out / "report.json"
    if (out / "meta.json").is_file() and report_path.is_file():
        try:
            report = json.loads(report_path.read_text())
        except ValueError:
            report = {}
        if report.get("sources") == [str(Path(p).resolve()) for p in sources] and report.get("options") == wanted:
            return out
        if report.get("options", {}).get("source_type") != "bvh":
            raise PrepareError(f"{out} holds another prepared dataset; choose another folder for {sources}")
    opts.pop("force", None)  # replacing a stale dataset is what this function is for
    prepare_bvh(sources, out, labels, joint_map, force=True, **{"progress": False, **opts})
    return out
