"""Varied generated captions: every action has several wordings, verbs are inflected correctly, a clip's pool mixes
sentence shapes and tenses, and the label caption stays first; rare actions go to train."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motiondiff.data.preparing.caption_wording import (
    ACTION_WORDING,
    STYLE_WORDING,
    inflect,
    inflect_phrase,
    varied_captions,
)
from motiondiff.data.preparing.captions import (
    CONTENT_PHRASES,
    STYLE_PHRASES,
    MotionFacts,
    generate_captions,
    normalise_caption,
)
from motiondiff.data.preparing.prepare import caption_seed
from motiondiff.data.preparing.splits import rare_to_train

FACTS = MotionFacts(4.0, 3.1, 3.3, "forward", 5.0, 0.8, (), ())


@pytest.mark.parametrize(
    ("verb", "forms"),
    [("run", ("runs", "running", "ran")), ("dash", ("dashes", "dashing", "dashed")),
     ("wave", ("waves", "waving", "waved")), ("jog", ("jogs", "jogging", "jogged")),
     ("carry", ("carries", "carrying", "carried")), ("bow", ("bows", "bowing", "bowed")),
     ("take", ("takes", "taking", "took")), ("punch", ("punches", "punching", "punched"))],
)  # fmt: skip
def test_inflect(verb, forms):
    assert tuple(inflect(verb, f) for f in ("third", "ing", "past")) == forms


def test_inflect_phrase_handles_coordinated_verbs_only():
    assert inflect_phrase("walk and turn left", "third") == "walks and turns left"
    assert inflect_phrase("walk, then turn to the left", "past") == "walked, then turned to the left"
    assert inflect_phrase("walk forward and to the left", "ing") == "walking forward and to the left"
    assert inflect_phrase("raise the right hand and wave it", "third") == "raises the right hand and waves it"


def test_every_label_has_varied_wording():
    assert set(CONTENT_PHRASES) <= set(ACTION_WORDING)
    assert set(STYLE_PHRASES) <= set(STYLE_WORDING)
    bandai = [c for c in CONTENT_PHRASES if c not in ("run-back", "sidestep-walk", "sidestep-run", "idle",
                                                          "transition", "unlabelled")]  # fmt: skip
    assert all(len(ACTION_WORDING[c]) >= 4 for c in bandai)


def test_pool_mixes_shapes_and_keeps_the_label_caption_first():
    rng = np.random.default_rng(0)
    caps = generate_captions("raise-up-both-hands", "tired", FACTS, rng, variants=12)
    assert caps[0].endswith("raises both hands wearily, as if tired.")  # the label caption the metric asks with
    assert len(caps) == 3 + 12 and len(set(caps)) == len(caps)
    varied = caps[3:]
    assert any(" is " in c for c in varied)  # progressive
    assert any(c.split()[0].endswith("ing") for c in varied)  # bare gerund
    assert any(w in c for c in varied for w in ("raised", "lifted", "put both", "held"))  # past tense
    assert len({c.split()[0] for c in varied}) >= 3  # several subjects / shapes
    assert generate_captions("walk", "normal", FACTS, np.random.default_rng(0)) == caps[:0] + generate_captions(
        "walk", "normal", FACTS, np.random.default_rng(0), variants=0)  # fmt: skip


def test_varied_captions_never_repeat_and_name_the_side():
    caps = varied_captions("wave-left-hand", "normal", np.random.default_rng(1), 10)
    assert len(caps) == len(set(caps)) >= 8
    assert all("left" in c for c in caps) and not any("right" in c for c in caps)


def test_caption_seed_differs_per_clip_with_variants():
    a, b = "dataset-2_walk_active_001", "dataset-2_walk_active_002"
    assert caption_seed(0, a, 0) == caption_seed(0, b, 0)  # the embedded data's seed, kept for `make data`
    assert caption_seed(0, a, 12) != caption_seed(0, b, 12)
    assert caption_seed(0, a, 12) == caption_seed(0, a, 12)


def test_rare_actions_go_to_train():
    split = ["val", "train", "test", "train", "val", "test", "train"]
    labels = ["kick", "walk", "walk", "walk", "walk", "punch", "punch"]
    assert rare_to_train(split, labels, 3) == ["train", "train", "test", "train", "val", "train", "train"]
    assert rare_to_train(split, labels, 0) == split


def test_paraphrase_set_is_kept_out_of_generated_captions():
    """The human-style paraphrases (data/paraphrases) cover every Bandai action; a generated caption that happens to
    equal one is left out (the label caption takes another subject), so no model trains on them."""
    from motiondiff.data.datamodules import embedded_data_root
    from motiondiff.data.preparing.prepare import load_held_out

    path = embedded_data_root().parent / "paraphrases" / "bandai_human.json"
    items = json.loads(path.read_text())["descriptions"]
    assert len(items) >= 60 and len({d["action"] for d in items}) >= 24
    assert {d["action"] for d in items} <= set(ACTION_WORDING)
    held_out = load_held_out([path])
    clashes = 0
    for content in ACTION_WORDING:
        for style in STYLE_WORDING:
            free = generate_captions(content, style, FACTS, np.random.default_rng(3), variants=40)
            kept = generate_captions(content, style, FACTS, np.random.default_rng(3), variants=40, held_out=held_out)
            assert not {normalise_caption(c) for c in kept} & held_out
            assert kept[0].split(" ", 2)[-1] == free[0].split(" ", 2)[-1] or kept[0].endswith(free[0].split()[-1])
            clashes += len(free) - len(kept)
    assert clashes > 0  # the generator does produce some of them (short sentences coincide): the filter matters
    assert normalise_caption("  A Man  takes a bow. ") == "a man takes a bow"


def test_broad_wording_names_the_action_in_every_sentence_and_adds_context_and_noise_without_touching_sides():
    """`--caption-wording broad`: no sentence of measurements alone (it fits several actions), context clauses and
    surface noise on the varied sentences, and the side words the mirror swaps stay intact."""
    from motiondiff.data.preparing.caption_noise import LEADS, TAILS, broaden

    still = MotionFacts(6.0, 0.1, 0.3, None, 0.0, 0.05, ("right",), ("right",))
    plain = generate_captions("wave-right-hand", "normal", still, np.random.default_rng(0), variants=12)
    assert plain[2].endswith("stays in place, with the right hand above the head.")  # the sentence broad replaces
    pools = [generate_captions("wave-right-hand", "normal", still, np.random.default_rng(s), 12, wording="broad")
             for s in range(20)]  # fmt: skip
    assert pools[0][0] == plain[0]  # the same label caption from the same seed

    def names_wave(c: str) -> bool:  # "waves", or one of its letter swaps ("wvaes")
        return any(sorted(w.strip(".,")) in (sorted("wave"), sorted("waves"), sorted("waved"), sorted("waving"))
                   for w in c.lower().split())  # fmt: skip

    assert all(names_wave(c) for p in pools for c in p)
    assert all(
        p[2].endswith("waves the right hand, staying in place, with the right hand above the head.") for p in pools
    )
    varied = [c for p in pools for c in p[3:]]
    assert any(t in c for c in varied for t in TAILS) and any(c.lower().startswith(LEADS) for c in varied)
    assert any(not c.endswith(".") for c in varied) and any(c[0].isupper() for c in varied)
    assert all(c.lower().count("right") >= 1 and "left" not in c.lower() for c in varied)
    rng = np.random.default_rng(3)
    swapped = {broaden("someone raises the right hand and waves it.", rng, context=0, noise=1) for _ in range(60)}
    typos = [c for c in swapped if c.rstrip(".").lower() != "someone raises the right hand and waves it"]
    assert typos and all("right" in c.lower() for c in swapped)
    assert all(sorted(c.lower().rstrip(".")) == sorted("someone raises the right hand and waves it") for c in typos)
    with pytest.raises(ValueError, match="plain or broad"):
        generate_captions("walk", "normal", still, np.random.default_rng(0), wording="messy")
