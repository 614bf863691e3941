"""The motion to edit, in the model's representation: from a BVH file, a joints .npy or a dataset clip.

Input motions are encoded exactly as the model's training data was (same joint map, 20 fps, canonical placement,
same representation), so an edit starts from what the model knows how to continue.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf

from motiondiff.data.formats.array_bounds import check_array_file
from motiondiff.data.formats.bvh import BVHError, read_bvh
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import SPLITS, load_split
from motiondiff.data.formats.smpl_params import SmplParamsError, is_smpl_params, load_smpl_body, read_smpl_params
from motiondiff.data.formats.up_axis import UpAxis, bvh_up_axis, detect_up_axis, parse_up_axis, undecided
from motiondiff.data.preparing.processing import TARGET_FPS, ClipError, process_motion
from motiondiff.data.representations import Representation
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import canonicalize_joints, ground_and_face, skeleton_for_dim
from motiondiff.edit.canonical import carries_placement, placement, to_canonical
from motiondiff.edit.input_files import check_input_file
from motiondiff.edit.masks import EditError
from motiondiff.geometry.rotations import qrot
from motiondiff.geometry.skeleton import Skeleton, get_skeleton
from motiondiff.runtime.paths import REPO_DIR, work_dir

MIN_INPUT_FRAMES = 4  # at least a kept frame on each side of a gap and something to generate
SPLIT_ORDER = ("test", "val", "train")  # where a bare clip id is looked up, in this order

log = logging.getLogger(__name__)


@dataclass
class InputMotion:
    """A motion to edit, in the model's representation.

    features  (N, D) de-normalised features (the window of the input that is edited)
    joints    (N, J, 3) the features decoded: the input as the model's representation sees it (its skeleton)
    """

    features: np.ndarray
    joints: np.ndarray
    source: str
    fps: float
    window: tuple[int, int]  # input frames [start, stop) that were encoded (the model has a maximum length)
    total_frames: int  # frames of the whole input (at the model's fps)
    clip_id: str | None = None
    split: str | None = None
    label: str | None = None  # the dataset's content label (action models are conditioned on these)
    captions: list[str] = field(default_factory=list)
    up: UpAxis | None = None  # a file's up axis (detected or forced) before it was turned to Y-up; None: dataset

    @property
    def num_frames(self) -> int:
        return len(self.features)


def load_input_motion(
    source: str | os.PathLike,
    module,
    *,
    data_root: str | os.PathLike | None = None,
    start: int = 0,
    frames: int | None = None,
    up_axis: str = "auto",
    smpl_model: str | os.PathLike | None = None,
    bvh=None,
) -> InputMotion:
    """The motion to edit, encoded in the model's representation.

    ``source``: a ``.bvh`` file (prepared like the dataset: joint map to SMPL-22, 20 fps, canonical placement, rig
    rotations for rotation representations), a ``.npy`` of joints (frames, J, 3) in metres at the model's fps on
    the representation's skeleton (hml263/kit251/jp only; a ``.npz`` holding such an array as ``joints`` or as its
    only array), an ``.npz`` of SMPL parameters (AMASS, export=smpl; `data.formats.smpl_params`: its 22 body joints,
    prepared like a BVH file; ``smpl_model``: the SMPL body model .npz for files that do not record their skeleton),
    or a dataset clip id, ``split:clip_id`` or a bare id looked up in ``data_root`` (default: the data the model was
    trained on).

    ``up_axis``: which way is up in a file: "auto" detects it (the axis the head sits above the feet along, see
    `motiondiff.data.formats.up_axis`; a file it cannot decide warns with `UpAxisWarning` and is read as Y-up), or
    "y", "z", "x", "-y", "-z", "-x" force it. The file is turned to Y-up before anything else; ``InputMotion.up``
    says what was found.

    ``start``/``frames``: the window to edit, from input frame ``start``, ``frames`` edited frames (default: as many
    as the model's maximum length allows). A file's window is cut before it is prepared, as `prepare` cuts long
    clips, so it starts at the origin facing +Z like every training clip. ``bvh``: the file already read
    (`read_bvh_input`, before the model loads).
    """
    text = str(source)
    path = Path(text)
    try:
        parse_up_axis(up_axis)
    except ValueError as err:
        raise EditError(str(err)) from None
    if path.suffix.lower() in (".bvh", ".npy", ".npz"):
        check_input_file(path)
        if path.suffix.lower() != ".bvh":
            _check_array_sizes(path)
        if path.suffix.lower() == ".bvh" or _holds_smpl_params(path):
            motion, units = (bvh, None) if bvh is not None else _read_motion(path, smpl_model)
            features, window, total, up = _bvh_features(path, motion, units, module, start, frames, up_axis)
        else:
            features, window, total, up = _npy_features(path, module, start, frames, up_axis)
        return _input_motion(module, features, text, window, total, {"up": up})
    if path.is_dir():
        raise EditError(f"input {path} is a folder: give a .bvh/.npy/.npz file inside it, or a dataset clip id")
    if os.path.lexists(path) and not path.is_file():  # a device, pipe or broken link: a path, not a clip id
        check_input_file(path)
    if path.is_file():
        raise EditError(f"input {path} is a {path.suffix or 'suffix-less'} file; edit reads .bvh, .npy (joints), .npz "
                        "(joints or SMPL parameters), or a dataset clip id")  # fmt: skip
    features, info = _dataset_features(text, module, data_root)
    return _dataset_window(module, features, text, start, frames, info)


def _input_motion(module, features, source: str, window, total: int, info: dict) -> InputMotion:
    rep: Representation = module.representation
    features = np.asarray(features, dtype=np.float32)
    joints = rep.decode_numpy(features).astype(np.float32)
    return InputMotion(features, joints, source, float(module.hparams.fps), window, total, **info)


def _dataset_window(module, features: np.ndarray, source: str, start: int, frames: int | None, info: dict):
    """A window of an encoded dataset clip; one that starts later is turned and moved so its first frame stands at
    the origin facing +Z (hml features carry no placement and need nothing)."""
    rep: Representation = module.representation
    total = len(features) + rep.frames_dropped
    window = frame_window(total, rep.frames_dropped, start, frames, int(module.hparams.max_frames), source)
    rows = np.asarray(features[window[0] : window[1] - rep.frames_dropped], dtype=np.float64)
    if window[0] > 0 and carries_placement(rep):
        rows = to_canonical(rep, rows, *placement(rep, rows, 0))
    return _input_motion(module, rows, source, window, total, info)


def dataset_motions(module, split: str = "test", data_root=None, frames: int | None = None) -> list[InputMotion]:
    """Every clip of a prepared dataset's split (default: the model's training data) with at least
    MIN_INPUT_FRAMES frames, as input motions (each cut to the model's maximum length, or ``frames``)."""

    root = Path(data_root) if data_root is not None else training_data_root(module)
    if root is None or not (root / "meta.json").is_file():
        raise EditError(
            f"no prepared dataset at {root}; pass data_root=<a folder made by motiondiff.data.preparing.prepare>"
        )
    data = load_split(root, split)
    motions = []
    for i in range(data.num_clips):
        feats = _encode_prepared(data, i, module, root)
        if len(feats) < MIN_INPUT_FRAMES:
            continue
        clip_id = str(data.arrays["ids"][i])
        info = {"clip_id": clip_id, "split": split, "label": data.label("content", i), "captions": data.captions(i)}
        n = None if frames is None else min(frames, len(feats))
        motions.append(_dataset_window(module, feats, f"{split}:{clip_id}", 0, n, info))
    return motions


def frame_window(total: int, dropped: int, start: int, frames: int | None, max_rows: int, source: str):
    """Input frames [start, stop) that encode to ``frames`` feature rows (default: as many as fit, at most
    ``max_rows``, the model's maximum); a representation drops ``dropped`` frames (hml: 1, the last velocity)."""
    if not 0 <= start < total:
        raise EditError(f"start={start} is outside the input {source!r}, which has {total} frames")
    available = total - start - dropped
    rows = min(available, max_rows) if frames is None else int(frames)
    if rows > max_rows:
        raise EditError(f"{rows} frames is longer than this model's maximum of {max_rows}; edit a shorter window")
    if rows < MIN_INPUT_FRAMES or rows > available:
        raise EditError(
            f"the input {source!r} has {total} frames: {rows} frames from frame {start} do not fit "
            f"(at least {MIN_INPUT_FRAMES} frames are needed)"
        )
    return start, start + rows + dropped


def feature_skeleton(module) -> Skeleton:
    """The skeleton the model's dataset measured joints on (SMPL-22 or KIT-21)."""
    spec = module.hparams.get("representation")
    return get_skeleton(spec["feature_skeleton"]) if spec else skeleton_for_dim(int(module.hparams.feature_dim))


def _uses_rig(rep: Representation) -> bool:
    return rep.needs_rotations or bool(getattr(rep, "uses_rig", False))


def _load_joints(path: Path) -> np.ndarray:
    """The joints array of a .npy, or of a .npz (its ``joints`` array, or its only array)."""
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as err:
        raise EditError(f"{path}: not a readable {path.suffix} array ({err})") from None
    if not isinstance(data, np.lib.npyio.NpzFile):
        return data
    with data:
        names = list(data.files)
        if "joints" in names or len(names) == 1:
            try:
                return data["joints" if "joints" in names else names[0]]
            except (ValueError, OSError, EOFError) as err:
                raise EditError(f"{path}: its joints array cannot be read ({err})") from None
    raise EditError(f"{path}: holds arrays {', '.join(names) or '(none)'}; name the joint positions 'joints' "
                    "(np.savez(path, joints=...)) or save them alone as .npy")  # fmt: skip


def joints_up_axis(joints: np.ndarray, skeleton: Skeleton, up_axis: str = "auto", source: str = "<joints>") -> UpAxis:
    """The up axis of joints (F, J, 3) on `skeleton` (its head: the last joint of its "head" part; its feet: the
    foot joints), by `motiondiff.data.formats.up_axis.detect_up_axis`."""
    head = skeleton.parts.get("head", ())
    feet = [j for side in skeleton.foot_joints for j in side]
    if parse_up_axis(up_axis) is None and not (head and feet):
        return undecided(source, f"its skeleton {skeleton.name} names no head or no feet to tell it from")
    return detect_up_axis(joints, head[-1] if head else 0, feet or [0], up_axis=up_axis, source=source)


def _npy_features(path: Path, module, start: int, frames: int | None, up_axis: str = "auto"):
    rep: Representation = module.representation
    if _uses_rig(rep) and rep.name != "jp":
        raise EditError(
            f"this model's representation {rep.name} needs joint rotations, which a file of joint positions does "
            "not have; give a .bvh file or a dataset clip id"
        )
    joints = _load_joints(path)
    if joints.dtype.kind != "f":
        raise EditError(f"{path}: holds {joints.dtype}, expected floating-point joint positions in metres (float32 "
                        "or float64)")  # fmt: skip
    skel = rep.skeleton
    if joints.ndim != 3 or joints.shape[1:] != (skel.num_joints, 3):
        raise EditError(
            f"{path}: joints of shape {joints.shape}, but this model ({rep.name}) reads (frames, {skel.num_joints}, "
            f"3) joints of its {skel.name} skeleton, metres, at {module.hparams.fps:g} fps (any up axis; "
            "up_axis= forces it); joint order: " + ", ".join(skel.joint_names)
        )
    if not np.isfinite(joints).all():
        raise EditError(f"{path}: joint positions contain NaN or Inf")
    up = joints_up_axis(joints, skel, up_axis, str(path))
    joints = joints.astype(np.float64) @ up.matrix.T  # turned to Y-up before anything else
    window = frame_window(len(joints), rep.frames_dropped, start, frames, int(module.hparams.max_frames), str(path))
    part = joints[window[0] : window[1]].astype(np.float64)
    if rep.name == "jp" and _uses_rig(rep):  # rig joints: the native skeleton's placement rule, its own bones
        placed = place_like_dataset(part, skel)
        return placed.reshape(len(placed), -1), window, len(joints), up
    canonical = canonicalize_joints(part, skel).astype(np.float32)  # as the dataset did (uniform skeleton)
    return rep.encode(ClipMotion(joints=canonical)), window, len(joints), up


def place_like_dataset(joints: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Rig joints moved rigidly as `prepare` placed the native skeleton: lowest joint on the floor, frame 0's root
    at the x/z origin facing +Z (as given when the skeleton has no facing joints)."""

    if skeleton.face_joints is None:
        return joints
    turn, shift = ground_and_face(joints, skeleton)
    return qrot(np.broadcast_to(turn, joints.shape[:-1] + (4,)), joints + shift)


def _check_array_sizes(path: Path) -> None:
    """EditError for a .npy/.npz whose arrays would take more than MAX_ARRAY_BYTES (read from its headers)."""

    try:
        check_array_file(path)
    except ValueError as err:
        raise EditError(str(err)) from None


def _holds_smpl_params(path: Path) -> bool:

    if path.suffix.lower() != ".npz":
        return False
    try:
        with np.load(path, allow_pickle=False) as data:
            return is_smpl_params(data.files)
    except (ValueError, OSError, EOFError) as err:
        raise EditError(f"{path}: not a readable .npz array ({err})") from None


def read_bvh_input(source: str | os.PathLike):
    """The BVHMotion of a ``.bvh`` input (EditError for a bad file), None for any other input: read before the model
    loads, so a bad file is refused at once."""
    path = Path(str(source))
    if path.suffix.lower() != ".bvh" or not path.is_file():
        return None
    check_input_file(path)  # unreadable by this user: said as such, not as a folder to write to
    return _read_motion(path, None)[0]


def _read_motion(path: Path, smpl_model) -> tuple[object, float | None]:
    """A BVH file, or an SMPL parameter file's body joints, as a BVHMotion; with its units when they are known
    (SMPL: metres; a BVH's are guessed from its skeleton)."""

    try:
        if path.suffix.lower() == ".bvh":
            return read_bvh(path), None
        return read_smpl_params(path, None if smpl_model is None else load_smpl_body(smpl_model)), 1.0
    except (BVHError, SmplParamsError) as err:
        raise EditError(str(err)) from None


def _bvh_features(path: Path, motion, units, module, start: int, frames: int | None, up_axis: str = "auto"):
    """Features of a window of a BVH-like motion (a BVH file, SMPL parameters), turned to Y-up (`bvh_up_axis`),
    then prepared exactly as `prepare` prepares a clip cut to a window."""

    rep: Representation = module.representation
    target = feature_skeleton(module)
    if target.name != "smpl22":
        raise EditError(
            f"BVH input is mapped to SMPL-22, but this model's dataset uses the {target.name} skeleton; give a .npy "
            f"of its joints instead"
        )
    if float(module.hparams.fps) != TARGET_FPS:
        raise EditError(f"BVH input is prepared at {TARGET_FPS:g} fps, but this model runs at {module.hparams.fps} fps")
    joint_map = _bvh_joint_map(module, motion, path, units)
    smpl = path.suffix.lower() != ".bvh"  # an SMPL parameter file: its rest pose is the Y-up template, no evidence
    up = bvh_up_axis(motion, joint_map, up_axis=up_axis, rest_pose=not smpl)
    turn = None if up.axis == "+y" else up.matrix  # a change of basis: offsets, End Sites and rotations turn with it
    total = motion.resampled_frames(TARGET_FPS)
    window = frame_window(total, rep.frames_dropped, start, frames, int(module.hparams.max_frames), str(path))
    try:  # only the window is resampled and turned (a long capture's other frames never are)
        clip = process_motion(motion, joint_map, window=window, turn=turn)
    except ClipError as err:
        raise EditError(f"{path}: {err}") from None
    if not _uses_rig(rep):
        return rep.encode(ClipMotion(joints=clip.joints)), window, total, up
    rig = rep.skeleton
    if tuple(clip.native.joint_names) != tuple(rig.joint_names) or tuple(clip.native.parents) != tuple(rig.parents):
        raise EditError(
            f"{path}: its skeleton ({len(clip.native.joint_names)} joints: {', '.join(clip.native.joint_names[:6])}, "
            f"...) is not this model's rig ({rig.num_joints} joints: {', '.join(rig.joint_names[:6])}, ...); "
            f"{rep.name} needs the same rig: use a model with hml263 features or a BVH of the training skeleton"
        )
    offsets = clip.native.offsets.astype(np.float64)
    features = rep.encode(ClipMotion(clip.joints, clip.native_rotations, clip.native_root, offsets, rig))
    return features, window, total, up


def _bvh_joint_map(module, motion, path: Path, units: float | None = None):
    """The joint map the model's dataset was prepared with when the file has its joints, else one inferred from
    the joint names (as `prepare bvh --joint-map auto`; `units`: metres per file unit when known)."""

    spec = module.hparams.get("representation") or {}
    if spec.get("joint_map"):
        known = JointMap(**spec["joint_map"])
        if known.source_joints() <= set(motion.joint_names):
            return known
    try:
        return JointMap.infer(motion.joint_names, motion.parents, offsets=motion.offsets, source=f"auto({path.name})",
                              units_to_metres=units)  # fmt: skip
    except ValueError as err:
        raise EditError(f"{path}: cannot map its joints to SMPL-22: {err}") from None


def training_data_root(module, data_dir: str | os.PathLike | None = None, cache_dir=None) -> Path | None:
    """Where the model's training dataset lives: the ``root`` of conf/dataset/<name>.yaml (the ``bvh`` dataset's
    prepared cache), resolved with ``data_dir``/``cache_dir`` (default: $MOTIONDIFF_DATA_DIR or the checkout's
    data/, $MOTIONDIFF_CACHE_DIR or .cache/motiondiff). None when the checkpoint names no dataset."""
    name = module.hparams.get("dataset") or ""
    if not name:
        return None
    data_dir = Path(data_dir or os.environ.get("MOTIONDIFF_DATA_DIR", REPO_DIR / "data"))
    cache_dir = Path(cache_dir or os.environ.get("MOTIONDIFF_CACHE_DIR", work_dir() / ".cache" / "motiondiff"))
    conf = REPO_DIR / "conf" / "dataset" / f"{name}.yaml"
    if not conf.is_file():
        return data_dir / name
    cfg = OmegaConf.merge(
        {"paths": {"data_dir": str(data_dir), "cache_dir": str(cache_dir)}}, {"dataset": OmegaConf.load(conf)}
    )
    return Path(cfg.dataset.datamodule.cache if name == "bvh" else cfg.dataset.root)


# A dataset whose clips the checkout ships a real subset of, with the same features and clip ids: a model trained on
# the full Bandai data looks clip ids up in the embedded data/bandai_mini until `make data-full` prepares data/bandai.
EMBEDDED_SUBSETS = {"bandai": "bandai_mini"}


def clip_data_root(module, data_dir=None, cache_dir=None) -> Path | None:
    """Where clip ids of the model's training data are looked up: its dataset folder (`training_data_root`), or the
    checkout's embedded real subset of it while the full dataset is not prepared."""
    root = training_data_root(module, data_dir, cache_dir)
    subset = EMBEDDED_SUBSETS.get(module.hparams.get("dataset") or "")
    if subset and (root is None or not root.is_dir()) and (REPO_DIR / "data" / subset).is_dir():
        log.info("%s is not prepared (make data-full): clip ids are looked up in the embedded data/%s", root, subset)
        return REPO_DIR / "data" / subset
    return root


def _dataset_features(spec: str, module, data_root) -> tuple[np.ndarray, dict]:
    split, _, clip_id = spec.rpartition(":")
    root = Path(data_root) if data_root is not None else clip_data_root(module)
    if root is None or not root.is_dir():
        raise EditError(
            f"input {spec!r} is not a .bvh or .npy file, and there is no dataset to look it up as a clip id in "
            f"({root or 'the checkpoint names no dataset'}); pass a file, or the dataset folder with data=<folder>"
        )
    if (root / "meta.json").is_file():
        return _prepared_clip(root, split, clip_id, module)
    official = root / "new_joint_vecs" / f"{clip_id}.npy"
    if official.is_file() and module.representation.name in ("hml263", "kit251"):
        return np.load(official).astype(np.float32), {"clip_id": clip_id, "captions": _official_captions(root, clip_id)}
    raise EditError(
        f"no clip {clip_id!r} in {root}: clip ids are looked up in a prepared dataset (meta.json, <split>.npz) or "
        "an official HumanML3D/KIT-ML folder (new_joint_vecs/<id>.npy); check the id or pass a .bvh/.npy file"
    )


def _official_captions(root: Path, clip_id: str) -> list[str]:
    path = root / "texts" / f"{clip_id}.txt"
    lines = path.read_text().splitlines() if path.is_file() else []
    return [line.split("#")[0].strip() for line in lines if line.strip()]


def _prepared_clip(root: Path, split: str, clip_id: str, module) -> tuple[np.ndarray, dict]:

    if split and split not in SPLITS:
        raise EditError(f"unknown split {split!r} in {split}:{clip_id}; choose from {', '.join(SPLITS)}")
    examples = []
    for name in [split] if split else SPLIT_ORDER:
        data = load_split(root, name)
        ids = [str(i) for i in data.arrays["ids"]]
        if clip_id in ids:
            i = ids.index(clip_id)
            info = {"clip_id": clip_id, "split": name, "label": data.label("content", i), "captions": data.captions(i)}
            return _encode_prepared(data, i, module, root), info
        examples += [f"{name}:{c}" for c in ids[:2]]
    where = f"the {split} split" if split else f"the {', '.join(SPLIT_ORDER)} splits"
    raise EditError(f"no clip {clip_id!r} in {where} of {root}; clip ids look like {', '.join(examples[:3])}")


def _encode_prepared(data, i: int, module, root: Path) -> np.ndarray:
    rep: Representation = module.representation
    a, s = data.arrays, data.clip_slice(i)
    if float(data.meta.get("fps", 20.0)) != float(module.hparams.fps):
        raise EditError(f"{root} is at {data.meta.get('fps')} fps, but this model runs at {module.hparams.fps} fps")
    if not _uses_rig(rep):
        return rep.encode(ClipMotion(joints=a["joints"][s]))
    names, parents = tuple(str(n) for n in a["native_joint_names"]), tuple(int(p) for p in a["native_parents"])
    if names != tuple(rep.skeleton.joint_names) or parents != tuple(rep.skeleton.parents):
        raise EditError(f"{root} is stored on another rig than this model's {rep.name} rig; pass data=<its dataset>")
    clip = ClipMotion(a["joints"][s], a["native_rotations"][s], a["native_root"][s],
                      a["native_offsets"][i].astype(np.float64), rep.skeleton)  # fmt: skip
    return rep.encode(clip)
