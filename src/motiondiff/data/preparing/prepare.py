"""Raw motion capture -> a prepared dataset folder (see motiondiff.data.formats.prepared for the format).

    python -m motiondiff.data.preparing.prepare bandai --src bandai-ds1.zip --src bandai-ds2.zip --out data/bandai
    python -m motiondiff.data.preparing.prepare bandai --src ... --out data/bandai_mini --per-group 1 --max-frames 120 --compact
    python -m motiondiff.data.preparing.prepare bvh --src 100STYLE.zip --out data/100style          (see prepare_bvh)
    python -m motiondiff.data.preparing.prepare bvh --src mocap/ --labels labels.csv --joint-map auto --out data/mocap

Every clip is read; each one that cannot be used is named with its reason; counts per split and label are printed
and saved in report.json. Files are written to temporary names and renamed, so an interrupted run leaves either
the previous dataset or the new one, never a mixture of half-written files.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from motiondiff.data.formats.archive import Source, SourceError
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import SPLITS
from motiondiff.data.preparing.captions import GENERATED_NOTE, WORDINGS
from motiondiff.data.preparing.staging import staged_folder
from motiondiff.data.preparing.writer import (  # noqa: F401  (PrepareError, check_output, caption_seed, load_held_out: part of this module's API)
    PrepareError,
    PrepareOptions,
    _write_license_and_readme,
    caption_seed,
    check_output,
    load_held_out,
    process_and_write,
)
from motiondiff.data.sources import bandai
from motiondiff.runtime.boundary import Stopped, error_line, signal_behind, stop_on_sigterm, stop_report


def prepare_bandai(
    sources: list[str | Path],
    out: str | Path,
    *,
    caption_variants: int = 12,
    rare_to_train: int = 3,
    held_out: list[str | Path] = (),
    caption_wording: str = "plain",
    **options,
) -> dict:
    """Prepare Bandai Namco releases into `out`; returns the report (also saved as report.json).
    `caption_variants`: generated sentences in varied wording per clip, beside the three label/measured ones;
    `rare_to_train`: every clip of a content label with fewer clips than this goes to train (0: none);
    `held_out`: JSON files of descriptions ({"descriptions": [{"text": ...}]}) no generated caption may equal.
    `caption_wording`: "plain" (clean templates) or "broad" (context clauses, surface noise, no measurements-only
    sentence: `captions.generate_captions`).
    `options`: those every source takes (`writer.PrepareOptions`: per_group, max_frames, compact, seed, workers,
    force, progress)."""
    opts = PrepareOptions.of("prepare_bandai", options)
    if caption_wording not in WORDINGS:
        raise PrepareError(f"caption_wording={caption_wording!r}: choose {' or '.join(WORDINGS)}")
    out = Path(out)
    check_output(out, opts.force)
    joint_map = JointMap.load("bandai_to_smpl22")
    clips, skipped = [], []
    for path in sources:
        found, bad = bandai.list_clips(Source(path))
        clips += found
        skipped += [(s.name, s.reason) for s in bad]
    if not clips:
        raise PrepareError("no usable clips in " + ", ".join(map(str, sources)))
    saved = {**opts.saved(), "caption_variants": caption_variants, "rare_to_train": rare_to_train,
             "held_out": [str(p) for p in held_out], "caption_wording": caption_wording}  # fmt: skip
    meta = {"captions": GENERATED_NOTE, "license": bandai.ATTRIBUTION}
    with staged_folder(out, opts.force) as build:  # a killed run leaves the old dataset or the new one, never a mixture
        report = process_and_write(clips, skipped, sources, build, joint_map, saved, meta, opts.workers, opts.progress)
        _write_license_and_readme(build, sources, report, out.name)
    return report


def print_report(report: dict, out: Path) -> None:
    total = sum(report["clips"].values())
    print(f"\nprepared {total} clips into {out}  ({', '.join(f'{s} {n}' for s, n in report['clips'].items())})")
    for kind in ("per_dataset", "per_content", "per_style"):
        names = sorted({k for s in SPLITS for k in report[kind][s]})
        print(f"\n{kind[4:]:<22}" + "".join(f"{s:>7}" for s in SPLITS))
        for n in names:
            print(f"  {n:<20}" + "".join(f"{report[kind][s].get(n, 0):>7}" for s in SPLITS))
    if set(report.get("up_axes", {})) - {"+y"}:
        print("\nup axes of the files (turned to +y): " + ", ".join(f"{a} {n}" for a, n in report["up_axes"].items()))
    print(f"\nskipped {len(report['skipped'])} clip(s)")
    for item in report["skipped"]:
        print(f"  {item['clip']}: {item['reason']}")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m motiondiff.data.preparing.prepare", description=__doc__.split("\n\n")[0]
    )
    sub = parser.add_subparsers(dest="dataset", required=True)
    b = sub.add_parser("bandai", help="Bandai Namco Research Motion Dataset 1/2 (zips or unzipped folders)")
    b.add_argument("--src", action="append", required=True, help="a release zip or folder (repeat for several)")
    b.add_argument(
        "--caption-variants",
        type=int,
        default=12,
        help="generated captions in varied wording per clip, beside the 3 label/measured ones (default 12)",
    )
    b.add_argument(
        "--rare-to-train",
        type=int,
        default=3,
        help="all clips of an action with fewer clips than this go to train (default 3; 0: none)",
    )
    b.add_argument(
        "--held-out",
        action="append",
        default=[],
        help="a JSON file of held-out descriptions no generated caption may repeat (repeatable)",
    )
    b.add_argument(
        "--caption-wording",
        choices=WORDINGS,
        default="plain",
        help="plain: clean generated sentences (default); broad: also context clauses, typos and case noise",
    )
    add_common_arguments(b)
    v = sub.add_parser("bvh", help="any folder or zip of BVH files, with an optional labels CSV (100STYLE, ...)")
    v.add_argument("--src", action="append", required=True, help="a folder or zip of .bvh files (repeat for several)")
    v.add_argument("--labels", help="CSV with a header: file (required), action, style, caption (several: a|b)")
    v.add_argument("--joint-map", default="auto", help="auto (from joint names), a shipped map name or path.json")
    v.add_argument("--units-to-metres", type=float, help="factor from file units to metres (default: guessed)")
    v.add_argument("--up-axis", default="auto", help="auto (detected per file), y, z, x, -y, -z or -x (forced)")
    add_common_arguments(v)
    return parser


def add_common_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--per-group", type=int, help="keep at most N clips per dataset x content x style (subset)")
    p.add_argument("--max-frames", type=int, help="crop longer clips to their most active N frames (at 20 fps)")
    p.add_argument("--compact", action="store_true", help="leave out derived arrays (recomputed on load)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, help="processes (default: up to 4)")
    p.add_argument("--force", action="store_true", help="replace a prepared dataset already in --out")


UNCHANGED = "the output folder is as it was before (prepared datasets are swapped in whole)"


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    restore = stop_on_sigterm(kept=f"; {UNCHANGED}")  # a scheduler's kill ends like Ctrl-C: exit 143, data kept
    try:
        return _prepare(args)
    finally:
        restore()  # main() may be called in-process: the caller's Ctrl-C and SIGTERM handlers come back


def _prepare(args) -> int:
    common = dict(per_group=args.per_group, max_frames=args.max_frames, compact=args.compact, seed=args.seed,
                  workers=args.workers, force=args.force)  # fmt: skip
    try:
        if args.dataset == "bvh":
            from motiondiff.data.preparing.from_bvh import prepare_bvh

            report = prepare_bvh(args.src, args.out, args.labels, args.joint_map, args.units_to_metres,
                                 up_axis=args.up_axis, **common)  # fmt: skip
        else:
            report = prepare_bandai(args.src, args.out, caption_variants=args.caption_variants,
                                    rare_to_train=args.rare_to_train, held_out=args.held_out,
                                    caption_wording=args.caption_wording, **common)  # fmt: skip
    except (PrepareError, SourceError, bandai.BandaiLayoutError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, Stopped) as stop:  # Ctrl-C, SIGTERM: reported once the progress bar has closed
        return _stopped(stop)
    except Exception as err:  # noqa: BLE001 - expected failures (disk, permissions, text) as one line; bugs re-raised
        stop = signal_behind(err)
        if stop is not None:  # a signal that C code turned into another error
            return _stopped(stop)
        line = error_line(err)
        if line is None:
            raise
        print(f"error: {line}", file=sys.stderr)
        return 2
    print_report(report, Path(args.out))
    return 0


def _stopped(stop: BaseException) -> int:
    """A stop's one line (Ctrl-C's says the data is unchanged; SIGTERM's line already does) and its exit code."""
    line, code = stop_report(stop)
    print(f"error: {line}" + ("" if isinstance(stop, Stopped) else f"; {UNCHANGED}"), file=sys.stderr)
    return code


if __name__ == "__main__":
    sys.exit(main())  # PrepareError lives in prepare_writer, so this __main__ copy catches what prepare_bvh raises
