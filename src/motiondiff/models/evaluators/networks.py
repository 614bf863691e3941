"""The two evaluators every motion-generation paper reports with, compatible with their official checkpoints.

- Text-motion matching (Guo et al. 2022, "Generating diverse and natural 3D human motions from text"): a
  convolutional movement encoder (features without foot contacts, length / 4), a BiGRU motion encoder and a BiGRU
  text encoder over word vectors + POS one-hots, trained contrastively so matching captions and motions are close
  in Euclidean distance. Module and parameter names match the official `text_mot_match/model/finest.tar`, so it
  loads strictly (`model_files.evaluators.load_official_t2m_evaluator`).
- Action recognition (Guo et al. 2020, HumanAct12 protocol): a 2-layer GRU over flattened joint positions; the
  output at the last valid frame goes through `linear1` + tanh (the 30-d features for FID/diversity) and `linear2`
  (the class logits). `model_files.evaluators.load_official_action_classifier` reads the official HumanAct12 checkpoint.

Evaluators trained on our own datasets (`python -m motiondiff.cli.train_evaluator`) have the same architectures
(sizes configurable) and are released as safetensors + JSON config (`model_files.evaluators`).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn
from torch.nn.utils.rnn import pack_padded_sequence

from motiondiff.data.representations.hml_features import feature_slices, joints_from_features, recover_root
from motiondiff.text.word_vectors import POS_CATEGORIES, Vocabulary, sequence, tag_captions

FOOT_CONTACT_DIMS = 4
OFFICIAL_MAX_FRAMES = 196  # the official loader's max_motion_length
_PAD_FRAMES = 8  # the last 4 feature dims (foot contacts) are not seen by the movement encoder


# ---- text-motion matching: the official three modules --------------------------------------------------------
class MovementConvEncoder(nn.Module):
    """(B, T, D) features -> (B, T/4, output) movement codes."""

    def __init__(self, input_size: int, hidden_size: int, output_size: int, dropout: float = 0.2):
        super().__init__()
        self.main = nn.Sequential(
            nn.Conv1d(input_size, hidden_size, 4, 2, 1),
            nn.Dropout(dropout),
            nn.LeakyReLU(0.2),
            nn.Conv1d(hidden_size, output_size, 4, 2, 1),
            nn.Dropout(dropout),
            nn.LeakyReLU(0.2),
        )
        self.out_net = nn.Linear(output_size, output_size)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out_net(self.main(x.transpose(1, 2)).transpose(1, 2))


class _BiGRUCo(nn.Module):
    """Shared body of the official text and motion encoders: input projection, BiGRU from a learned initial state,
    both directions' last states -> MLP."""

    def __init__(self, input_size: int, hidden_size: int, output_size: int):
        super().__init__()
        self.input_emb = nn.Linear(input_size, hidden_size)
        self.gru = nn.GRU(hidden_size, hidden_size, batch_first=True, bidirectional=True)
        self.output_net = nn.Sequential(
            nn.Linear(hidden_size * 2, hidden_size),
            nn.LayerNorm(hidden_size),
            nn.LeakyReLU(0.2),
            nn.Linear(hidden_size, output_size),
        )
        self.hidden = nn.Parameter(torch.randn(2, 1, hidden_size))

    def _encode(self, x: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        packed = pack_padded_sequence(self.input_emb(x), lengths.cpu(), batch_first=True, enforce_sorted=False)
        _, last = self.gru(packed, self.hidden.repeat(1, x.shape[0], 1))
        return self.output_net(torch.cat([last[0], last[1]], dim=-1))


class TextEncoderBiGRUCo(_BiGRUCo):
    def __init__(self, word_size: int, pos_size: int, hidden_size: int, output_size: int):
        super().__init__(word_size, hidden_size, output_size)
        self.pos_emb = nn.Linear(pos_size, word_size)

    def forward(self, word_embs: torch.Tensor, pos_onehot: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        return self._encode(word_embs + self.pos_emb(pos_onehot), lengths)


class MotionEncoderBiGRUCo(_BiGRUCo):
    def forward(self, movements: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        return self._encode(movements, lengths)


class TextMotionEvaluator(nn.Module):
    """Captions and motions -> embeddings in one space (R-precision, FID, MM-Dist, diversity, multimodality).

    `encode_motion` takes de-normalised features (B, N, D) in the dataset's layout (HumanML3D 263 / KIT 251) and
    normalises them with the evaluator's own Mean/Std, as the official protocol does. Word vectors are a frozen
    GloVe table (official) or an embedding learned with the evaluator (`learned_words=True`).
    """

    def __init__(
        self,
        feature_dim: int,
        words: list[str],
        word_dim: int = 300,
        movement_hidden: int = 512,
        movement_size: int = 512,
        text_hidden: int = 512,
        motion_hidden: int = 1024,
        output_size: int = 512,
        unit_length: int = 4,
        learned_words: bool = True,
        dropout: float = 0.2,
    ):
        super().__init__()
        self.config = {k: v for k, v in locals().items() if k not in ("self", "__class__", "words")}
        self.vocab = Vocabulary(list(words))
        self.unit_length = unit_length
        self.movement_encoder = MovementConvEncoder(
            feature_dim - FOOT_CONTACT_DIMS, movement_hidden, movement_size, dropout
        )
        self.motion_encoder = MotionEncoderBiGRUCo(movement_size, motion_hidden, output_size)
        self.text_encoder = TextEncoderBiGRUCo(word_dim, len(POS_CATEGORIES), text_hidden, output_size)
        self.word_vectors = nn.Embedding(len(self.vocab.words), word_dim)
        self.word_vectors.weight.requires_grad_(learned_words)
        self.register_buffer("mean", torch.zeros(feature_dim))
        self.register_buffer("std", torch.ones(feature_dim))
        self._tagged: dict[str, list[tuple[str, str]]] = {}
        self.pad_to: int | None = None  # official: every motion zero-padded to this many frames (196)

    @property
    def words(self) -> list[str]:
        return self.vocab.words

    def set_normalisation(self, mean, std) -> None:
        self.mean.copy_(torch.as_tensor(np.asarray(mean), dtype=torch.float32))
        std = torch.as_tensor(np.asarray(std), dtype=torch.float32)
        self.std.copy_(torch.where(std < 1e-8, torch.ones_like(std), std))

    # -- motion --
    def normalised_input(self, features: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """De-normalised features (B, N, D) -> what the movement encoder reads: the evaluator's normalisation,
        foot contacts dropped, zeros past each length, then zero frames appended. The official loader pads every
        motion with zeros to 196 frames (`pad_to`, set by `load_official_t2m_evaluator`), so its convolutions see
        zero frames after a shorter clip's end and their own border after a 196-frame one; without `pad_to` (our
        evaluators, trained so) 8 zero frames, which cover the convolutions' reach after every clip."""
        features = features.to(self.mean)
        x = (features - self.mean) / self.std
        valid = torch.arange(x.shape[1], device=x.device)[None] < lengths.to(x.device)[:, None]
        x = x * valid[..., None]
        extra = _PAD_FRAMES if self.pad_to is None else max(0, self.pad_to - x.shape[1])
        return torch.nn.functional.pad(x[..., :-FOOT_CONTACT_DIMS], (0, 0, 0, extra))

    def encode_motion(self, features: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """De-normalised features (B, N, D), lengths (B,) -> (B, output_size)."""
        movements = self.movement_encoder(self.normalised_input(features, lengths))
        units = (lengths // self.unit_length).clamp(1, movements.shape[1])
        return self.motion_encoder(movements, units)

    # -- text --
    def tokenize(self, captions: list[str]) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Word ids (B, L), POS one-hots (B, L, 15) and lengths (B,) of captions (tags are cached per caption)."""
        new = [c for c in dict.fromkeys(captions) if c not in self._tagged]
        for c, words in zip(new, tag_captions(new), strict=True):
            self._tagged[c] = words
        encoded = [self.vocab.encode(sequence(self._tagged[c])) for c in captions]
        lengths = torch.tensor([len(ids) for ids, _ in encoded])
        ids = torch.zeros(len(captions), int(lengths.max()), dtype=torch.long)
        pos = torch.zeros(len(captions), int(lengths.max()), len(POS_CATEGORIES))
        for i, (w, p) in enumerate(encoded):
            ids[i, : len(w)] = torch.tensor(w)
            pos[i, torch.arange(len(p)), torch.tensor(p)] = 1.0
        return ids, pos, lengths

    def use_tokens(self, tokens: dict[str, list[str]]) -> None:
        """Tag these captions with the dataset's own "word/POS" tokens (HumanML3D/KIT texts files), as the official
        loader does, instead of tagging them again with spaCy."""
        for caption, toks in tokens.items():
            self._tagged[caption] = [tuple(t.rsplit("/", 1)) if "/" in t else (t, "OTHER") for t in toks]

    def encode_text(self, captions: list[str]) -> torch.Tensor:
        ids, pos, lengths = self.tokenize(captions)
        device = self.mean.device
        return self.text_encoder(self.word_vectors(ids.to(device)), pos.to(device), lengths)


# ---- action recognition ------------------------------------------------------------------------------------------
class ActionClassifierGRU(nn.Module):
    """HumanAct12 protocol classifier: motion (B, J, 3, T), lengths (B,) -> (logits (B, C), features (B, 30)).

    The official code starts the GRU from a random normal state; `hidden=None` here starts from zeros so
    evaluation is deterministic (the reference outputs were made with zeros too)."""

    def __init__(self, input_size: int = 72, hidden_size: int = 128, num_layers: int = 2, num_classes: int = 12,
                 feature_size: int = 30, input_kind: str = "joints"):  # fmt: skip
        super().__init__()
        if input_kind not in INPUT_KINDS:
            raise ValueError(f"input_kind={input_kind!r}; choose from {INPUT_KINDS}")
        self.config = {k: v for k, v in locals().items() if k not in ("self", "__class__")}
        self.input_kind = input_kind  # what `motion_input` feeds it: see there
        self.recurrent = nn.GRU(input_size, hidden_size, num_layers)  # sequence-first, as the checkpoint
        self.linear1 = nn.Linear(hidden_size, feature_size)
        self.linear2 = nn.Linear(feature_size, num_classes)

    def forward(self, motion: torch.Tensor, lengths: torch.Tensor, hidden: torch.Tensor | None = None):
        b, j, c, t = motion.shape
        x = motion.reshape(b, j * c, t).permute(2, 0, 1).float()  # (T, B, J*3), joint-major like the original
        if hidden is None:
            hidden = x.new_zeros(self.recurrent.num_layers, b, self.recurrent.hidden_size)
        out, _ = self.recurrent(x, hidden)
        last = out[lengths.to(out.device).long() - 1, torch.arange(b, device=out.device)]
        features = torch.tanh(self.linear1(last))
        return self.linear2(features), features


INPUT_KINDS = ("joints", "pose_trajectory")


def classifier_input(joints: torch.Tensor) -> torch.Tensor:
    """Joints (B, T, J, 3) -> classifier input (B, J, 3, T), relative to the first frame's root on the ground, so
    the classifier sees where the motion goes but not where it started."""
    origin = joints[:, :1, :1].clone()
    origin[..., 1] = 0.0
    return (joints - origin).permute(0, 2, 3, 1)


def pose_and_trajectory(features: np.ndarray, num_joints: int) -> np.ndarray:
    """HumanML3D-layout features (..., N, D) -> (..., N, J, 3): "joint" 0 is the root's path (x, z from its start,
    y its height), joints 1..J-1 are positions relative to the root in the root's own facing frame (the features'
    ric block). Same information as world positions, but the pose no longer depends on where the body is going,
    which a small GRU classifier learns from far fewer clips."""
    _, root = recover_root(np.asarray(features, dtype=np.float64))
    ric = features[..., feature_slices(num_joints)["ric"]].reshape(features.shape[:-1] + (num_joints - 1, 3))
    return np.concatenate([root[..., None, :], ric], axis=-2).astype(np.float32)


def motion_input(classifier: ActionClassifierGRU, features: torch.Tensor, num_joints: int) -> torch.Tensor:
    """De-normalised features (B, N, D) -> the classifier's input (B, J, 3, N), as it was trained to read them:
    world joint positions (`input_kind="joints"`, the HumanAct12 protocol) or `pose_and_trajectory`."""
    x = features.detach().float().cpu().numpy()
    if classifier.input_kind == "pose_trajectory":
        joints = pose_and_trajectory(x, num_joints)
    else:
        joints = joints_from_features(x, num_joints)
    return classifier_input(torch.from_numpy(joints)).to(features.device)
