"""Varied wording for GENERATED captions: synonyms, body-part wording, subjects, tenses and sentence shapes.

A model conditioned on a few caption templates only understands those templates; people describe the same action
in many ways ("raises both arms", "puts both hands up", "is lifting both hands over the head"). Each action here has
several verb phrases in the base form, inflected by `inflect` (a small table of the irregular verbs these phrases
use: written by hand because the phrases are fixed and a morphology library would add a dependency for ~20 verbs),
and each style several manner words. `varied_captions` draws sentences from these at random.
"""

from __future__ import annotations

import numpy as np

# Base-form verb phrases per Bandai (and 100STYLE) content label; the first verb of a phrase is inflected.
ACTION_WORDING: dict[str, tuple[str, ...]] = {
    "walk": ("walk", "walk forward", "walk straight ahead", "stroll forward", "take steps forward", "walk ahead"),
    "run": ("run", "run forward", "jog forward", "jog", "run ahead", "run at a steady pace"),
    "dash": ("dash at full speed", "sprint", "sprint forward", "run as fast as possible", "race ahead",
             "dash forward"),
    "walk-back": ("walk backward", "walk backwards", "step backward", "back up", "retreat step by step",
                  "walk in reverse"),
    "walk-left": ("walk forward and to the left", "walk diagonally to the left", "walk ahead toward the left",
                  "head forward and left", "walk off to the front left"),
    "walk-right": ("walk forward and to the right", "walk diagonally to the right", "walk ahead toward the right",
                   "head forward and right", "walk off to the front right"),
    "walk-turn-left": ("walk and turn left", "walk, then turn to the left", "turn left while walking",
                       "walk and make a left turn", "walk and curve to the left"),
    "walk-turn-right": ("walk and turn right", "walk, then turn to the right", "turn right while walking",
                        "walk and make a right turn", "walk and curve to the right"),
    "bow": ("bow", "take a bow", "bow politely", "bend forward at the waist to bow", "bow the head and upper body",
            "make a deep bow"),
    "bye": ("wave goodbye with one hand", "wave goodbye", "wave farewell with one hand", "say goodbye with a wave",
            "wave one hand to say bye"),
    "byebye": ("wave goodbye with both hands", "wave farewell with both hands", "wave both hands to say goodbye",
               "say bye-bye with both hands"),
    "guide": ("gesture to show someone the way", "point the way", "show someone the direction with an arm",
              "guide someone with a gesture of the hand", "direct someone with an open hand"),
    "respond": ("respond to someone with a gesture", "answer someone with a gesture", "reply with a hand gesture",
                "react to someone with the hands"),
    "call": ("beckon someone to come over", "call someone over", "motion for someone to come closer",
             "wave someone over", "gesture for someone to approach"),
    "punch": ("throw punches", "punch", "punch forward", "jab with the fists", "strike with the fists",
              "throw a few punches"),
    "kick": ("kick", "kick forward", "kick with one leg", "kick out with a foot", "do a kick",
             "swing a leg to kick"),
    "slash": ("swing an arm as if slashing with a sword", "slash with an imaginary sword", "make sword slashes",
              "cut through the air as if holding a blade", "swing a sword"),
    "dance-short": ("dance", "dance briefly", "do a short dance", "dance in place"),
    "dance-long": ("dance", "dance for a while", "keep dancing", "perform a dance"),
    "wave-both-hands": ("wave both hands", "wave both arms", "wave with both hands", "wave both hands in the air",
                        "wave with two hands"),
    "wave-left-hand": ("wave the left hand", "wave the left arm", "wave with the left hand",
                       "raise the left hand and wave it"),
    "wave-right-hand": ("wave the right hand", "wave the right arm", "wave with the right hand",
                        "raise the right hand and wave it"),
    "raise-up-both-hands": ("raise both hands", "raise both arms", "lift both hands", "lift both arms over the head",
                            "put both hands up", "hold both arms up high", "raise both hands above the head"),
    "raise-up-left-hand": ("raise the left hand", "raise the left arm", "lift the left hand", "put the left hand up",
                           "hold the left arm up high", "lift the left arm above the head"),
    "raise-up-right-hand": ("raise the right hand", "raise the right arm", "lift the right hand",
                            "put the right hand up", "hold the right arm up high", "lift the right arm above the head"),
    "run-back": ("run backward", "jog backwards", "run in reverse"),
    "sidestep-walk": ("walk sideways", "sidestep", "step to the side"),
    "sidestep-run": ("run sideways", "shuffle quickly to the side"),
    "idle": ("stand in place", "stand still", "stay where they are"),
    "transition": ("move, switching between gaits", "change from one gait to another"),
    "unlabelled": ("move",),
}  # fmt: skip

# Style label -> manner words (adverbial phrases) and adjectives for the subject ("a tired man").
STYLE_WORDING: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "normal": (("",), ()),
    "happy": (("happily", "cheerfully", "in a happy mood", "joyfully"), ("happy", "cheerful")),
    "sad": (("sadly", "gloomily", "in a sad way", "dejectedly"), ("sad", "gloomy")),
    "angry": (("angrily", "furiously", "in an angry way"), ("angry", "furious")),
    "proud": (("proudly", "with pride", "confidently, chest out"), ("proud",)),
    "not-confident": (("timidly, without confidence", "shyly", "hesitantly", "unsurely"), ("timid", "shy")),
    "masculinity": (("in a masculine manner", "in a manly way", "with a masculine posture"), ("masculine",)),
    "masculine": (("in a masculine manner", "in a manly way", "with a masculine posture"), ("masculine",)),
    "feminine": (("in a feminine manner", "in a ladylike way", "gracefully, in a feminine style"), ("feminine",)),
    "childish": (("like a child", "childishly", "in a childlike way"), ("childish",)),
    "old": (("like an old person", "slowly, like an old man", "stiffly, like an elderly person"), ("old", "elderly")),
    "elderly": (("like an elderly person", "slowly, like an old person", "stiffly, like an elderly person"),
                ("elderly", "old")),
    "tired": (("wearily, as if tired", "tiredly", "wearily", "as if worn out"), ("tired", "weary")),
    "exhausted": (("as if exhausted", "in an exhausted way", "as if completely worn out"), ("exhausted",)),
    "active": (("energetically", "actively", "with a lot of energy", "vigorously"), ("energetic", "lively")),
    "youthful": (("in a youthful way", "with youthful energy", "like a young person"), ("young", "youthful")),
    "musical": (("rhythmically, as in a musical", "theatrically, as in a musical", "with a musical flair"), ()),
    "giant": (("heavily, like a giant", "with heavy, big movements", "like a giant"), ("giant", "huge")),
    "chimpira": (("with a swagger, like a street thug", "like a thug", "with a swagger"), ("swaggering",)),
    "unlabelled": (("",), ()),
}  # fmt: skip

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
