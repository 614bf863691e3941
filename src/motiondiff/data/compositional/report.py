"""What a compositional dataset holds (motiondiff.data.compositional.dataset): numbers per split, README and summary text."""

from __future__ import annotations

from collections import Counter

import numpy as np

from motiondiff.data.formats.prepared import SPLITS, PreparedSplit
from motiondiff.geometry.skeleton import SMPL22

FEET = [j for side in SMPL22.foot_joints for j in side]
STANDING_FOOT_SPEED = 0.25  # m/s: below this, in both clips next to a seam, the feet are planted there


def max_joint_speed(joints: np.ndarray, fps: float, which=slice(None)) -> np.ndarray:
    """(N-1,) the fastest joint's speed (m/s) between consecutive frames (of the joints `which` selects)."""
    return np.linalg.norm(np.diff(joints[:, which], axis=0), axis=-1).max(-1) * fps


def max_joint_acceleration(joints: np.ndarray, fps: float) -> np.ndarray:
    """(N-2,) the largest joint acceleration (m/s^2): a hard cut shows as a spike where a cross-fade has none."""
    return np.linalg.norm(np.diff(joints, 2, axis=0), axis=-1).max(-1) * fps * fps


def seam_measures(joints: np.ndarray, sources: list[np.ndarray], frames, transition: int, fps: float) -> list[dict]:
    """Per seam: `peak`, the fastest joint inside the transition (one frame either side), divided by the larger of
    the two joined windows' median (`to_median`) and max (`to_max`) fastest-joint speed; a blow-up (a limb thrown
    across the body, a root jump) shows as a ratio far above 1 against the max; `acceleration_to_max` likewise for
    the largest joint acceleration (two frames either side). `standing`: both clips' feet are
    planted next to the seam; `foot_slide`: the longest ground path of a foot over the transition (m)."""
    speed = max_joint_speed(joints, fps)
    acc = max_joint_acceleration(joints, fps)
    out = []
    for k in range(1, len(frames)):
        s = frames[k][0]
        peak = float(speed[max(s - 1, 0) : s + transition + 1].max())
        a, b = max_joint_speed(sources[k - 1], fps), max_joint_speed(sources[k], fps)
        near = max(max_joint_speed(sources[k - 1][-transition - 1 :], fps, FEET).max(),
                   max_joint_speed(sources[k][: transition + 1], fps, FEET).max())  # fmt: skip
        feet = joints[s : s + transition + 1][:, FEET][..., [0, 2]]
        out.append({"peak": peak, "to_median": peak / max(np.median(a), np.median(b)),
                    "to_max": peak / max(a.max(), b.max()), "standing": bool(near < STANDING_FOOT_SPEED),
                    "acceleration_to_max": float(acc[max(s - 2, 0) : s + transition + 1].max()) / max(
                        max_joint_acceleration(sources[k - 1], fps).max(), max_joint_acceleration(sources[k], fps).max()),
                    "foot_slide": float(np.linalg.norm(np.diff(feet, axis=0), axis=-1).sum(0).max())})  # fmt: skip
    return out


def _quantiles(values) -> dict:
    v = np.asarray(values, dtype=np.float64)
    return {"min": float(v.min()), "median": float(np.median(v)), "p95": float(np.quantile(v, 0.95)),
            "max": float(v.max())}  # fmt: skip


