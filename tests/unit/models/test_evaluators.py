"""Evaluators: official checkpoints load and reproduce their reference outputs; released ones round-trip."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
import torch
from fixtures.official_layouts import layout_shapes, write_glove

from motiondiff.model_files.evaluators import (
    load_official_action_classifier,
    load_official_t2m_evaluator,
    load_released,
    save_released,
)
from motiondiff.models.evaluators.networks import ActionClassifierGRU, TextMotionEvaluator, classifier_input
from motiondiff.runtime.errors import UsageError
from motiondiff.text.word_vectors import POS_INDEX, Vocabulary, load_glove, pos_category, sequence, tag_caption


def test_official_action_classifier_reproduces_reference(shared):
    folder = shared("reference", "action-recognition")
    model = load_official_action_classifier(folder / "action_recognition_model_humanact12.tar")
    ref = np.load(folder / "humanact12_classifier_reference.npz")
    with torch.no_grad():
        logits, features = model(
            torch.from_numpy(ref["motion"]), torch.from_numpy(ref["lengths"]), torch.from_numpy(ref["hidden"])
        )
        logits0, _ = model(torch.from_numpy(ref["motion"]), torch.from_numpy(ref["lengths"]))  # hidden=None: zeros
    err_logits = np.abs(logits.numpy() - ref["logits"]).max()
    err_features = np.abs(features.numpy() - ref["features"]).max()
    print(f"\nofficial HumanAct12 classifier: max |logits - ref| {err_logits:.2e}, |features - ref| {err_features:.2e}")
    assert err_logits <= 1e-5 and err_features <= 1e-5
    assert torch.equal(logits0, logits)
    assert features.shape == (4, 30) and logits.shape == (4, 12)


def test_official_t2m_state_dict_loads_strictly(shared, tmp_path):
    layout = layout_shapes(shared("reference", "t2m_evaluator_state_dict_layout.txt").read_text())
    assert set(layout) == {"movement_encoder", "text_encoder", "motion_encoder"}
    gen = torch.Generator().manual_seed(0)
    state = {name: {k: torch.randn(shape, generator=gen) for k, shape in keys.items()} for name, keys in layout.items()}
    torch.save({**state, "epoch": 10, "it": 1000}, tmp_path / "finest.tar")
    words = ["sos", "eos", "unk", "person", "walk", "forward"]
    vectors = write_glove(tmp_path, words)
    np.save(tmp_path / "mean.npy", np.zeros(263, np.float32))
    np.save(tmp_path / "std.npy", np.full(263, 2.0, np.float32))
    model = load_official_t2m_evaluator(tmp_path / "finest.tar", tmp_path, tmp_path / "mean.npy", tmp_path / "std.npy")
    n_keys = 0
    for name, keys in layout.items():
        loaded = getattr(model, name).state_dict()
        assert set(loaded) == set(keys)
        for k in keys:
            assert torch.equal(loaded[k], state[name][k])
            n_keys += 1
    print(f"\nstrict load of the official T2M layout: {n_keys} tensors in 3 modules, all equal")
    assert np.array_equal(model.word_vectors.weight.detach().numpy(), vectors)
    with torch.no_grad():
        assert model.encode_text(["a person walks forward."]).shape == (1, 512)
        assert model.encode_motion(torch.randn(2, 40, 263), torch.tensor([40, 24])).shape == (2, 512)
    # a state dict with one key too many must fail (strict)
    state["text_encoder"]["extra"] = torch.zeros(1)
    torch.save(state, tmp_path / "bad.tar")
    with pytest.raises(RuntimeError, match="extra"):
        load_official_t2m_evaluator(tmp_path / "bad.tar", tmp_path, tmp_path / "mean.npy", tmp_path / "std.npy")


def test_glove_loader_refuses_pickled_code(tmp_path):
    words = ["sos", "eos", "unk", "walk"]
    write_glove(tmp_path, words)
    vocab, vectors = load_glove(tmp_path)
    assert vocab.words == words and vectors.shape == (4, 300)

    class Payload:
        def __reduce__(self):
            return (print, ("pwned",))

    with open(tmp_path / "our_vab_idx.pkl", "wb") as f:
        pickle.dump(Payload(), f)
    with pytest.raises(pickle.UnpicklingError, match="not allowed"):
        load_glove(tmp_path)


def test_caption_tokens_follow_the_official_processing():
    words = tag_caption("A person walks forward 3.5 meters, then turns left.")
    assert [w for w, _ in words] == ["a", "person", "walk", "forward", "meter", "then", "turn", "left"]
    seq = sequence(words)
    assert seq[0] == ("sos", "OTHER") and seq[-1] == ("eos", "OTHER")
    assert pos_category("walk", "VERB") == POS_INDEX["Act_VIP"]
    assert pos_category("left", "NOUN") == POS_INDEX["Loc_VIP"]
    assert pos_category("person", "NOUN") == POS_INDEX["NOUN"]
    assert pos_category("and", "CCONJ") == POS_INDEX["OTHER"]
    vocab = Vocabulary.from_captions(["a person walks."])
    ids, pos = vocab.encode([("zebra", "NOUN")])
    assert ids == [vocab.index["unk"]] and pos == [POS_INDEX["OTHER"]]  # unknown words: unk/OTHER (official)
    assert len(sequence([("w", "NOUN")] * 30)) == 22  # sos + 20 words + eos


def test_released_evaluators_round_trip(tmp_path):
    torch.manual_seed(0)
    tm = TextMotionEvaluator(263, ["person", "walk"], word_dim=16, movement_hidden=32, movement_size=32,
                             text_hidden=32, motion_hidden=32, output_size=8).eval()  # fmt: skip
    tm.set_normalisation(np.ones(263), np.full(263, 3.0))
    clf = ActionClassifierGRU(66, 16, 2, 5).eval()
    save_released(tm, tmp_path / "text_motion", {"dataset": "x"})
    save_released(clf, tmp_path / "action")
    tm2, meta = load_released(tmp_path / "text_motion")
    clf2, _ = load_released(tmp_path / "action.safetensors")
    assert meta == {"dataset": "x"} and tm2.words == tm.words
    x, lengths = torch.randn(3, 24, 263), torch.tensor([24, 16, 9])
    with torch.no_grad():
        assert torch.equal(tm2.encode_motion(x, lengths), tm.encode_motion(x, lengths))
        assert torch.equal(tm2.encode_text(["a person walks"]), tm.encode_text(["a person walks"]))
        j = classifier_input(torch.randn(3, 24, 22, 3))
        assert torch.equal(clf2(j, lengths)[0], clf(j, lengths)[0])
    assert not list(tmp_path.glob("*.tmp"))
    with pytest.raises(FileNotFoundError, match="train_evaluator"):
        load_released(tmp_path / "missing")


def test_a_changed_or_unchecked_evaluator_release_is_refused(tmp_path):
    save_released(ActionClassifierGRU(66, 16, 2, 5).eval(), tmp_path / "action")
    weights, config = tmp_path / "action.safetensors", tmp_path / "action.json"
    data = bytearray(weights.read_bytes())
    data[-5] ^= 0x01  # one bit of a weight
    weights.write_bytes(bytes(data))
    with pytest.raises(UsageError, match="weights_sha256"):
        load_released(tmp_path / "action")
    doc = json.loads(config.read_text())
    config.write_text(json.dumps({k: v for k, v in doc.items() if k != "weights_sha256"}))
    with pytest.raises(UsageError, match="records no weights_sha256"):
        load_released(tmp_path / "action")


def test_motion_encoding_ignores_padding():
    torch.manual_seed(0)
    tm = TextMotionEvaluator(263, ["a"], movement_hidden=32, movement_size=32, text_hidden=32, motion_hidden=32,
                             output_size=8).eval()  # fmt: skip
    x = torch.randn(1, 32, 263)
    padded = torch.cat([x, torch.randn(1, 16, 263) * 100], dim=1)
    with torch.no_grad():
        a = tm.encode_motion(x, torch.tensor([32]))
        b = tm.encode_motion(padded, torch.tensor([32]))
    assert torch.allclose(a, b, atol=1e-6)


def test_classifier_input_is_relative_to_the_first_root_on_the_ground():
    joints = torch.randn(2, 10, 22, 3)
    x = classifier_input(joints)
    assert x.shape == (2, 22, 3, 10)
    assert torch.allclose(x[:, 0, [0, 2], 0], torch.zeros(2, 2))  # root starts at the origin on the ground
    assert torch.allclose(x[:, 0, 1, 0], joints[:, 0, 0, 1])  # heights kept


def test_pose_and_trajectory_holds_the_world_joints():
    from motiondiff.data.representations.hml_features import features_from_joints, joints_from_features, recover_root
    from motiondiff.geometry.rotations import qinv, qrot
    from motiondiff.models.evaluators.networks import pose_and_trajectory

    t = np.linspace(0, 2, 41)[:, None]
    rng = np.random.default_rng(0)
    from motiondiff.geometry.skeleton import SMPL22

    rest = np.cumsum(rng.normal(0, 0.1, (22, 3)), axis=0) + [0, 1.0, 0]
    joints = (
        rest[None]
        + 0.05 * np.sin(3 * t)[..., None]
        + np.stack([0.8 * t[:, 0], 0 * t[:, 0], 0.3 * t[:, 0]], -1)[:, None]
    )
    feats = features_from_joints(joints.astype(np.float32), SMPL22)
    pt = pose_and_trajectory(feats, 22)
    r_rot, _ = recover_root(feats.astype(np.float64))
    world = qrot(np.broadcast_to(qinv(r_rot)[:, None], pt[:, 1:].shape[:-1] + (4,)), pt[:, 1:].astype(np.float64))
    world[..., [0, 2]] += pt[:, :1, [0, 2]]
    ref = joints_from_features(feats, 22)
    assert np.abs(pt[:, 0] - ref[:, 0]).max() < 1e-5
    assert np.abs(world - ref[:, 1:]).max() < 1e-5


def test_mirroring_swaps_sides_of_joints_and_labels():
    from motiondiff.data.mirror import mirrored_labels
    from motiondiff.geometry.skeleton import KIT21, SMPL22

    for skel in (SMPL22, KIT21):
        perm = skel.mirror_permutation
        assert sorted(perm) == list(range(skel.num_joints)) and all(perm[perm[i]] == i for i in perm)
        moved = [skel.joint_names[i] for i in range(skel.num_joints) if perm[i] != i]
        assert len(moved) == 16  # SMPL-22: 8 pairs (hips to wrists); KIT-21: shoulders to feet
    assert SMPL22.joint_names[SMPL22.mirror_permutation[SMPL22.index("l_wrist")]] == "r_wrist"
    names = ["walk", "wave-left-hand", "wave-right-hand", "walk-left", "raise-left"]
    assert mirrored_labels(names) == [0, 2, 1, 3, 4]  # no "walk-right" or "raise-right": kept
