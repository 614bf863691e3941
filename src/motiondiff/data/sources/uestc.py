"""Loader for UESTC in the layout ACTOR and MDM read (VIBE estimates post-processed by ACTOR).

Facts reproduced (ACTOR src/datasets/uestc.py, identical in MDM data_loaders/a2m/uestc.py):
- `info/names.txt` lists the 25,600 videos `a{action}_d{view}_p{subject:03d}_c{camera}_color.avi` in the order of
  the pickle's lists; the action label is the `a` number (0..39, 40 classes), names from `info/action_classes.txt`;
- a clip uses its first min(num_frames_min.txt line, len(pose)) frames, consecutive (no subsampling);
- cross-subject split: 51 fixed training subjects, the other 67 of 1..118 test; videos of camera 2 at view 8 (the
  moving camera) are dropped from both; train keeps only clips with at least 3/4 of the model's `num_frames`
  (60 in ACTOR/MDM -> 45 frames), test keeps every clip. "val" is a deterministic stratified subset of test (10 per
  action); the official code has no val split (MDM reads "val" as test);
- the global translation is ACTOR's: (tx, ty) of VIBE's `orig_cam` and a depth from its scale (focal 500, image
  540), minus frame 0, added to `joints3d` - or `globtrans_usez.pkl` when the root has ACTOR's cache of it;
- `joints3d` holds VIBE's 49 joints (25 OpenPose + 24 extra, ACTOR src/models/smpl.py JOINT_MAP); 14 of them are
  SMPL joints (OpenPose MidHip = SMPL pelvis, ...). The SMPL-22 joints and the offsets come from those (see
  smpl_clips): feet, head, spine split, collars and hands follow the SMPL-neutral template where they are unseen.
Not reproduced: ACTOR turns camera-2 clips by -view x 45 deg about the vertical to the front view; that rigid turn is
undone by the canonical placement (facing +Z), so it is skipped. VIBE works in the camera frame (y down); the up
axis is detected per file and converted to y-up with a proper rotation. Frame rate: 20 fps, the rate MDM samples
and renders UESTC at (the videos' own rate is not used by ACTOR either). Captions are GENERATED from action names.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np

from motiondiff.data.preparing.splits import stratified_subset
from motiondiff.data.representations.clip import ClipSplit, LabelledClip
from motiondiff.data.sources.smpl_clips import action_caption, detect_up_axis, mean_rig, placed_motion, smpl_sequence
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import DatasetNotFoundError
from motiondiff.runtime.safe_pickle import load_pickle

log = logging.getLogger(__name__)

PICKLE = "vibe_cache_refined.pkl"
GLOBTRANS = "globtrans_usez.pkl"
INFO_FILES = ("info/names.txt", "info/num_frames_min.txt", "info/action_classes.txt")
LAYOUT = f"""\
  <root>/{PICKLE}   pickled dict of per-video lists, in names.txt order (ACTOR's post-processed VIBE):
    'pose'      (M, 72) float: SMPL axis-angle, 24 joints x 3, global orientation first (camera frame)
    'joints3d'  (M, 49, 3) float: VIBE joints (25 OpenPose + 24 extra), root-relative, metres
    'orig_cam'  (M, 4) float: weak-perspective camera (sx, sy, tx, ty), gives the translation
    ('pred_cam', 'betas', 'bboxes', 'frame_ids' may be present; unused)
  <root>/info/names.txt           one video per line: a<action>_d<view>_p<subject>_c<camera>_color.avi
  <root>/info/num_frames_min.txt  one frame count per line (a clip uses min(count, M) frames)
  <root>/info/action_classes.txt  40 lines: the name of action 0..39
  <root>/{GLOBTRANS}       optional: ACTOR's cache of the translations (list of (M, 3))"""
HOW_TO_GET = (
    "run ACTOR's prepare/download_datasets.sh (github.com/Mathux/ACTOR; MDM's prepare/download_a2m_datasets.sh is "
    "the same): it downloads uestc.tar.bz2 (ACTOR's post-processed VIBE estimates, see ACTOR's DATASETS.md); pass "
    "the extracted uestc/ folder as root"
)
TRAIN_SUBJECTS = frozenset([1, 2, 6, 12, 13, 16, 21, 24, 28, 29, 30, 31, 33, 35, 39, 41, 42, 45, 47, 50, 52, 54, 55,
                            57, 59, 61, 63, 64, 67, 69, 70, 71, 73, 77, 81, 84, 86, 87, 88, 90, 91, 93, 96, 99, 102,
                            103, 104, 107, 108, 112, 113])  # fmt: skip
NUM_SUBJECTS = 118
NUM_ACTIONS = 40
# VIBE/SPIN joint index -> SMPL joint (OpenPose joints that VIBE takes from the SMPL skeleton itself).
VIBE_TO_SMPL = {8: 0, 12: 1, 9: 2, 13: 4, 10: 5, 14: 7, 11: 8, 1: 12, 5: 16, 2: 17, 6: 18, 3: 19, 7: 20, 4: 21}
VIBE_NECK, VIBE_MIDHIP = 1, 8
FOCAL, IMAGE_SIZE = 500.0, 540.0  # ACTOR's get_z constants
FPS = 20.0
ACTOR_NUM_FRAMES = 60
VAL_PER_ACTION = 10
SPLITS = ("train", "val", "test")
_NAME = re.compile(r"^a(\d+)_d(\d+)_p(\d+)_c(\d+)")


def _not_found(path: Path, detail: str) -> DatasetNotFoundError:
    return DatasetNotFoundError(path, dataset="UESTC", layout=LAYOUT, how_to_get=HOW_TO_GET, detail=detail)


def _bad(path: Path, what: str) -> ValueError:
    return ValueError(f"{path}: {what}; expected layout:\n{LAYOUT}")


def parse_video_name(name: str) -> tuple[int, int, int, int]:
    """(action, view, subject, camera) of `a{action}_d{view}_p{subject}_c{camera}_color.avi`."""
    m = _NAME.match(name)
    if m is None:
        raise ValueError(f"UESTC video name {name!r} is not a<action>_d<view>_p<subject>_c<camera>_...")
    action, view, subject, camera = (int(g) for g in m.groups())
    return action, view, subject, camera


def actor_translation(joints: np.ndarray, cam: np.ndarray) -> np.ndarray:
    """ACTOR's get_trans_from_vibe (use_z=True): per frame (tx, ty, z) with z = focal * 3D height / 2D height of
    the joints under the camera (sx, sy, tx, ty), relative to frame 0. joints (M, 49, 3), cam (M, 4)."""
    xy = joints[..., :2]
    target = (cam[:, None, :1] * (xy + cam[:, None, 2:4]) + 1.0) * 0.5 * IMAGE_SIZE
    h3d = np.linalg.norm(xy.max(axis=1) - xy.min(axis=1), axis=-1)
    h2d = np.linalg.norm(target.max(axis=1) - target.min(axis=1), axis=-1)
    trans = np.stack([cam[:, 2], cam[:, 3], FOCAL * h3d / h2d], axis=-1)
    return trans - trans[:1]


def _read_lines(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()


def read_uestc(root: str | Path) -> dict:
    """The files of a UESTC root, checked against the layout: names, frames (used per video), action names, and
    per video pose (M, 72), joints3d (M, 49, 3), translation (M, 3) (lazily for ACTOR's orig_cam)."""
    root = Path(root).expanduser()
    if not root.is_dir():
        raise _not_found(root, "the dataset root does not exist")
    for rel in (PICKLE, *INFO_FILES):
        if not (root / rel).is_file():
            raise _not_found(root / rel, "required file missing")
    names = _read_lines(root / INFO_FILES[0])
    counts_path = root / INFO_FILES[1]
    try:
        counts = [int(s) for s in _read_lines(counts_path)]
    except ValueError as e:
        raise _bad(counts_path, f"not one integer per line ({e})") from None
    action_names = [s.strip() for s in _read_lines(root / INFO_FILES[2]) if s.strip()]
    if len(action_names) != NUM_ACTIONS:
        raise _bad(root / INFO_FILES[2], f"{len(action_names)} action names, expected {NUM_ACTIONS}")
    vibe = load_pickle(root / PICKLE)
    globtrans = load_pickle(root / GLOBTRANS) if (root / GLOBTRANS).is_file() else None
    _check_structure(vibe, root / PICKLE, names, counts, globtrans)
    return {"root": root, "names": names, "counts": counts, "action_names": action_names, "vibe": vibe,
            "globtrans": globtrans}  # fmt: skip


def _check_structure(vibe, path: Path, names: list[str], counts: list[int], globtrans) -> None:
    if not isinstance(vibe, dict):
        raise _bad(path, f"the pickle holds a {type(vibe).__name__}, not a dict")
    keys = ("pose", "joints3d") + (() if globtrans is not None else ("orig_cam",))
    for key in keys:
        if key not in vibe:
            raise _bad(path, f"key {key!r} missing (keys found: {sorted(map(str, vibe))})")
    sizes = {"names.txt": len(names), "num_frames_min.txt": len(counts), **{k: len(vibe[k]) for k in keys}}
    if globtrans is not None:
        sizes[GLOBTRANS] = len(globtrans)
    if len(set(sizes.values())) != 1:
        raise _bad(path, f"one entry per video is expected everywhere, found lengths {sizes}")
    for i, name in enumerate(names):
        try:
            action = parse_video_name(name)[0]
        except ValueError as e:
            raise _bad(path.parent / INFO_FILES[0], f"line {i + 1}: {e}") from None
        if not 0 <= action < NUM_ACTIONS:
            raise _bad(path.parent / INFO_FILES[0], f"line {i + 1} {name!r}: action {action} outside 0..39")
        pose, joints = np.shape(vibe["pose"][i]), np.shape(vibe["joints3d"][i])
        if np.size(vibe["pose"][i]) == 0 or np.size(vibe["joints3d"][i]) == 0:
            continue  # a video VIBE found nobody in: ACTOR keeps the entry empty; it has no frames to use
        if len(pose) != 2 or pose[1] != 72:
            raise _bad(path, f"pose[{i}] has shape {pose}, expected (M, 72)")
        if joints[1:] != (49, 3) or joints[0] < min(counts[i], pose[0]):
            raise _bad(path, f"joints3d[{i}] has shape {joints}, expected ({pose[0]}, 49, 3) like pose[{i}]")
        if "orig_cam" in keys and np.shape(vibe["orig_cam"][i]) != (pose[0], 4):
            raise _bad(path, f"orig_cam[{i}] has shape {np.shape(vibe['orig_cam'][i])}, expected ({pose[0]}, 4)")
        if globtrans is not None and np.shape(globtrans[i]) != (pose[0], 3):
            raise _bad(
                path.parent / GLOBTRANS, f"entry {i} has shape {np.shape(globtrans[i])}, expected ({pose[0]}, 3)"
            )


def split_indices(data: dict, split: str, num_frames: int = ACTOR_NUM_FRAMES) -> list[int]:
    """Video indices of a split (ACTOR's cross-subject protocol; val: stratified subset of test)."""
    if split not in SPLITS:
        raise ValueError(f"unknown UESTC split {split!r}; expected one of {SPLITS}")
    train, test = [], []
    for i, name in enumerate(data["names"]):
        _, view, subject, camera = parse_video_name(name)
        if camera != 1 and view == 8:
            continue
        if not 1 <= subject <= NUM_SUBJECTS:
            raise ValueError(f"UESTC video {name!r}: subject {subject} belongs to no split (1..{NUM_SUBJECTS})")
        (train if subject in TRAIN_SUBJECTS else test).append(i)
    if split == "train":
        return [i for i in train if used_frames(data, i) >= num_frames * 3 / 4]
    if split == "val":
        actions = [parse_video_name(data["names"][i])[0] for i in test]
        keep = stratified_subset([data["names"][i] for i in test], actions, VAL_PER_ACTION)
        return [test[k] for k in keep]
    return test


def used_frames(data: dict, i: int) -> int:
    vibe = data["vibe"]
    if np.size(vibe["pose"][i]) == 0 or np.size(vibe["joints3d"][i]) == 0:
        return 0
    return min(data["counts"][i], len(vibe["pose"][i]))


def _sequence(data: dict, i: int, up_axis: str):
    n = used_frames(data, i)
    vibe = data["vibe"]
    joints = np.asarray(vibe["joints3d"][i], dtype=np.float64)[:n]
    if data["globtrans"] is not None:
        trans = np.asarray(data["globtrans"][i], dtype=np.float64)[:n]
    else:
        trans = actor_translation(joints, np.asarray(vibe["orig_cam"][i], dtype=np.float64)[:n])
    world = joints + trans[:, None]
    positions = np.zeros((n, 24, 3))
    positions[:, list(VIBE_TO_SMPL.values())] = world[:, list(VIBE_TO_SMPL)]
    return smpl_sequence(np.asarray(vibe["pose"][i])[:n], positions, VIBE_TO_SMPL.values(), up_axis)


def load_uestc(root: str | Path, split: str = "train", num_frames: int = ACTOR_NUM_FRAMES) -> ClipSplit:
    """One split of UESTC as `LabelledClip`s on the SMPL-24 rig (rig offsets: mean over the train clips).

    `num_frames` is the model's window (ACTOR/MDM: 60); train drops clips shorter than 3/4 of it, as ACTOR does."""
    data = read_uestc(root)
    vibe = data["vibe"]
    up_axis = detect_up_axis(
        np.asarray(j)[:, VIBE_NECK] - np.asarray(j)[:, VIBE_MIDHIP] for j in vibe["joints3d"] if np.size(j)
    )
    log.info("UESTC: source up axis %s (converted to +y)", up_axis)
    indices = split_indices(data, split, num_frames)
    empty = [i for i in indices if used_frames(data, i) < 2]  # features need two frames (ACTOR fails on none)
    if empty:
        log.warning("UESTC %s: %d videos with fewer than 2 frames skipped", split, len(empty))
    indices = [i for i in indices if used_frames(data, i) >= 2]
    train = [i for i in split_indices(data, "train", num_frames) if used_frames(data, i) >= 2]
    seqs = {i: _sequence(data, i, up_axis) for i in indices}
    rig = mean_rig([(seqs[i] if i in seqs else _sequence(data, i, up_axis)).offsets for i in train])
    clips = []
    for i in indices:
        name = data["names"][i]
        action, view, subject, camera = parse_video_name(name)
        motion, placement = placed_motion(seqs[i], rig)
        action_name = data["action_names"][action]
        meta = {"captions_generated": True, "dataset": "uestc", "index": i, "video": name, "view": view,
                "subject": subject, "camera": camera, "action_name": action_name, "source_up_axis": up_axis,
                "placement": placement}  # fmt: skip
        clip_id = name.removesuffix("_color.avi")
        clips.append(LabelledClip(clip_id, motion, [action_caption(action_name)], action, meta))
    log.info("UESTC %s: %d clips", split, len(clips))
    return ClipSplit(clips=clips, action_names=data["action_names"], fps=FPS, feature_skeleton=SMPL22, rig=rig)
