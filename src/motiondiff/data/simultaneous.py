"""Simultaneous-action training data: the legs and path of one real clip with the upper body of another.

    python -m motiondiff.data.simultaneous out=data/bandai_mini_simultaneous [src=data/bandai_mini] [seed=0]
        [train=256] [val=16] [test=16] [force=true]

Why: every real Bandai clip does one thing, so a model trained on them has only seen walking legs with swinging arms,
and a body-part edit that keeps a walk's legs and asks for "raises both hands" gets swinging arms back. SINC
(Athanasiou et al. 2023, "spatial composition of 3D human motions for simultaneous action generation") builds such
training pairs synthetically from single-action clips; this is that idea on the native rig:

- pairs of ONE split: a locomotion clip (content label starting with one of LOCOMOTION) gives the root path and the
  lower body, an in-place arm gesture (ARM_GESTURES) gives the upper body, whole: the locomotion clip must be at least
  as long and is cut to the gesture's length at its most active window (cutting the gesture instead lost the held
  part of half the "raises both hands" clips, and a model fine-tuned on such pairs stopped raising its hands);
- the rig's local joint rotations are taken per joint: the rig preset ``upper_body`` (spine and above) from the
  gesture, the rest and the root from the locomotion clip, on the locomotion clip's bones; forward kinematics,
  the dataset's joint map and HumanML3D's canonicalisation then give the SMPL-22 joints and the features exactly as
  ``prepare`` gives a real clip's (a pair of a clip with itself gives back its prepared joints);
- captions are GENERATED: the two clips' first (labels-only) captions joined with "and", both orders
  ("the person walks like a child and raises both hands energetically.").

Output: the npz layout of ``motiondiff.data.prepared`` (content/style/action of an item are its locomotion clip's;
``upper_source_ids`` / ``upper_content`` name the gesture clip), the source's Mean/Std (a model trained on the
source keeps its normalisation when fine-tuned on both), meta.json, report.json, README.md and the source's LICENSE.
``conf/dataset/bandai_mini_simultaneous.yaml`` trains on the source's clips plus these and validates on the source.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.atomic import atomic_write
from motiondiff.data.captions import GENERATED_NOTE
from motiondiff.data.compositional_join import Joined, place_canonically, split_subject
from motiondiff.data.features import canonicalize_joints
from motiondiff.data.joint_map import JointMap
from motiondiff.data.prepare import PrepareError, check_output
from motiondiff.data.prepared import SPLITS, PreparedSplit, fill_derived, load_split, save_split
from motiondiff.data.processing import most_active_window
from motiondiff.kinematics import forward_kinematics
from motiondiff.skeleton import SMPL22

LOCOMOTION = ("walk", "run", "dash")  # content labels (prefixes) whose legs and path say what the clip does
ARM_GESTURES = ("bye", "byebye", "call", "guide", "raise-up-", "wave-")  # done in place, with the arms
MIN_FRAMES = 30  # 1.5 s: a shorter pair no longer shows either action


@dataclass
class Pair:
    lower: int  # source clip giving the root path and the lower body
    upper: int  # source clip giving the upper body
    lower_window: tuple[int, int]
    upper_window: tuple[int, int]
    captions: list[str]
    joints: np.ndarray  # (N, 22, 3) canonical SMPL-22
    rotations: np.ndarray  # (N, J, 4) native local rotations, canonically placed
    root: np.ndarray  # (N, 3)


def _matches(label: str, kinds: tuple[str, ...]) -> bool:
    return any(label == k or (k.endswith("-") and label.startswith(k)) or label.startswith(k + "-") for k in kinds)


def candidates(data: PreparedSplit) -> tuple[list[int], list[int]]:
    """(locomotion clips, arm-gesture clips) of a split, by content label, at least MIN_FRAMES long."""
    long_enough = [i for i in range(data.num_clips) if int(data.arrays["lengths"][i]) >= MIN_FRAMES]
    lower = [i for i in long_enough if _matches(data.label("content", i), LOCOMOTION)]
    upper = [i for i in long_enough if _matches(data.label("content", i), ARM_GESTURES)]
    return lower, upper


def join_simultaneous(first: str, second: str) -> str:
    """ "the person walks. " + "a man raises both hands." -> "the person walks and raises both hands."."""
    subject, rest = split_subject(first)
    _, other = split_subject(second)
    return f"{subject} {rest} and {other}.".strip() if subject else f"{rest} and {other}."


def compose_pair(data: PreparedSplit, joint_map: JointMap, lower: int, upper: int) -> Pair:
    """The upper body of clip ``upper`` on the legs and path of clip ``lower`` (module docstring); the longer clip
    is cut to the shorter one's length at its most active window."""
    a, rig = data.arrays, data.rig()
    n = min(int(a["lengths"][lower]), int(a["lengths"][upper]))
    lw = most_active_window(a["joints"][data.clip_slice(lower)], n)
    uw = most_active_window(a["joints"][data.clip_slice(upper)], n)
    rotations = a["native_rotations"][data.clip_slice(lower)][lw[0] : lw[1]].astype(np.float64).copy()
    top = list(rig.parts["upper_body"])
    rotations[:, top] = a["native_rotations"][data.clip_slice(upper)][uw[0] : uw[1]][:, top]
    root = a["native_root"][data.clip_slice(lower)][lw[0] : lw[1]].astype(np.float64)
    offsets = a["native_offsets"][lower].astype(np.float64)
    translations = np.broadcast_to(offsets, rotations.shape[:-1] + (3,)).copy()
    translations[:, 0] = root
    world, _ = forward_kinematics(rotations, translations, rig.parents)
    joints = canonicalize_joints(joint_map.apply(world, list(rig.joint_names), to_metres=False), SMPL22)
    placed = place_canonically(Joined(joints, rotations, root, [(0, n)]), offsets, rig.with_offsets(offsets))
    first, second = data.captions(lower)[0], data.captions(upper)[0]
    captions = [join_simultaneous(first, second), join_simultaneous(second, first)]
    return Pair(lower, upper, lw, uw, captions, placed.joints, placed.rotations, placed.root)