def split_report(seqs, data: PreparedSplit, arrays: dict, transition: int, fps: float) -> dict:
    """Counts, lengths, action nodes of the first captions, seam speed ratios and five sample captions."""
    seams = [m for s in seqs for m in s.seams]
    standing = [m["foot_slide"] for m in seams if m["standing"]]
    lengths = arrays["lengths"]
    n_actions = [sum(s.actions) for s in seqs]
    cropped = sum(
        (b - a) < int(data.arrays["lengths"][i]) for s in seqs for i, (a, b) in zip(s.indices, s.windows, strict=True)
    )
    used = {int(i) for s in seqs for i in s.indices}
    return {
        "sequences": len(seqs),
        "clips_joined": dict(sorted(Counter(len(s.indices) for s in seqs).items())),
        "frames": int(lengths.sum()),
        "length_frames": _quantiles(lengths),
        "length_histogram_s": {
            f"{lo}-{lo + 2}": int(((lengths / fps >= lo) & (lengths / fps < lo + 2)).sum()) for lo in range(0, 10, 2)
        },  # fmt: skip
        "segments_cropped": f"{cropped} of {sum(len(s.indices) for s in seqs)}",
        "source_clips_used": f"{len(used)} of {data.num_clips}",
        "captions_per_sequence": dict(sorted(Counter(len(s.captions) for s in seqs).items())),
        "action_nodes_first_caption": dict(sorted(Counter(n_actions).items())),
        "exactly_one_action_per_clip": f"{sum(all(a == 1 for a in s.actions) for s in seqs)} of {len(seqs)}",
        "seams": len(seams),
        "seam_ratio_to_median_speed": _quantiles([m["to_median"] for m in seams]),
        "seam_ratio_to_max_speed": _quantiles([m["to_max"] for m in seams]),
        "seam_ratio_to_max_acceleration": _quantiles([m["acceleration_to_max"] for m in seams]),
        "seams_standing": len(standing),
        "standing_seam_foot_slide_m": _quantiles(standing) if standing else None,
        "samples": [s.captions[0] for s in seqs[:5]],
    }


def _fmt(q: dict, digits: int = 2) -> str:
    return f"median {q['median']:.{digits}f}, 95th percentile {q['p95']:.{digits}f}, max {q['max']:.{digits}f}"


def summary(report: dict) -> str:
    """Markdown summary of a build (what docs/results/guidedmotion/compositional_data.md holds)."""
    o, sp = report["options"], report["splits"]
    lines = [
        "# Compositional multi-action data (bandai_mini_compositional)",
        "",
        f"Built with `{report['command']}`: 2-3 real Bandai clips of one split joined with {o['transition_s']} s "
        f"({o['transition_frames']} frames) smooth-step transitions; captions are the clips' GENERATED captions "
        'joined with ", then" / ", and then" (not human-written). The test split is the complex-motion subset '
        "(>= 3 local actions, >= 150 frames).",
        "",
        "| | " + " | ".join(SPLITS) + " |",
        "|---|" + "---|" * len(SPLITS),
    ]
    rows = [
        ("sequences", lambda r: str(r["sequences"])),
        ("clips joined (count: sequences)", lambda r: ", ".join(f"{k}: {v}" for k, v in r["clips_joined"].items())),
        ("frames in all", lambda r: str(r["frames"])),
        ("length, frames (min / median / max)",
         lambda r: f"{r['length_frames']['min']:.0f} / {r['length_frames']['median']:.0f} / {r['length_frames']['max']:.0f}"),
        ("length histogram, s (0-2, 2-4, ...)", lambda r: ", ".join(str(v) for v in r["length_histogram_s"].values())),
        ("clips cropped to their most active window", lambda r: r["segments_cropped"]),
        ("source clips used", lambda r: r["source_clips_used"]),
        ("action nodes of the first caption (n: sequences)",
         lambda r: ", ".join(f"{k}: {v}" for k, v in r["action_nodes_first_caption"].items())),
        ("exactly one action node per joined clip", lambda r: r["exactly_one_action_per_clip"]),
        ("joined captions per sequence (n: sequences)",
         lambda r: ", ".join(f"{k}: {v}" for k, v in r["captions_per_sequence"].items())),
        ("seam speed / larger median speed (median, p95, max)",
         lambda r: " / ".join(f"{r['seam_ratio_to_median_speed'][q]:.2f}" for q in ("median", "p95", "max"))),
        ("seam speed / larger max speed (median, p95, max)",
         lambda r: " / ".join(f"{r['seam_ratio_to_max_speed'][q]:.2f}" for q in ("median", "p95", "max"))),
        ("seam acceleration / larger max acceleration (median, p95, max)",
         lambda r: " / ".join(f"{r['seam_ratio_to_max_acceleration'][q]:.2f}" for q in ("median", "p95", "max"))),
        ("seams between standing clips: foot slide, cm (median, p95, max)",
         lambda r: f"{r['seams_standing']} of {r['seams']}: " + " / ".join(
             f"{100 * r['standing_seam_foot_slide_m'][q]:.1f}" for q in ("median", "p95", "max"))
         if r["standing_seam_foot_slide_m"] else "none"),
        ("draws refused (reason: count)", lambda r: "; ".join(f"{k}: {v}" for k, v in r["draws_refused"].items())),
    ]  # fmt: skip
    lines += [f"| {name} | " + " | ".join(get(sp[s]) for s in SPLITS) + " |" for name, get in rows]
    lines += ["", "Seam speed: the fastest joint inside a transition (one frame either side) divided by the larger "
              "of the two joined windows' median (or max) per-frame fastest-joint speed; draws above "
              f"{o.get('max_seam_ratio', '?')}x the median are refused. Foot slide: the longest ground path of a foot "
              "over a transition where both clips have their feet planted next to the seam (a cross-fade cannot "
              f"step, so a change of stance slides); draws above {o.get('max_standing_foot_slide_m', '?')} m are "
              "refused.", "",
              "Five test captions (the first caption of a sequence, which evaluation uses):", ""]  # fmt: skip
    lines += [f"{k + 1}. {c}" for k, c in enumerate(sp["test"]["samples"])]
    size = sum(report.get("npz_bytes", {}).values()) / 2**20
    lines += ["", "Notes:", "",
              "- Every joined caption has at least one action node (`parse_caption`) inside each clip's part; more "
              "than one where a label phrase has two verbs (\"walks and turns left\", \"gestures to show someone the "
              "way\") or the parser reads a style phrase as one (\"as if tired\").",
              f"- Size: the three npz files hold {size:.1f} MB (float32 joints + native rotations compress to about "
              "570 bytes a frame), which is why the counts are below a few hundred train / 100 test sequences; "
              "`train=N test=N` builds more.",
              "- Training (`dataset=bandai_mini_compositional`) concatenates these train sequences with bandai_mini's "
              "252 single train clips (`extra_train`); `max_frames` 196, so no sequence is cropped."]  # fmt: skip
    return "\n".join(lines) + "\n"


