"""GENERATED captions for motion that has no human-written ones (e.g. the Bandai Namco clips).

Captions are built from two sources and are always marked as generated wherever they are stored:
- the clip's labels (content such as "walk-turn-left", style such as "tired"), through the phrase tables below;
- what the motion measurably does, from its canonical 22-joint positions (facing +Z at frame 0, x = left, y = up):
  distance and direction travelled, net turn, speed, and which hands rise above the head or shoulders.
Several phrasings per clip let text-conditioned training see varied wording, as with HumanML3D's 3+ captions; with
`variants`, many more from `caption_wording` (synonyms, body-part wording, tenses, sentence shapes); with
`wording="broad"`, every sentence names the action and the varied ones carry context clauses and surface noise
(`caption_noise`).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from motiondiff.data.preparing.caption_noise import broaden
from motiondiff.data.preparing.caption_wording import varied_captions
from motiondiff.geometry.skeleton import SMPL22

GENERATED_NOTE = "generated from labels and measured motion; not human-written"

# Content labels of both Bandai zips -> (verb phrase, short noun for "<style> <noun>") in present tense.
CONTENT_PHRASES = {
    "walk": "walks",
    "run": "runs",
    "dash": "dashes at full speed",
    "walk-back": "walks backward",
    "walk-left": "walks forward and to the left",  # measured: a diagonal path, body facing the way it goes
    "walk-right": "walks forward and to the right",
    "walk-turn-left": "walks and turns left",
    "walk-turn-right": "walks and turns right",
    "bow": "bows",
    "bye": "waves goodbye with one hand",
    "byebye": "waves goodbye with both hands",
    "guide": "gestures to show someone the way",
    "respond": "responds to someone with a gesture",
    "call": "beckons someone to come over",
    "punch": "throws punches",
    "kick": "kicks",
    "slash": "swings an arm as if slashing with a sword",
    "dance-short": "dances",
    "dance-long": "dances",
    "wave-both-hands": "waves both hands",
    "wave-left-hand": "waves the left hand",
    "wave-right-hand": "waves the right hand",
    "raise-up-both-hands": "raises both hands",
    "raise-up-left-hand": "raises the left hand",
    "raise-up-right-hand": "raises the right hand",
    # 100STYLE's content codes (motiondiff.data.preparing.from_bvh) and unlabelled BVH files
    "run-back": "runs backward",
    "sidestep-walk": "walks sideways",
    "sidestep-run": "runs sideways",
    "idle": "stands in place",
    "transition": "moves, switching between gaits",
    "unlabelled": "moves",
}

# Style labels -> adverbial phrase ("" for the neutral style).
STYLE_PHRASES = {
    "normal": "",
    "happy": "happily",
    "sad": "sadly",
    "angry": "angrily",
    "proud": "proudly",
    "not-confident": "timidly, without confidence",
    "masculinity": "in a masculine manner",
    "masculine": "in a masculine manner",
    "feminine": "in a feminine manner",
    "childish": "like a child",
    "old": "like an old person",
    "elderly": "like an elderly person",
    "tired": "wearily, as if tired",
    "exhausted": "as if exhausted",
    "active": "energetically",
    "youthful": "in a youthful way",
    "musical": "rhythmically, as in a musical",
    "giant": "heavily, like a giant",
    "chimpira": "with a swagger, like a street thug",
    "unlabelled": "",
}


@dataclass
class MotionFacts:
    """What a clip measurably does (metres, seconds, degrees)."""

    duration: float
    distance: float  # straight-line displacement of the root on the ground
    path_length: float
    direction: str | None  # "forward", "backward", "to the left", "to the right" relative to the start facing
    turn_degrees: float  # net change of facing, positive = to the left
    speed: float  # path length / duration
    hands_above_head: tuple[str, ...]  # "left", "right"
    hands_above_shoulders: tuple[str, ...]


def measure(joints: np.ndarray, fps: float = 20.0) -> MotionFacts:
    """Facts from canonical SMPL-22 joints (F, 22, 3)."""
    names = SMPL22.joint_names
    idx = {n: names.index(n) for n in ("pelvis", "head", "l_wrist", "r_wrist", "l_shoulder", "r_shoulder")}
    root = joints[:, idx["pelvis"], [0, 2]]
    steps = np.linalg.norm(np.diff(root, axis=0), axis=-1)
    duration = (len(joints) - 1) / fps
    disp = root[-1] - root[0]
    distance = float(np.linalg.norm(disp))
    direction = _direction(disp) if distance > 0.3 else None  # below ~one step the direction is noise
    turn = _facing_angle(joints[-1]) - _facing_angle(joints[0])
    turn = float((np.degrees(turn) + 180.0) % 360.0 - 180.0)
    min_time = int(round(0.3 * fps))  # a hand counts as raised when it stays up for 0.3 s

    def raised(above: np.ndarray) -> bool:
        return int(above.sum()) >= min_time

    head_y = joints[:, idx["head"], 1]
    above_head = tuple(
        s for s, w in (("left", "l_wrist"), ("right", "r_wrist")) if raised(joints[:, idx[w], 1] > head_y)
    )
    above_sh = tuple(
        s for s, w, sh in (("left", "l_wrist", "l_shoulder"), ("right", "r_wrist", "r_shoulder"))
        if raised(joints[:, idx[w], 1] > joints[:, idx[sh], 1] + 0.05)
    )  # fmt: skip
    return MotionFacts(
        duration=duration,
        distance=distance,
        path_length=float(steps.sum()),
        direction=direction,
        turn_degrees=turn,
        speed=float(steps.sum() / max(duration, 1e-6)),
        hands_above_head=above_head,
        hands_above_shoulders=above_sh,
    )


_DIRECTIONS = ("forward", "forward and to the left", "to the left", "backward and to the left", "backward",
               "backward and to the right", "to the right", "forward and to the right")  # fmt: skip


def _direction(disp: np.ndarray) -> str:
    """One of 8 directions of a ground displacement (x = left, z = forward of the start facing)."""
    angle = np.degrees(np.arctan2(disp[0], disp[1]))  # 0 = forward, 90 = left
    return _DIRECTIONS[int(np.round(angle / 45.0)) % 8]


def _facing_angle(frame: np.ndarray) -> float:
    """Yaw of the body's forward direction (0 = +Z, positive towards +X = left)."""
    across = (frame[2] - frame[1]) + (frame[17] - frame[16])  # right minus left (hips + shoulders)
    forward = np.cross([0.0, 1.0, 0.0], across)
    return float(np.arctan2(forward[0], forward[2]))


