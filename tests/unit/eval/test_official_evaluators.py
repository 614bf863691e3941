"""evaluator=official: the papers' evaluators load from MDM's layout, and what the evaluation pipeline embeds equals
calling the loaded official modules directly on the input their own code builds (<= 1e-5)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import torch
from fixtures.action_layouts import fk
from fixtures.official_layouts import stgcn_state, write_official_action, write_official_t2m
from scipy.spatial.transform import Rotation

from motiondiff.data.representations import RotationRepresentation
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import feature_slices
from motiondiff.data.representations.spec import representation_spec
from motiondiff.eval import official
from motiondiff.geometry.skeleton import SMPL22, SMPL24
from motiondiff.model_files.evaluators import load_official_action_classifier
from motiondiff.models.evaluators.stgcn import STGCNRecognition, load_official_uestc_recognition, spatial_adjacency

# y-up -> source axes for a "-y" source: 180 degrees about x, (x, y, z) -> (x, -y, -z)
SOURCE_FROM_YUP_MINUS_Y = np.diag([1.0, -1.0, -1.0])


def _fake(dataset_root_clips=None, num_joints=24, representation=None, feature_dim=None, mean=None, std=None):
    """Stand-ins for the module (hparams) and datamodule (train clips' meta, statistics) official_evaluators reads."""
    module = SimpleNamespace(hparams=SimpleNamespace(num_joints=num_joints, feature_dim=feature_dim,
                                                     get=lambda k, d=None: representation if k == "representation" else d))  # fmt: skip
    clips = [SimpleNamespace(meta={"source_up_axis": "-y"})]
    dm = SimpleNamespace(clips=lambda split: SimpleNamespace(clips=clips), mean=mean, std=std,
                         action_names=[f"a{i}" for i in range(40)])  # fmt: skip
    return module, dm


def _rp6jr_motion(rng, n: int) -> tuple[RotationRepresentation, np.ndarray, np.ndarray, np.ndarray]:
    """A random SMPL-24 motion: (representation, its de-normalised rp6jr features, local matrices, world joints)."""
    rep = RotationRepresentation("rp6jr", SMPL24)
    rotvec = rng.normal(scale=0.4, size=(n, 24, 3)).cumsum(0) * 0.1
    rot = Rotation.from_rotvec(rotvec.reshape(-1, 3))
    quat = rot.as_quat()[:, [3, 0, 1, 2]].reshape(n, 24, 4)
    root = np.cumsum(rng.normal(scale=0.02, size=(n, 3)), 0) + [0, 0.9, 0]
    clip = ClipMotion(joints=np.zeros((n, 22, 3)), rotations=quat, root=root, rig=SMPL24)
    mats = rot.as_matrix().reshape(n, 24, 3, 3)
    joints = fk(rotvec.reshape(n, 72), np.asarray(SMPL24.offsets), root)
    return rep, rep.encode(clip).astype(np.float64), mats, joints


def test_spatial_partition_of_a_chain_by_hand():
    # chain 0-1-2 around node 0; degrees with self-links 2, 3, 2; columns divided by the receiving node's degree
    a = spatial_adjacency((-1, 0, 1))
    assert np.allclose(a[0], np.diag([1 / 2, 1 / 3, 1 / 2]))
    assert np.allclose(a[1], [[0, 0, 0], [1 / 2, 0, 0], [0, 1 / 3, 0]])  # from the node further from the center
    assert np.allclose(a[2], [[0, 1 / 3, 0], [0, 0, 1 / 2], [0, 0, 0]])  # from the node closer to the center
    full = spatial_adjacency(SMPL24.parents)
    assert full.shape == (3, 24, 24) and np.allclose(full.sum(axis=(0, 1)), 1.0)  # each column sums to 1


def test_stgcn_loads_the_official_layout_strictly(tmp_path):
    state = stgcn_state()
    torch.save(state, tmp_path / "uestc_rot6d_stgcn.tar")
    model = load_official_uestc_recognition(tmp_path / "uestc_rot6d_stgcn.tar")
    loaded = model.state_dict()
    assert set(loaded) == set(state) and all(torch.equal(loaded[k], state[k]) for k in state)
    print(f"\nstrict load of the UESTC ST-GCN layout: {len(state)} tensors, all equal")
    del state["st_gcn_networks.4.residual.0.weight"]
    torch.save(state, tmp_path / "bad.tar")
    with pytest.raises(RuntimeError, match="residual"):
        load_official_uestc_recognition(tmp_path / "bad.tar")
    assert isinstance(model, STGCNRecognition)


def test_uestc_embedding_equals_the_official_module_on_its_own_input(tmp_path):
    rng = np.random.default_rng(0)
    write_official_action(tmp_path)
    rep, feats, mats, _ = _rp6jr_motion(rng, 60)
    spec = representation_spec(rep, SMPL22)
    module, dm = _fake(representation=spec, feature_dim=feats.shape[1])
    ev = official.official_evaluators("uestc", tmp_path, module, dm).for_module(module)
    got = ev.embed_motion([feats.astype(np.float32)])
    # ACTOR's input: global orientation in the source's axes, every joint's matrix as its first two rows
    m = mats.copy()
    m[:, 0] = SOURCE_FROM_YUP_MINUS_Y @ m[:, 0]
    x = torch.from_numpy(m[..., :2, :].reshape(60, 24, 6)).float().permute(1, 2, 0)[None]
    stgcn = load_official_uestc_recognition(tmp_path / "assets" / "actionrecognition" / "uestc_rot6d_stgcn.tar")
    with torch.no_grad():
        logits, features = stgcn(x)
    err = max(
        np.abs(got["action_features"] - features.numpy()).max(), np.abs(got["action_logits"] - logits.numpy()).max()
    )
    print(f"\nUESTC ST-GCN through the pipeline vs direct: max |diff| {err:.2e}")
    assert err <= 1e-5 and got["action_features"].shape == (1, 256)


@pytest.mark.shared
def test_humanact12_pipeline_reproduces_the_reference_and_equals_direct_calls(shared, tmp_path):
    ref_dir = shared("reference", "action-recognition")
    write_official_action(tmp_path, ref_dir)
    rng = np.random.default_rng(1)
    rep, feats, _, joints = _rp6jr_motion(rng, 50)
    module, dm = _fake(representation=representation_spec(rep, SMPL22), feature_dim=feats.shape[1])
    ev = official.official_evaluators("humanact12", tmp_path, module, dm).for_module(module)
    # 1. the reference outputs through the pipeline's own 24-joint (72-d) input stage
    ref = np.load(ref_dir / "humanact12_classifier_reference.npz")
    with torch.no_grad():
        logits, features = ev.action_reader.classify(torch.from_numpy(ref["motion"]), torch.from_numpy(ref["lengths"]))
    err_ref = max(np.abs(logits.numpy() - ref["logits"]).max(), np.abs(features.numpy() - ref["features"]).max())
    # 2. model features -> 24 joints by FK, in the source axes, minus the first root (ACTOR) -> the classifier
    got = ev.embed_motion([feats.astype(np.float32)])
    src = joints @ SOURCE_FROM_YUP_MINUS_Y.T
    x = torch.from_numpy(src - src[:1, :1]).float().permute(1, 2, 0)[None]
    classifier = load_official_action_classifier(ref_dir / "action_recognition_model_humanact12.tar")
    with torch.no_grad():
        direct_logits, direct_features = classifier(x, torch.tensor([50]))
    err = np.abs(got["action_features"] - direct_features.numpy()).max()
    print(f"\nHumanAct12: reference through the pipeline {err_ref:.2e}; pipeline vs direct on FK joints {err:.2e}")
    assert err_ref <= 1e-5 and err <= 1e-5
    assert np.abs(got["action_logits"] - direct_logits.numpy()).max() <= 1e-5
    assert ev.action_names[1] == "walk" and got["action_logits"].shape == (1, 12)


def test_official_action_evaluators_refuse_a_model_without_24_joints(tmp_path):
    write_official_action(tmp_path)
    module, dm = _fake(representation=None, feature_dim=263, num_joints=22)
    with pytest.raises(ValueError, match="representation=rp6jr"):
        official.official_evaluators("uestc", tmp_path, module, dm)


@pytest.mark.shared
@pytest.mark.parametrize("dataset,dim", [("humanml3d", 263), ("kit", 251)])
def test_t2m_embedding_equals_the_official_procedure(shared, tmp_path, dataset, dim):
    name = {"humanml3d": "t2m", "kit": "kit"}[dataset]
    state = write_official_t2m(tmp_path, shared("reference", "t2m_evaluator_state_dict_layout.txt").read_text(),
                               name, dim)  # fmt: skip
    joints = 22 if dim == 263 else 21
    module, dm = _fake(num_joints=joints, feature_dim=dim)
    ev = official.official_evaluators(dataset, tmp_path, module, dm).for_module(module)
    rng = np.random.default_rng(2)
    lengths = [196, 120, 44]
    feats = [rng.normal(size=(n, dim)).astype(np.float32) for n in lengths]
    got = ev.embed_motion(feats)["text_motion"]
    # The official procedure: re-normalise with the evaluator's meta statistics, zero-pad to 196 frames, drop the
    # foot contacts, movement encoder, then the motion encoder over length // 4 units (sorted, packed).
    meta = tmp_path / name / "Comp_v6_KLD01" / "meta"
    mean, std = np.load(meta / "mean.npy"), np.load(meta / "std.npy")
    x = np.zeros((3, 196, dim), np.float32)
    for i, f in enumerate(feats):
        x[i, : len(f)] = (f - mean) / std
    m = ev.text_motion
    for mod in ("movement_encoder", "motion_encoder"):
        assert all(torch.equal(v, state[mod][k]) for k, v in getattr(m, mod).state_dict().items())
    with torch.no_grad():
        movements = m.movement_encoder(torch.from_numpy(x[..., :-4]))
        direct = m.motion_encoder(movements, torch.tensor(lengths) // 4).numpy()
    err = np.abs(got - direct).max()
    print(f"\nofficial {name} evaluator: pipeline vs official procedure max |diff| {err:.2e}")
    assert err <= 1e-5


def test_evaluator_std_divides_root_velocity_and_contacts_by_feat_bias():
    std = np.ones(263, np.float32)
    _, out = official.evaluator_std(np.zeros(263), std, 22)
    s = feature_slices(22)
    assert np.allclose(out[:4], 0.2) and np.allclose(out[s["local_vel"]], 0.2) and np.allclose(out[-4:], 0.2)
    assert np.allclose(out[s["ric"]], 1.0) and np.allclose(out[s["rot6d"]], 1.0) and std[0] == 1.0


def test_missing_official_files_name_the_layout(tmp_path):
    module, dm = _fake(num_joints=22, feature_dim=263)
    with pytest.raises(FileNotFoundError, match="finest.tar") as err:
        official.official_evaluators("humanml3d", tmp_path, module, dm)
    assert "glove" in str(err.value)  # the whole layout is shown


def test_official_text_side_reads_the_texts_files_tokens():
    from motiondiff.models.evaluators.networks import TextMotionEvaluator
    from motiondiff.text.word_vectors import POS_INDEX

    model = TextMotionEvaluator(263, ["person", "walk", "jump"], word_dim=8)
    caption = "someone strolls"  # spaCy would tag other words; the file's tokens decide
    model.use_tokens({caption: ["person/NOUN", "jump/VERB"]})
    ids, pos, lengths = model.tokenize([caption])
    v = model.vocab.index
    assert ids[0].tolist() == [v["sos"], v["person"], v["jump"], v["eos"]] and lengths.tolist() == [4]
    assert pos[0, 2].argmax() == POS_INDEX["Act_VIP"] and pos[0, 1].argmax() == POS_INDEX["NOUN"]