def readme(name: str, report: dict, meta: dict) -> str:
    sp, o = report["splits"], report["options"]
    counts = ", ".join(f"{s} {sp[s]['sequences']}" for s in SPLITS)
    return f"""# {name}

Multi-action sequences made by motiondiff from the real clips of `{o["src"]}` (Bandai Namco Research Motion
Dataset 1 and 2): each joins 2-3 clips of ONE split (train with train, test with test) with {o["transition_s"]} s
smooth-step transitions (`motiondiff.data.compositional.dataset`).

**Attribution:** {meta["license"]}. The license is in [LICENSE](LICENSE) (non-commercial use only).

- sequences: {counts}; 20 fps, metres, y up, at most {o["max_frames"]} frames
- test = the complex-motion subset of GuidedMotion: >= 3 local actions, >= 150 frames
- captions: **generated** (not human-written): each clip's generated caption (from its labels and what it measurably
  does; new ones for clips cropped to their most active window) joined with ", then" / ", and then"; every joined
  caption parses (`motiondiff.text.parse`) to at least one action node per joined clip
- draws whose transition moves a joint faster than {o["max_seam_ratio"]:g}x the joined clips' median speed, or slides a
  foot more than {o["max_standing_foot_slide_m"]:g} m between two standing clips, are refused (counts in report.json)
- content/style/action of a sequence are its first clip's, kept so the layout loads (use it for text conditioning);
  segment_content/segment_style hold every clip's labels
- format: `motiondiff.data.formats.prepared`, plus {SEGMENT_NOTE}
- Mean/Std: over the train features of `{o["src"]}` and of this train split together
  (`conf/dataset/bandai_mini_compositional.yaml` trains on both); numbers per split: report.json

Rebuilt with (in a motiondiff checkout):

    {report["command"]} force=true
"""


SEGMENT_NOTE = (
    "per-segment arrays: segment_offsets, segment_source_ids, segment_source_frames, segment_frames, "
    "segment_captions, segment_content, segment_style, transition_frames (see meta.json)"
)
