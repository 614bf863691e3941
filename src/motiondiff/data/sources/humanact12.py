"""Loader for HumanAct12 in the pickled layout ACTOR and MDM read (`HumanAct12Poses`).

Facts reproduced (ACTOR src/datasets/humanact12poses.py, MDM data_loaders/a2m/humanact12poses.py, ACTOR
src/preprocess/humanact12_process.py that wrote the file):
- one pickle, a dict of parallel lists: 'poses' (N, 72) SMPL axis-angle of 24 joints (global orientation first),
  'joints3D' (N, 24, 3) the HumanAct12 joints (the SMPL joints of the same fit), 'y' the coarse action 0..11;
- all frames of a clip are used; 12 actions named as in ACTOR's `humanact12_coarse_action_enumerator`;
- there is no held-out split: every clip trains, and the official evaluation (MDM eval/a2m/gru_eval.py) compares
  generated motions with the training clips. Here "train" and "test" are all clips; "val" is a deterministic
  stratified subset of them (10 clips per action) for cheap validation during training.
Frame rate: 20 fps, the rate MDM samples and renders HumanAct12 at (and HumanML3D imports its clips without
resampling). The up axis of the source is detected once per file (see smpl_clips.detect_up_axis) and converted to
y-up with a proper rotation; the clip is then placed canonically (floor y=0, frame-0 root at the x,z origin, facing
+Z). Captions are GENERATED from the action name (meta["captions_generated"]).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from motiondiff.data.preparing.splits import stratified_subset
from motiondiff.data.representations.clip import ClipSplit, LabelledClip
from motiondiff.data.sources.smpl_clips import (
    NECK,
    PELVIS,
    action_caption,
    detect_up_axis,
    mean_rig,
    placed_motion,
    smpl_sequence,
)
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import DatasetNotFoundError
from motiondiff.runtime.safe_pickle import load_pickle

log = logging.getLogger(__name__)

PICKLE = "humanact12poses.pkl"
LAYOUT = f"""\
  <root>/{PICKLE}   pickled dict of parallel lists, one entry per clip (ACTOR's HumanAct12Poses):
    'poses'     (N, 72) float: SMPL axis-angle, 24 joints x 3, global orientation first
    'joints3D'  (N, 24, 3) float: SMPL joint positions, metres
    'y'         int 0..11: coarse action label
    ('oldposes' may be present; unused)"""
HOW_TO_GET = (
    "run ACTOR's prepare/download_datasets.sh (github.com/Mathux/ACTOR; MDM's prepare/download_a2m_datasets.sh is "
    f"the same): it downloads HumanAct12Poses.tar.gz, whose HumanAct12Poses/ folder holds {PICKLE}; pass that folder "
    "as root. See ACTOR's DATASETS.md (built from PHSPD + HumanAct12 by src/preprocess/humanact12_process.py)"
)
ACTION_NAMES = ("warm_up", "walk", "run", "jump", "drink", "lift_dumbbell", "sit", "eat", "turn steering wheel",
                "phone", "boxing", "throw")  # fmt: skip
FPS = 20.0
VAL_PER_ACTION = 10
SPLITS = ("train", "val", "test")


def _not_found(path: Path, detail: str) -> DatasetNotFoundError:
    return DatasetNotFoundError(path, dataset="HumanAct12", layout=LAYOUT, how_to_get=HOW_TO_GET, detail=detail)


def read_humanact12(root: str | Path) -> tuple[list[np.ndarray], list[np.ndarray], list[int]]:
    """(poses (N, 72), joints3D (N, 24, 3), action) per clip, checked against the layout."""
    root = Path(root).expanduser()
    if not root.is_dir():
        raise _not_found(root, "the dataset root does not exist")
    path = root / PICKLE
    if not path.is_file():
        raise _not_found(path, "required file missing")
    data = load_pickle(path)
    return _check_structure(data, path)


def _check_structure(data, path: Path):
    def bad(what: str) -> ValueError:
        return ValueError(f"{path}: {what}; expected layout:\n{LAYOUT}")

    if not isinstance(data, dict):
        raise bad(f"the pickle holds a {type(data).__name__}, not a dict")
    for key in ("poses", "joints3D", "y"):
        if key not in data:
            raise bad(f"key {key!r} missing (keys found: {sorted(map(str, data))})")
    poses, joints, labels = data["poses"], data["joints3D"], data["y"]
    sizes = {k: len(data[k]) for k in ("poses", "joints3D", "y")}
    if len(set(sizes.values())) != 1:
        raise bad(f"'poses', 'joints3D' and 'y' must have one entry per clip, found lengths {sizes}")
    out_poses, out_joints, out_labels = [], [], []
    for i, (p, j, y) in enumerate(zip(poses, joints, labels, strict=True)):
        p, j = np.asarray(p), np.asarray(j)
        if p.ndim != 2 or p.shape[1] != 72:
            raise bad(f"poses[{i}] has shape {p.shape}, expected (N, 72)")
        if j.shape != (len(p), 24, 3):
            raise bad(f"joints3D[{i}] has shape {j.shape}, expected ({len(p)}, 24, 3) to match poses[{i}]")
        if not _is_label(y, len(ACTION_NAMES)):
            raise bad(f"y[{i}] is {y!r}, expected an action id in 0..{len(ACTION_NAMES) - 1}")
        out_poses.append(p)
        out_joints.append(j)
        out_labels.append(int(y))
    return out_poses, out_joints, out_labels


def _is_label(y, count: int) -> bool:
    return np.ndim(y) == 0 and np.issubdtype(np.asarray(y).dtype, np.integer) and 0 <= int(y) < count


def split_indices(labels: list[int], split: str) -> list[int]:
    """Clip indices of a split: all for train/test (the official protocol), a stratified subset for val."""
    if split not in SPLITS:
        raise ValueError(f"unknown HumanAct12 split {split!r}; expected one of {SPLITS}")
    if split == "val":
        return stratified_subset([clip_id(i) for i in range(len(labels))], labels, VAL_PER_ACTION)
    return list(range(len(labels)))


def clip_id(index: int) -> str:
    return f"humanact12_{index:04d}"  # the pickle has no names: its order is the official index


def load_humanact12(root: str | Path, split: str = "train") -> ClipSplit:
    """One split of HumanAct12 as `LabelledClip`s on the SMPL-24 rig (rig offsets: mean over the train clips)."""
    poses, joints, labels = read_humanact12(root)
    indices = split_indices(labels, split)
    up_axis = detect_up_axis(j[:, NECK] - j[:, PELVIS] for j in joints)
    log.info("HumanAct12: source up axis %s (converted to +y)", up_axis)
    usable = [i for i in range(len(poses)) if len(poses[i]) >= 2]  # canonical features need two frames
    if len(usable) < len(poses):
        log.warning("HumanAct12: %d clips with fewer than 2 frames skipped", len(poses) - len(usable))
    seqs = {i: smpl_sequence(poses[i], joints[i], range(24), up_axis) for i in usable}
    # train is every clip, so the rig of every split is the mean over all usable clips
    rig = mean_rig([seqs[i].offsets for i in split_indices(labels, "train") if i in seqs])
    clips = []
    for i in indices:
        if i not in seqs:
            continue
        motion, placement = placed_motion(seqs[i], rig)
        name = ACTION_NAMES[labels[i]]
        meta = {"captions_generated": True, "dataset": "humanact12", "index": i, "action_name": name,
                "source_up_axis": up_axis, "placement": placement}  # fmt: skip
        clips.append(LabelledClip(clip_id(i), motion, [action_caption(name)], labels[i], meta))
    log.info("HumanAct12 %s: %d clips", split, len(clips))
    return ClipSplit(clips=clips, action_names=list(ACTION_NAMES), fps=FPS, feature_skeleton=SMPL22, rig=rig)
