"""The prepared-dataset format: one npz per split (train/val/test) + Mean.npy/Std.npy + meta.json in one folder.

Clips have different lengths, so per-frame arrays are concatenated over clips and `frame_offsets` (C+1) says where
each clip starts. Arrays (C clips, F frames in all, J native joints):

    ids, dataset, content, style, action (C)       clip id, source dataset, label ids (names in *_names)
    lengths (C), frame_offsets (C+1)               frames per clip at `fps` (20)
    joints (F, 22, 3)                              canonical SMPL-22 joints, metres (HumanML3D's new_joints)
    features (F - C, 263)                          HumanML3D features, N-1 rows per clip          [derived]
    native_rotations (F, J, 4), native_root (F, 3) local joint quaternions (w,x,y,z) + root position
    native_positions (F, J, 3)                     FK of the above, metres                          [derived]
    native_joint_names, native_parents (J), native_offsets (C, J, 3)   bone offsets per clip (performers differ)
    captions (K), caption_offsets (C+1)            captions; GENERATED ones are flagged by captions_generated:
    captions_generated ()  or (C)                   one flag for all clips, or one per clip where a labels file
                                                   gave human-written captions for some (the `bvh` source)

"[derived]" arrays may be left out ("compact", used for the embedded dataset to stay small): loading recomputes
them with the very same functions that made them, so both forms load to identical arrays.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.data.datasets import MotionRecord
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import features_from_canonical
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.errors import DatasetNotFoundError

SPLITS = ("train", "val", "test")
DERIVED = ("features", "native_positions")
PREPARED_LAYOUT = """  {root}/train.npz, {root}/val.npz, {root}/test.npz   one npz per split
  {root}/Mean.npy, {root}/Std.npy                     feature statistics of the train split
  {root}/meta.json                                     labels, skeleton, caption note, source"""


def save_split(path: Path, arrays: dict[str, np.ndarray], compact: bool = False) -> None:
    arrays = {k: v for k, v in arrays.items() if not (compact and k in DERIVED)}
    atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays), suffix=".npz")


@dataclass
class PreparedSplit:
    """One split of a prepared dataset, with every array (derived ones recomputed when stored compact)."""

    arrays: dict[str, np.ndarray]
    mean: np.ndarray
    std: np.ndarray
    meta: dict

    @property
    def num_clips(self) -> int:
        return len(self.arrays["ids"])

    def clip_slice(self, i: int) -> slice:
        o = self.arrays["frame_offsets"]
        return slice(int(o[i]), int(o[i + 1]))

    def feature_slice(self, i: int) -> slice:
        o = self.arrays["frame_offsets"]
        return slice(int(o[i]) - i, int(o[i + 1]) - i - 1)  # each clip has one row fewer than frames

    def captions(self, i: int) -> list[str]:
        o = self.arrays["caption_offsets"]
        return [str(c) for c in self.arrays["captions"][o[i] : o[i + 1]]]

    def captions_generated(self, i: int) -> bool:
        flags = np.asarray(self.arrays.get("captions_generated", True))
        return bool(flags if flags.ndim == 0 else flags[i])

    def label(self, kind: str, i: int) -> str:
        return str(self.arrays[f"{kind}_names"][self.arrays[kind][i]])

    def rig(self) -> Skeleton:
        """The native rotation skeleton with the mean bone offsets of this split's clips (performers differ)."""
        a = self.arrays
        offsets = a["native_offsets"].astype(np.float64).mean(axis=0)
        names = [str(n) for n in a["native_joint_names"]]
        return Skeleton.infer("native", names, a["native_parents"], offsets, fps=float(a["fps"]))

    def clips(self) -> list[ClipMotion]:
        """Every clip's canonical SMPL-22 joints and native local rotations (what representations encode)."""
        a, rig = self.arrays, self.rig()
        out = []
        for i in range(self.num_clips):
            s = self.clip_slice(i)
            out.append(
                ClipMotion(
                    joints=a["joints"][s],
                    rotations=a["native_rotations"][s],
                    root=a["native_root"][s],
                    offsets=a["native_offsets"][i].astype(np.float64),
                    rig=rig,
                )
            )
        return out

    def records(self) -> list[MotionRecord]:
        feats = self.arrays["features"]
        return [
            MotionRecord(
                id=str(self.arrays["ids"][i]),
                motion=feats[self.feature_slice(i)],
                texts=self.captions(i),
                action=int(self.arrays["action"][i]),
                meta={
                    "content": self.label("content", i),
                    "style": self.label("style", i),
                    "captions_generated": self.captions_generated(i),
                },
            )
            for i in range(self.num_clips)
        ]


def load_split(root: str | Path, split: str) -> PreparedSplit:
    root = Path(root)
    if split not in SPLITS:
        raise ValueError(f"unknown split {split!r}; choose from {SPLITS}")
    needed = [root / f"{split}.npz", root / "Mean.npy", root / "Std.npy", root / "meta.json"]
    missing = [p for p in needed if not p.is_file()]
    if missing:
        raise DatasetNotFoundError(
            missing[0],
            dataset="prepared dataset",
            layout=PREPARED_LAYOUT.format(root=root),
            how_to_get=f"python -m motiondiff.data.preparing.prepare bandai --src <zip or folder> --out {root}",
            detail=f"{len(missing)} of the prepared files are missing",
        )
    with np.load(needed[0], allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    fill_derived(arrays)
    return PreparedSplit(arrays, np.load(needed[1]), np.load(needed[2]), json.loads(needed[3].read_text()))


def fill_derived(arrays: dict[str, np.ndarray]) -> None:
    """Recompute arrays left out of a compact file (same functions as `prepare`, so results are identical)."""
    offsets = arrays["frame_offsets"]
    clips = range(len(offsets) - 1)
    if "features" not in arrays:
        arrays["features"] = np.concatenate(
            [features_from_canonical(arrays["joints"][offsets[i] : offsets[i + 1]]) for i in clips]
        )
    if "native_positions" not in arrays:
        translations = np.repeat(arrays["native_offsets"], np.diff(offsets), axis=0)
        translations[:, 0] = arrays["native_root"]
        pos, _ = forward_kinematics(arrays["native_rotations"], translations, arrays["native_parents"])
        arrays["native_positions"] = pos.astype(np.float32)
