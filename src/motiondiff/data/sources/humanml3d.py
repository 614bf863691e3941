"""Loaders for the official HumanML3D and KIT-ML layouts, producing the project's shared `MotionRecord`s.

Segments are cut exactly as the official `Text2MotionDatasetV2` (text-to-motion / MDM) does, so a split
gives the same clips, segments and captions as the official loader; only the segment ids differ (deterministic
here, see `segment_id`). Facts reproduced:
- clips with fewer than `min_motion_len` (40 HumanML3D, 24 KIT) or with 200 frames or more are dropped;
- caption line `caption#tokens#start#end`: NaN times read as 0.0; start == end == 0.0 means the whole motion;
- whole-motion captions of a clip form one record (id = clip id), added only if the clip has at least one;
- every other caption is its own record of `motion[int(start * 20):int(end * 20)]` (same length rules);
- ids listed in the split file whose feature or text file is missing are skipped (counted and logged here).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.data.datasets import MotionRecord
from motiondiff.runtime.errors import DatasetNotFoundError

log = logging.getLogger(__name__)

GUO_REPO = "https://github.com/EricGuo5513/HumanML3D"


@dataclass(frozen=True)
class OfficialLayout:
    """Constants of one official dataset layout."""

    key: str  # the `dataset=` name
    name: str
    feature_dim: int
    num_joints: int
    fps: float
    min_motion_len: int  # official: 40 for HumanML3D ('t2m'), 24 for KIT
    how_to_get: str
    max_motion_len: int = 196  # frames a model sees at most (the official max_motion_length)
    unit_length: int = 4  # lengths are multiples of this (the evaluator's conv encoder downsamples by 4)
    max_clip_frames: int = 200  # official: clips and segments with >= 200 frames are dropped
    # QUIRK kept on purpose: the official loader converts caption times to frames with x20 for BOTH datasets,
    # although KIT-ML runs at 12.5 fps. Published KIT numbers were computed with these (mis-timed) segments,
    # so comparable results need the same cut.
    seconds_to_frames: float = 20.0

    def describe(self) -> str:
        d, j = self.feature_dim, self.num_joints
        return "\n".join(
            [
                f"  <root>/new_joint_vecs/<id>.npy   features, float32 (N, {d})",
                f"  <root>/new_joints/<id>.npy       joint positions (N, {j}, 3) (optional for training)",
                "  <root>/texts/<id>.txt            per line: caption#word/POS word/POS ...#start#end",
                "                                    (seconds; 0.0#0.0 or nan = the whole motion)",
                f"  <root>/Mean.npy, <root>/Std.npy  normalisation statistics ({d},)",
                "  <root>/{train,val,test}.txt      one id per line",
            ]
        )


HUMANML3D = OfficialLayout(
    key="humanml3d",
    name="HumanML3D",
    feature_dim=263,
    num_joints=22,
    fps=20.0,
    min_motion_len=40,
    how_to_get=f"build it with the scripts and instructions of {GUO_REPO} (needs AMASS + HumanAct12)",
)
KIT = OfficialLayout(
    key="kit",
    name="KIT-ML",
    feature_dim=251,
    num_joints=21,
    fps=12.5,
    min_motion_len=24,
    how_to_get=f"processed KIT-ML in this layout is obtained through the instructions of {GUO_REPO} (KIT-ML)",
)
LAYOUTS: dict[str, OfficialLayout] = {HUMANML3D.key: HUMANML3D, KIT.key: KIT}


def get_layout(dataset: str) -> OfficialLayout:
    try:
        return LAYOUTS[dataset.lower()]
    except KeyError:
        raise ValueError(f"unknown official dataset {dataset!r}; expected one of {sorted(LAYOUTS)}") from None


@dataclass
class Caption:
    text: str
    tokens: list[str]  # "word/POS" strings, as written in the file (the official evaluator embeds them)
    start: float  # seconds; NaN already read as 0.0, as the official loader does
    end: float

    @property
    def whole_motion(self) -> bool:
        return self.start == 0.0 and self.end == 0.0

    def frames(self, layout: OfficialLayout) -> tuple[int, int]:
        # int() truncates, as officially (1.52 s -> 30.4 -> frame 30); Python floats: identical rounding.
        return int(self.start * layout.seconds_to_frames), int(self.end * layout.seconds_to_frames)


def _seconds(field: str) -> float:
    value = float(field)
    return 0.0 if math.isnan(value) else value


def parse_caption_line(line: str, source: Path | str = "<text>") -> Caption:
    """`caption#tokens#start#end` -> Caption. Malformed lines raise (officially: clip silently dropped)."""
    parts = line.strip().split("#")
    try:
        return Caption(parts[0], parts[1].split(" "), _seconds(parts[2]), _seconds(parts[3]))
    except (IndexError, ValueError):
        raise ValueError(
            f"{source}: malformed caption line {line.strip()!r}; expected 'caption#word/POS ...#start#end'"
        ) from None


def read_captions(path: Path) -> list[Caption]:
    lines = path.read_text(encoding="utf-8").splitlines()
    return [parse_caption_line(line, f"{path}:{i + 1}") for i, line in enumerate(lines) if line.strip()]


def read_split_ids(path: Path) -> list[str]:
    """Ids of a split file, one per line (blank lines ignored)."""
    return [s for s in (line.strip() for line in Path(path).read_text(encoding="utf-8").splitlines()) if s]


def segment_id(clip_id: str, caption: Caption, index: int) -> str:
    """`<clip>#<start>-<end>#<line>`.

    The official loader names segments `<random letter>_<clip>`, which changes from run to run (and with the
    global random state); ids here must be stable so cached features, generated samples and logs can be
    matched across runs. The caption's line index makes the id unique even when two lines share a time span.
    """
    return f"{clip_id}#{caption.start:g}-{caption.end:g}#{index}"


def _not_found(path: Path, layout: OfficialLayout, detail: str = "") -> DatasetNotFoundError:
    return DatasetNotFoundError(
        path, dataset=layout.name, layout=layout.describe(), how_to_get=layout.how_to_get, detail=detail
    )


def _width_error(path: Path, shape: tuple, layout: OfficialLayout, what: str) -> ValueError:
    other = [lay.key for lay in LAYOUTS.values() if lay.feature_dim == (shape[-1] if shape else None)]
    hint = f" (that is the width of dataset={other[0]!r})" if other and other[0] != layout.key else ""
    want = f"({layout.feature_dim},)" if what == "statistics" else f"(N, {layout.feature_dim})"
    return ValueError(f"{path}: {what} have shape {shape}, but {layout.name} expects {want}{hint}")


def check_layout(root: Path, layout: OfficialLayout, split: str) -> Path:
    """Raise DatasetNotFoundError for the first missing required path; return the split file."""
    if not root.is_dir():
        raise _not_found(root, layout, "the dataset root does not exist")
    for sub in ("new_joint_vecs", "texts"):
        if not (root / sub).is_dir():
            raise _not_found(root / sub, layout, "required folder missing")
    for name in ("Mean.npy", "Std.npy", f"{split}.txt"):
        if not (root / name).is_file():
            raise _not_found(root / name, layout, "required file missing")
    return root / f"{split}.txt"


def load_mean_std(root: Path, layout: OfficialLayout) -> tuple[np.ndarray, np.ndarray]:
    stats = []
    for name in ("Mean.npy", "Std.npy"):
        arr = np.load(root / name)
        if arr.shape != (layout.feature_dim,):
            raise _width_error(root / name, arr.shape, layout, "statistics")
        stats.append(arr.astype(np.float32))
    return stats[0], stats[1]


def load_features(path: Path, layout: OfficialLayout) -> np.ndarray:
    try:
        motion = np.load(path)  # allow_pickle stays False: an object array is refused, not unpickled
    except (ValueError, OSError, EOFError) as err:
        raise ValueError(f"{path}: not a readable .npy array ({err}); re-extract {layout.name} or drop the id "
                         "from the split file") from None  # fmt: skip
    if motion.ndim != 2 or motion.shape[1] != layout.feature_dim:
        raise _width_error(path, motion.shape, layout, "features")
    bad = ~np.isfinite(motion)
    if bad.any():
        frame = int(np.argwhere(bad)[0][0])
        raise ValueError(f"{path}: {int(bad.sum())} NaN/Inf values (first in frame {frame}); the features are "
                         f"corrupt: re-extract {layout.name} or drop the id from the split file")  # fmt: skip
    return motion


def _fits(n: int, layout: OfficialLayout) -> bool:
    return layout.min_motion_len <= n < layout.max_clip_frames


def segment_records(
    clip_id: str, motion: np.ndarray, captions: list[Caption], layout: OfficialLayout, meta: dict
) -> list[MotionRecord]:
    """The records one clip yields: its whole-motion captions together, then one per usable time span."""
    whole = [c for c in captions if c.whole_motion]
    records = []
    if whole:
        records.append(
            MotionRecord(
                id=clip_id,
                motion=motion,
                texts=[c.text for c in whole],
                meta={**meta, "frames": (0, len(motion)), "tokens": [c.tokens for c in whole]},
            )
        )
    for index, cap in enumerate(captions):
        if cap.whole_motion:
            continue
        f0, f1 = cap.frames(layout)
        part = motion[f0:f1]
        if not _fits(len(part), layout):
            continue
        span = {"frames": (f0, f0 + len(part)), "seconds": (cap.start, cap.end), "tokens": [cap.tokens]}
        rid = segment_id(clip_id, cap, index)
        records.append(MotionRecord(id=rid, motion=part, texts=[cap.text], meta={**meta, **span}))
    return records


def _warn_skipped(layout: OfficialLayout, split: str, ids: list[str], total: int, what: str) -> None:
    if ids:
        log.warning(
            "%s %s: %d of %d ids in %s.txt have no %s and were skipped (as officially); first: %s",
            layout.name, split, len(ids), total, split, what, ", ".join(ids[:5]),
        )  # fmt: skip


def load_official_split(
    root: str | Path, split: str, dataset: str = "humanml3d"
) -> tuple[list[MotionRecord], np.ndarray, np.ndarray]:
    """Records of one split of an official HumanML3D/KIT-ML root, with the root's Mean/Std (not normalised).

    Each record's meta holds `clip_id`, `frames` (start, end) in the clip, `tokens` (one list per caption,
    parallel to `texts`), `source` (the feature file), `joints_path` (when `new_joints/<id>.npy` exists; not
    loaded) and, for time-span segments, `seconds`.
    """
    layout = get_layout(dataset)
    root = Path(root).expanduser()
    split_file = check_layout(root, layout, split)
    mean, std = load_mean_std(root, layout)
    ids = read_split_ids(split_file)
    records: list[MotionRecord] = []
    no_motion, no_text, no_caption, dropped = [], [], [], 0
    for clip_id in ids:
        npy = root / "new_joint_vecs" / f"{clip_id}.npy"
        if not npy.is_file():
            no_motion.append(clip_id)
            continue
        motion = load_features(npy, layout)  # width checked before the length rules: wrong roots fail loudly
        if not _fits(len(motion), layout):
            dropped += 1
            continue
        text = root / "texts" / f"{clip_id}.txt"
        if not text.is_file():
            no_text.append(clip_id)
            continue
        meta = {"clip_id": clip_id, "dataset": layout.key, "source": str(npy)}
        joints = root / "new_joints" / f"{clip_id}.npy"
        if joints.is_file():
            meta["joints_path"] = str(joints)
        captions = read_captions(text)
        if not captions:
            no_caption.append(clip_id)
            continue
        records += segment_records(clip_id, motion, captions, layout, meta)
    if ids and len(no_motion) == len(ids):
        detail = f"none of the {len(ids)} ids of {split_file} has a .npy"
        raise _not_found(root / "new_joint_vecs", layout, detail)
    _warn_skipped(layout, split, no_motion, len(ids), "new_joint_vecs/<id>.npy")
    _warn_skipped(layout, split, no_text, len(ids), "texts/<id>.txt")
    _warn_skipped(layout, split, no_caption, len(ids), "caption line in texts/<id>.txt (empty file)")
    log.info(
        "%s %s: %d records from %d ids (%d clips outside [%d, %d) frames dropped)",
        layout.name, split, len(records), len(ids), dropped, layout.min_motion_len, layout.max_clip_frames,
    )  # fmt: skip
    return records, mean, std
