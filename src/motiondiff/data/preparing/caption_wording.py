"""Varied wording for GENERATED captions: synonyms, body-part wording, subjects, tenses and sentence shapes.

A model conditioned on a few caption templates only understands those templates; people describe the same action
in many ways ("raises both arms", "puts both hands up", "is lifting both hands over the head"). Each action here has
several verb phrases in the base form, inflected by `inflect` (a small table of the irregular verbs these phrases
use: written by hand because the phrases are fixed and a morphology library would add a dependency for ~20 verbs),
and each style several manner words. `varied_captions` draws sentences from these at random.
"""

from __future__ import annotations

import json
from importlib import resources

import numpy as np

# The phrase tables are data (motiondiff/assets/caption_wording.json): per action label, base-form verb phrases whose
# first verb is inflected; per style label, manner phrases and adjectives for the subject ("a tired man").
_TABLES = json.loads((resources.files("motiondiff") / "assets" / "caption_wording.json").read_text(encoding="utf-8"))
ACTION_WORDING: dict[str, tuple[str, ...]] = {k: tuple(v) for k, v in _TABLES["actions"].items()}
STYLE_WORDING: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    k: (tuple(v["manners"]), tuple(v["adjectives"])) for k, v in _TABLES["styles"].items()
}

SUBJECT_NOUNS = ("person", "man", "woman", "figure", "character", "human")
PLAIN_SUBJECTS = ("a person", "someone", "a man", "a woman", "the person", "the figure", "a character", "somebody")

_IRREGULAR = {  # base: (third person, -ing, past)
    "run": ("runs", "running", "ran"),
    "jog": ("jogs", "jogging", "jogged"),
    "take": ("takes", "taking", "took"),
    "throw": ("throws", "throwing", "threw"),
    "swing": ("swings", "swinging", "swung"),
    "put": ("puts", "putting", "put"),
    "cut": ("cuts", "cutting", "cut"),
    "hold": ("holds", "holding", "held"),
    "step": ("steps", "stepping", "stepped"),
    "say": ("says", "saying", "said"),
    "stand": ("stands", "standing", "stood"),
    "bend": ("bends", "bending", "bent"),
    "make": ("makes", "making", "made"),
    "keep": ("keeps", "keeping", "kept"),
    "do": ("does", "doing", "did"),
    "stay": ("stays", "staying", "stayed"),
    "change": ("changes", "changing", "changed"),
}
_VOWELS = "aeiou"
_VERBS = {p.split(" ")[0].rstrip(",") for ps in ACTION_WORDING.values() for p in ps} | {"curve"}


def inflect(verb: str, form: str) -> str:
    """'third' (runs), 'ing' (running) or 'past' (ran) of an English base-form verb used in these phrases."""
    if verb in _IRREGULAR:
        return _IRREGULAR[verb][("third", "ing", "past").index(form)]
    if form == "third":
        if verb.endswith(("s", "sh", "ch", "x", "z")):
            return verb + "es"
        return verb[:-1] + "ies" if verb.endswith("y") and verb[-2] not in _VOWELS else verb + "s"
    stem = verb[:-1] if verb.endswith("e") and not verb.endswith(("ee", "ye")) else verb
    if form == "ing":
        return stem + "ing"
    if verb.endswith("y") and verb[-2] not in _VOWELS:
        return verb[:-1] + "ied"
    return stem + "ed" if not verb.endswith("e") else verb + "d"


def inflect_phrase(phrase: str, form: str) -> str:
    """Inflect the leading verb of a phrase and a verb right after 'and' / 'then' ("walk and turn left")."""
    out, next_is_verb = [], True
    for i, w in enumerate(phrase.split(" ")):
        core = w.rstrip(",")
        out.append(inflect(core, form) + w[len(core) :] if next_is_verb and (i == 0 or core in _VERBS) else w)
        next_is_verb = core in ("and", "then")
    return " ".join(out)


def _a(word: str) -> str:
    return ("an " if word[0] in _VOWELS else "a ") + word


def varied_captions(content: str, style: str, rng: np.random.Generator, count: int) -> list[str]:
    """`count` distinct-as-possible generated sentences naming this action and style in varied wording."""
    phrases = ACTION_WORDING.get(content, (content.replace("-", " "),))
    manners, adjectives = STYLE_WORDING.get(style, ((f"in a {style.replace('-', ' ')} style",), ()))
    out: list[str] = []
    for _ in range(count * 4):
        if len(out) == count:
            break
        phrase = str(rng.choice(phrases))
        manner = str(rng.choice(manners))
        shape = int(rng.integers(5))
        if adjectives and rng.random() < 0.3:  # "a tired man walks": the style moves into the subject
            subject, manner = f"{_a(str(rng.choice(adjectives)))} {rng.choice(SUBJECT_NOUNS)}", ""
        else:
            subject = str(rng.choice(PLAIN_SUBJECTS))
        tail = f" {manner}" if manner else ""
        if shape <= 1:  # the commonest human shape gets two chances in five
            text = f"{subject} {inflect_phrase(phrase, 'third')}{tail}."
        elif shape == 2:
            text = f"{subject} is {inflect_phrase(phrase, 'ing')}{tail}."
        elif shape == 3:
            text = f"{subject} {inflect_phrase(phrase, 'past')}{tail}."
        elif shape == 4:
            text = f"{inflect_phrase(phrase, 'ing')}{tail}."  # a bare gerund phrase, as people tag clips
        if text not in out:
            out.append(text)
    return out