def pairs_of(data: PreparedSplit) -> list[tuple[int, int]]:
    """Every (locomotion, gesture) pair of a split whose locomotion clip is at least as long as the gesture."""
    lower, upper = candidates(data)
    n = data.arrays["lengths"]
    return [(lo, up) for lo in lower for up in upper if n[lo] >= n[up]]


def build_split(data: PreparedSplit, joint_map: JointMap, count: int, seed: int, split_index: int) -> list[Pair]:
    """``count`` distinct pairs drawn uniformly from ``pairs_of``; the same arguments give the same pairs."""
    pairs = pairs_of(data)
    if count > len(pairs):
        raise ValueError(f"only {len(pairs)} pairs can be made from this split; ask for fewer")
    picks = np.random.default_rng([seed, split_index]).choice(len(pairs), size=count, replace=False)
    return [compose_pair(data, joint_map, *pairs[int(k)]) for k in picks]


def split_arrays(pairs: list[Pair], data: PreparedSplit, split: str) -> dict[str, np.ndarray]:
    """The prepared npz layout (motiondiff.data.prepared), labels of the locomotion clip, plus the gesture's."""
    a = data.arrays
    lower = [p.lower for p in pairs]
    upper = [p.upper for p in pairs]
    lengths = np.array([len(p.joints) for p in pairs])
    arrays = {
        "ids": np.array([f"simultaneous_{split}_{k:03d}" for k in range(len(pairs))]),
        "lengths": lengths,
        "frame_offsets": np.concatenate([[0], np.cumsum(lengths)]),
        "joints": np.concatenate([p.joints for p in pairs]).astype(np.float32),
        "native_rotations": np.concatenate([p.rotations for p in pairs]).astype(np.float32),
        "native_root": np.concatenate([p.root for p in pairs]).astype(np.float32),
        "native_joint_names": a["native_joint_names"],
        "native_parents": a["native_parents"],
        "native_offsets": a["native_offsets"][lower],
        "captions": np.array([c for p in pairs for c in p.captions]),
        "caption_offsets": np.concatenate([[0], np.cumsum([len(p.captions) for p in pairs])]),
        "captions_generated": np.array(True),
        "fps": a["fps"],
        "lower_source_ids": a["ids"][lower],
        "lower_source_frames": np.array([p.lower_window for p in pairs]),
        "upper_source_ids": a["ids"][upper],
        "upper_source_frames": np.array([p.upper_window for p in pairs]),
        "upper_content": a["content"][upper],
    }
    for kind in ("dataset", "content", "style", "action"):
        arrays[kind], arrays[f"{kind}_names"] = a[kind][lower], a[f"{kind}_names"]
    fill_derived(arrays)
    return arrays


def _readme(name: str, meta: dict, report: dict) -> str:
    counts = ", ".join(f"{s} {report['splits'][s]['pairs']}" for s in SPLITS)
    samples = "\n".join(f"  - {c}" for c in report["splits"]["train"]["sample_captions"])
    return f"""# {name}

Simultaneous actions made by motiondiff from the real clips of `{meta["simultaneous"]["src"]}` (Bandai Namco
Research Motion Dataset 1 and 2): the root path and lower body of a locomotion clip with the upper body (spine and
above, rig joint rotations) of an in-place arm gesture of the SAME split, as SINC (Athanasiou et al. 2023) builds
simultaneous-action data (`motiondiff.data.simultaneous`).

**Attribution:** Bandai Namco Research Motion Dataset, Bandai Namco Research Inc., CC BY-NC 4.0. The license is in
[LICENSE](LICENSE) (non-commercial use only).

- pairs: {counts}; 20 fps, metres, y up; locomotion labels {", ".join(LOCOMOTION)}; gestures {", ".join(ARM_GESTURES)}
- captions: **generated** (not human-written): the two clips' generated labels-only captions joined with "and",
  in both orders, e.g.
{samples}
- content/style/action of an item are its locomotion clip's (text conditioning only); `upper_source_ids`,
  `upper_source_frames`, `upper_content` name the gesture clip
- Mean/Std: the source's (the dataset config trains on the source's clips and these together)

Rebuilt with (in a motiondiff checkout):

    {report["command"]} force=true
"""


