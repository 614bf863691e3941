"""Caption parser rules (`motiondiff.text.parse`, whose docstring documents them): which tokens are actions
(plain verbs, repairs of verbs the tagger mislabelled, nominal predicates), the argument phrases of an action with
their implicit subjects, and the role of each phrase.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from motiondiff.text.parse_lexicon import (
    CLAUSE_DEPS,
    CLAUSE_ON_NOUN_DEPS,
    DIRECTION_NOUNS,
    DIRECTION_PREPS,
    DIRECTION_WORDS,
    DISCOURSE_WORDS,
    GOAL_PREPS,
    HEAD_ARGUMENT_DEPS,
    INHERIT_DEPS,
    INSTRUMENT_PREPS,
    LOCATION_PREPS,
    LOCATION_WORDS,
    MANNER_NOUNS,
    MANNER_PREPS,
    MODIFIER_DEPS,
    PATH_NOUNS,
    SKIP_DEPS,
    START_PREPS,
    SUBJECT_DEPS,
    TIME_MARKERS,
    TIME_NOUNS,
    TIME_PREPS,
    TIME_WORDS,
    WH_TAGS,
    can_be_verb,
    can_head_subject,
    may_be_mistagged_verb,
)

if TYPE_CHECKING:
    from spacy.tokens import Doc, Token

__all__ = ["Argument", "action_words", "arguments_of", "find_actions", "role_of"]


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


def _subject_phrase(tok: Token) -> tuple[int, ...] | None:
    """Rule 2b: left modifiers of `tok` that open the sentence and include a possible subject head."""
    mods = [c for c in tok.lefts if c.dep_ in MODIFIER_DEPS]
    if tok.dep_ in ("compound", "amod", "nmod"):  # "a human plays guitar" read as one noun phrase "plays guitar"
        mods += [c for c in tok.head.lefts if c.i < tok.i and c.dep_ in MODIFIER_DEPS]
    mods.sort(key=lambda c: c.i)
    if not mods or mods[-1].lower_.endswith("ing"):  # "jumping jacks", "walking stick": a noun compound
        return None
    if not any(c.dep_ != "det" and can_head_subject(c) for c in mods):
        return None
    phrase = tuple(range(min(c.left_edge.i for c in mods), tok.i))
    covered = {t.i for c in mods for t in c.subtree}
    if phrase[0] != _sentence_start(tok) or not covered >= set(phrase):
        return None
    return phrase


def _repair_candidates(doc: Doc, strict: bool) -> tuple[list[Token], dict[int, tuple[int, ...]]]:
    """Rules 2a-2d: predicates the tagger mislabelled. Returns the tokens and the subject phrases found by 2b.
    strict (the caption has plain verbs too): only "-s" forms tagged as plural nouns (NNS) and words with an
    auxiliary, and no gerund rule ("is doing some stretching" has a real -ing noun)."""
    candidates = [t for t in doc if may_be_mistagged_verb(t)]
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


def action_words(verb: Token, nominal: bool) -> tuple[int, ...]:
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