def _hands_phrase(hands: tuple[str, ...], where: str) -> str:
    if len(hands) == 2:
        return f"with both hands {where}"
    return f"with the {hands[0]} hand {where}"


def _round_metres(d: float) -> str:
    return f"{d:.1f} meters" if d < 10 else f"{d:.0f} meters"


def _turn_phrase(turn: float) -> str:
    side = "left" if turn > 0 else "right"
    deg = int(round(abs(turn) / 15.0) * 15)  # people say "90 degrees", not "87"
    if deg >= 165:
        return "turning around"
    return f"turning about {deg} degrees to the {side}"


SUBJECTS = ("a person", "someone", "a man", "a woman", "the person")
WORDINGS = ("plain", "broad")  # generate_captions(wording=...): clean templates, or also context and surface noise


def normalise_caption(text: str) -> str:
    """Lower case, single spaces, no final full stop: how captions are compared with a held-out set."""
    return " ".join(text.lower().split()).rstrip(".")


def generate_captions(
    content: str,
    style: str,
    facts: MotionFacts,
    rng: np.random.Generator,
    variants: int = 0,
    held_out: Collection[str] = frozenset(),
    wording: str = "plain",
) -> list[str]:
    """Phrasings for one clip, all generated: labels only (first: the label caption evaluation uses), labels +
    measured details, measured only, then `variants` sentences in varied wording (`caption_wording`).
    `wording="broad"`: the third sentence names the action beside what was measured (a sentence of measurements
    alone, such as "stays in place, with the right hand above the head", fits several actions and teaches none of
    them), and the varied sentences go through `caption_noise.broaden`.
    `held_out` (normalised with `normalise_caption`): sentences that must never be a training caption, such as an
    evaluation's human-written paraphrases; one the generator happens to produce is left out (the label caption
    takes another subject)."""
    verb = CONTENT_PHRASES.get(content, content.replace("-", " ") + "s")
    manner = STYLE_PHRASES.get(style, f"in a {style.replace('-', ' ')} style")
    subjects = [str(s) for s in rng.choice(SUBJECTS, size=3, replace=False)]
    details = _detail_phrases(facts)
    label_caption = _sentence(subjects[0], verb, manner)
    for subject in SUBJECTS:
        if normalise_caption(label_caption) not in held_out:
            break
        label_caption = _sentence(subject, verb, manner)
    captions = [label_caption]
    if details:
        captions.append(_sentence(subjects[1], verb, manner, ", ".join(details)))
    travel = (
        f"travels {facts.direction} {_round_metres(facts.distance)} at {facts.speed:.1f} m/s"
        if facts.direction is not None
        else "stays in place"
    )
    measured = ", ".join(d for d in details if not d.startswith("moving"))
    if wording == "broad":
        travel = f"{verb}, {'staying in place' if facts.direction is None else travel.replace('travels', 'travelling')}"
    elif wording not in WORDINGS:
        raise ValueError(f"caption wording must be {' or '.join(WORDINGS)}, got {wording!r}")
    captions.append(_sentence(subjects[2], travel, "", measured))
    if variants:
        varied = [c for c in varied_captions(content, style, rng, variants + 3) if c not in captions][:variants]
        captions += [broaden(c, rng) for c in varied] if wording == "broad" else varied
    return captions[:1] + [c for c in captions[1:] if normalise_caption(c) not in held_out]


def _detail_phrases(facts: MotionFacts) -> list[str]:
    details = []
    if facts.direction is not None:
        details.append(f"moving {facts.direction} about {_round_metres(facts.distance)}")
    if abs(facts.turn_degrees) >= 30:
        details.append(_turn_phrase(facts.turn_degrees))
    if facts.hands_above_head:
        details.append(_hands_phrase(facts.hands_above_head, "above the head"))
    elif facts.hands_above_shoulders:
        details.append(_hands_phrase(facts.hands_above_shoulders, "above the shoulders"))
    return details


def _sentence(subject: str, verb: str, manner: str, detail: str = "") -> str:
    text = " ".join(p for p in (subject, verb, manner) if p)
    if detail:
        text += ", " + detail
    return text + "."