def build(src: str | Path, out: str | Path, counts: dict[str, int], seed: int = 0, force: bool = False) -> dict:
    """Write the simultaneous-action dataset into ``out``; returns its report (also saved as report.json)."""
    src, out = Path(src), Path(out)
    check_output(out, force)
    sources = {s: load_split(src, s) for s in SPLITS}
    src_meta = sources["train"].meta
    source, target = str(src_meta.get("joint_map", "bandai->smpl22")).split("->")
    joint_map = JointMap.load(src / "joint_map.json") if (src / "joint_map.json").is_file() else JointMap.load(
        f"{source}_to_{target}")  # fmt: skip
    arrays, report = {}, {"splits": {}}
    for k, split in enumerate(SPLITS):
        pairs = build_split(sources[split], joint_map, counts[split], seed, k)
        arrays[split] = split_arrays(pairs, sources[split], split)
        lower, upper = candidates(sources[split])
        report["splits"][split] = {
            "pairs": len(pairs), "locomotion_clips": len(lower), "gesture_clips": len(upper),
            "possible_pairs": len(pairs_of(sources[split])),
            "frames": int(arrays[split]["lengths"].sum()),
            "sample_captions": [p.captions[0] for p in pairs[:5]],
        }  # fmt: skip
    command = f"python -m motiondiff.data.simultaneous src=data/{src.name} out=data/{out.name} seed={seed} " + " ".join(
        f"{s}={counts[s]}" for s in SPLITS
    )
    report["command"] = command
    meta = {
        "clips": {s: len(arrays[s]["ids"]) for s in SPLITS},
        "frames": {s: int(arrays[s]["lengths"].sum()) for s in SPLITS},
        "labels": src_meta["labels"],
        "fps": float(sources["train"].arrays["fps"]),
        "joint_map": src_meta.get("joint_map", "bandai->smpl22"),
        "captions": f"{GENERATED_NOTE}; two clips' generated captions joined with 'and' (simultaneous actions)",
        "license": src_meta.get("license", ""),
        "simultaneous": {"src": src.name, "seed": seed, "counts": counts, "command": command,
                         "locomotion": list(LOCOMOTION), "gestures": list(ARM_GESTURES),
                         "mean_std": f"those of {src.name}"},
    }  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    for split in SPLITS:
        save_split(out / f"{split}.npz", arrays[split], compact=True)
    for name in ("Mean.npy", "Std.npy"):
        data = (src / name).read_bytes()
        atomic_write(out / name, lambda tmp, d=data: Path(tmp).write_bytes(d), suffix=".npy")
    if (src / "LICENSE").is_file():
        text = (src / "LICENSE").read_text()
        atomic_write(out / "LICENSE", lambda tmp: Path(tmp).write_text(text), suffix="")
    atomic_write(out / "README.md", lambda tmp: Path(tmp).write_text(_readme(out.name, meta, report)), suffix=".md")
    # meta.json last: its presence marks a complete dataset (check_output)
    for name, obj in (("report.json", report), ("meta.json", meta)):
        atomic_write(out / name, lambda tmp, o=obj: Path(tmp).write_text(json.dumps(o, indent=1)), suffix=".json")
    return report


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = dict(a.split("=", 1) for a in argv if "=" in a)
    bad = [a for a in argv if "=" not in a] + sorted(
        set(args) - {"out", "src", "seed", "train", "val", "test", "force"}
    )
    if bad or "out" not in args:
        usage = "\n".join(__doc__.strip().splitlines()[2:4])
        print(f"usage:\n{usage}\nnot understood: {bad or 'out= is missing'}", file=sys.stderr)
        return 2
    counts = {"train": int(args.get("train", 256)), "val": int(args.get("val", 16)), "test": int(args.get("test", 16))}
    repo = Path(__file__).resolve().parents[3]
    try:
        report = build(args.get("src", repo / "data" / "bandai_mini"), args["out"], counts, int(args.get("seed", 0)),
                       args.get("force", "false").lower() in ("1", "true", "yes"))  # fmt: skip
    except (PrepareError, ValueError) as err:
        print("error: " + str(err).replace("--out ", "out=").replace("--force", "force=true"), file=sys.stderr)
        return 2
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
