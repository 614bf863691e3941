"""`evaluate.py evaluator=official`: the papers' own evaluators, fed as their code feeds them.

- HumanML3D / KIT: Guo et al.'s text-motion matching model (`finest.tar`), its GloVe table, and the evaluator's own
  meta mean/std (the dataset statistics with the std of the root, velocity and foot-contact blocks divided by
  feat_bias 5 when the evaluator was trained; read from the meta files, derived only when they are absent).
- HumanAct12: action-to-motion's GRU classifier on the 24 SMPL joints (72-d per frame), as MDM/ACTOR compute them:
  joint positions of the model's own rig (FK of its rotations), in the source data's axes, relative to the first
  frame's root joint.
- UESTC: ACTOR's ST-GCN recognition model on the 6D rotations of the 24 SMPL joints (`motiondiff.models.evaluators.stgcn`); MDM
  Table 4 reports FID against the train and the test clips.

Our datasets are canonicalised when loaded (y up, frame-0 root at the x/z origin facing +z). Motion goes back to the
source's axes with the inverse of the loader's up-axis rotation, for generated and real clips alike; the per-clip
heading turn of the canonical placement is not undone (a generated motion has none to undo).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch

from motiondiff.data.representations import JointPositions, RotationRepresentation
from motiondiff.data.representations.hml_features import feature_slices
from motiondiff.data.representations.spec import representation_from_spec
from motiondiff.data.sources.smpl_clips import UP_TO_Y
from motiondiff.eval.protocol import Evaluators, pad
from motiondiff.geometry.rotations import quat_to_matrix
from motiondiff.model_files.evaluators import load_official_action_classifier, load_official_t2m_evaluator
from motiondiff.models.evaluators.stgcn import load_official_uestc_recognition

log = logging.getLogger(__name__)

FEAT_BIAS = 5.0  # the official evaluator's weighting of root, velocity and contact features
HUMANACT12_ACTIONS = ("warm_up", "walk", "run", "jump", "drink", "lift_dumbbell", "sit", "eat",
                      "turn steering wheel", "phone", "boxing", "throw")  # fmt: skip
LAYOUT = """\
  <official_dir>/t2m/text_mot_match/model/finest.tar        HumanML3D text-motion evaluator (MDM's download script)
  <official_dir>/t2m/Comp_v6_KLD01/meta/{mean,std}.npy     its normalisation (or <official_dir>/dataset/t2m_{mean,std}.npy)
  <official_dir>/kit/...                                    the same for KIT-ML
  <official_dir>/glove/our_vab_{data.npy,idx.pkl}           the GloVe table of both
  <official_dir>/assets/actionrecognition/humanact12_gru.tar        HumanAct12 classifier (or action_recognition_model_humanact12.tar)
  <official_dir>/assets/actionrecognition/uestc_rot6d_stgcn.tar     UESTC ST-GCN"""
_T2M = {"humanml3d": "t2m", "kit": "kit"}


class OfficialLayoutError(FileNotFoundError):
    """A file of the official evaluators is missing: the message names it and the expected layout."""


def _first(paths: list[Path], what: str) -> Path:
    for p in paths:
        if p.is_file():
            return p
    raise OfficialLayoutError(f"no {what}: looked for {', '.join(map(str, paths))}. Expected layout:\n{LAYOUT}")


def evaluator_std(mean: np.ndarray, std: np.ndarray, num_joints: int) -> tuple[np.ndarray, np.ndarray]:
    """The official evaluator's statistics from a dataset's Mean/Std: std of root (4 dims), local velocities and foot
    contacts divided by FEAT_BIAS, positions and rotations unchanged (what its training script saved as meta)."""
    s = feature_slices(num_joints)
    std = np.array(std, dtype=np.float32, copy=True)
    for block in ("root_rot_vel", "root_lin_vel", "root_y", "local_vel", "contacts"):
        std[s[block]] /= FEAT_BIAS
    return np.asarray(mean, dtype=np.float32), std


def t2m_paths(official_dir: Path, dataset: str) -> dict[str, Path | None]:
    name = _T2M[dataset]
    meta = [official_dir / name / "Comp_v6_KLD01" / "meta", official_dir / "dataset"]
    found = {"checkpoint": _first([official_dir / name / "text_mot_match" / "model" / "finest.tar"],
                                  f"{name} text-motion evaluator"),
             "glove": official_dir / "glove"}  # fmt: skip
    for stat in ("mean", "std"):
        cands = [meta[0] / f"{stat}.npy", meta[1] / f"{name}_{stat}.npy"]
        found[stat] = next((p for p in cands if p.is_file()), None)
    return found


def official_evaluators(dataset: str, official_dir: str | Path, module, dm) -> Evaluators:
    """The official evaluators of `dataset` ("humanml3d", "kit", "humanact12", "uestc") for `module`'s output."""
    official_dir = Path(official_dir)
    if not official_dir.is_dir():
        raise OfficialLayoutError(f"official_dir={official_dir} is not a folder. Expected layout:\n{LAYOUT}")
    if dataset in _T2M:
        p = t2m_paths(official_dir, dataset)
        if p["mean"] is None or p["std"] is None:
            mean, std = evaluator_std(dm.mean, dm.std, module.hparams.num_joints)
            log.warning("no evaluator meta mean/std under %s: derived from the dataset's Mean/Std with feat_bias %g",
                        official_dir, FEAT_BIAS)  # fmt: skip
        else:
            mean, std = np.load(p["mean"]), np.load(p["std"])
        model = load_official_t2m_evaluator(p["checkpoint"], p["glove"], mean, std, _T2M[dataset])
        return Evaluators(text_motion=model, num_joints=module.hparams.num_joints, meta={"source": "official"})
    rep, up = _rig_representation(module), _source_up_axis(dm)
    folder = official_dir / "assets" / "actionrecognition"
    if dataset == "humanact12":
        path = _first([folder / "humanact12_gru.tar", folder / "action_recognition_model_humanact12.tar"],
                      "HumanAct12 action classifier")  # fmt: skip
        classifier = load_official_action_classifier(path)
        reader = humanact12_reader(classifier, rep, up)
        names = HUMANACT12_ACTIONS
    elif dataset == "uestc":
        stgcn = load_official_uestc_recognition(_first([folder / "uestc_rot6d_stgcn.tar"], "UESTC ST-GCN"))
        reader = uestc_reader(stgcn, rep, up)
        names = tuple(dm.action_names)
    else:
        raise ValueError(f"no official evaluator for dataset {dataset!r}: humanml3d, kit, humanact12, uestc have one")
    ev = Evaluators(action=reader.model, num_joints=module.hparams.num_joints,
                    meta={"source": "official", "action": {"action_names": list(names)}})  # fmt: skip
    ev.action_reader = reader
    return ev


def _rig_representation(module):

    rep = representation_from_spec(module.hparams.get("representation"), module.hparams.feature_dim)
    if not isinstance(rep, (RotationRepresentation, JointPositions)) or rep.skeleton.num_joints != 24:
        raise ValueError(
            f"the official action evaluators read the 24 SMPL joints; this model generates {rep.name} on "
            f"{rep.skeleton.num_joints} joints: train it with representation=rp6jr (MDM's) or use evaluator=released"
        )
    return rep


def _source_up_axis(dm) -> str:
    clips = dm.clips("train").clips
    return clips[0].meta.get("source_up_axis", "+y") if clips else "+y"


def to_source_axes(up_axis: str) -> np.ndarray:
    """3x3 rotation from our y-up frame back to the source data's axes (inverse of the loader's conversion)."""
    return quat_to_matrix(UP_TO_Y[up_axis]).T


class ActionReader:
    """De-normalised features of the model's representation -> (logits, features) of an official classifier."""

    def __init__(self, model: torch.nn.Module, make_input: Callable[[torch.Tensor, torch.Tensor], torch.Tensor],
                 reads_lengths: bool):  # fmt: skip
        self.model, self.make_input, self.reads_lengths = model, make_input, reads_lengths

    @torch.inference_mode()
    def __call__(self, features: list[np.ndarray]) -> tuple[torch.Tensor, torch.Tensor]:
        x, lengths = pad(features)
        return self.classify(self.make_input(x, lengths), lengths)

    def classify(self, model_input: torch.Tensor, lengths: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The classifier on its own input: (B, 24, 3, T) joints (HumanAct12) or (B, 24, 6, T) rotations (UESTC)."""
        if self.reads_lengths:  # the GRU reads its output at the last valid frame
            return self.model(model_input, lengths)
        return self.model(model_input)  # ST-GCN pools over every frame given (ACTOR's clips all have 60)


def humanact12_input(joints: torch.Tensor, lengths: torch.Tensor, up_axis: str) -> torch.Tensor:
    """World joints (B, T, 24, 3) in our y-up frame -> the classifier's (B, 24, 3, T): source axes, minus the first
    frame's root (ACTOR: `joints3D - joints3D[0, 0]`), zero past each length."""
    m = torch.as_tensor(to_source_axes(up_axis), dtype=joints.dtype)
    src = joints @ m.T
    src = src - src[:, :1, :1]
    valid = torch.arange(src.shape[1])[None] < lengths[:, None]
    return (src * valid[..., None, None]).permute(0, 2, 3, 1).contiguous()


def humanact12_reader(classifier, rep, up_axis: str) -> ActionReader:
    def make_input(x, lengths):
        return humanact12_input(rep.decode(x.double()).float(), lengths, up_axis)

    return ActionReader(classifier, make_input, reads_lengths=True)


def rotation_6d_rows(mats: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) -> (..., 6): the first two rows (PyTorch3D's `matrix_to_rotation_6d`, which ACTOR uses)."""
    return mats[..., :2, :].reshape(mats.shape[:-2] + (6,))


def uestc_input(local_mats: torch.Tensor, lengths: torch.Tensor, up_axis: str) -> torch.Tensor:
    """Local rotation matrices (B, T, 24, 3, 3) in our y-up frame (joint 0 global) -> the ST-GCN's (B, 24, 6, T):
    the global orientation turned back to the source axes, all joints as 6D rows, zero past each length."""
    m = torch.as_tensor(to_source_axes(up_axis), dtype=local_mats.dtype)
    mats = local_mats.clone()
    mats[:, :, 0] = m @ mats[:, :, 0]
    six = rotation_6d_rows(mats)
    valid = torch.arange(six.shape[1])[None] < lengths[:, None]
    return (six * valid[..., None, None]).permute(0, 2, 3, 1).contiguous()


def uestc_reader(stgcn, rep, up_axis: str) -> ActionReader:
    if not isinstance(rep, RotationRepresentation):
        raise ValueError(f"the official UESTC ST-GCN reads joint rotations; {rep.name} has none: use rp6jr")

    def make_input(x, lengths):
        return uestc_input(rep.rotation_matrices(x.double()).float(), lengths, up_axis)

    return ActionReader(stgcn, make_input, reads_lengths=False)
