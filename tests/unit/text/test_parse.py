"""Caption -> semantic graph (GuidedMotion): hand-checked parses, graph invariants, statistics and the CLI."""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest

from motiondiff.text.parse import (
    ROLES,
    CaptionGraph,
    caption_statistics,
    load_kitml_captions,
    main,
    parse_caption,
    parse_captions,
)

KITML = Path("/work/shared/reference/kitml-captions/annotations.json")


def actions(graph: CaptionGraph) -> list[str]:
    return [graph.nodes[i].text for i in graph.action_ids()]


def roles(graph: CaptionGraph, action: int = 0) -> list[tuple[str, str]]:
    """(role, phrase) pairs of the action-th action node, in caption order."""
    return [(role, node.text) for role, node in graph.specifics_of(graph.action_ids()[action])]


# caption -> [(action text, [(role, phrase), ...], local description), ...], checked by hand
HAND_CHECKED = {
    "a person walks forward and then turns left": [
        ("walks", [("ARG0", "a person"), ("ARGM-DIR", "forward")], "walks forward"),
        ("turns", [("ARG0", "a person"), ("ARGM-TMP", "then"), ("ARGM-DIR", "left")], "turns left"),
    ],
    "someone picks up an object with his right hand": [
        (
            "picks up",
            [("ARG0", "someone"), ("ARG1", "an object"), ("ARG2", "with his right hand")],
            "picks up an object with his right hand",
        ),
    ],
    "a man is walking slowly in a circle": [
        (
            "walking",
            [("ARG0", "a man"), ("ARGM-MNR", "slowly"), ("ARGM-DIR", "in a circle")],
            "walking slowly in a circle",
        ),
    ],
    "a person walking forward": [("walking", [("ARG0", "a person"), ("ARGM-DIR", "forward")], "walking forward")],
    "the person jumps from the box to the floor": [
        (
            "jumps",
            [("ARG0", "the person"), ("ARG3", "from the box"), ("ARG4", "to the floor")],
            "jumps from the box to the floor",
        ),
    ],
    "a person walks forward while waving his arms": [
        (
            "walks",
            [("ARG0", "a person"), ("ARGM-DIR", "forward"), ("ARGM-TMP", "while waving his arms")],
            "walks forward",
        ),
        ("waving", [("ARG0", "a person"), ("ARG1", "his arms")], "waving his arms"),
    ],
    "a person jogs in place, then sits down on the floor twice": [
        ("jogs", [("ARG0", "a person"), ("ARGM-LOC", "in place")], "jogs in place"),
        (
            "sits down",
            [("ARG0", "a person"), ("ARGM-TMP", "then"), ("ARGM-LOC", "on the floor"), ("ARGM-TMP", "twice")],
            "sits down on the floor twice",
        ),
    ],
    "A person is pushed from behind and falls down": [
        ("pushed", [("ARG1", "A person"), ("ARGM-DIR", "from behind")], "pushed from behind"),
        ("falls down", [("ARG0", "A person")], "falls down"),
    ],
    "a man moves like a monkey": [("moves", [("ARG0", "a man"), ("ARGM-MNR", "like a monkey")], "moves like a monkey")],
}


@pytest.mark.parametrize("caption", list(HAND_CHECKED))
def test_hand_checked_parses(caption):
    graph = parse_caption(caption)
    expected = HAND_CHECKED[caption]
    assert actions(graph) == [a for a, _, _ in expected]
    for k, (_, expected_roles, _) in enumerate(expected):
        assert roles(graph, k) == expected_roles
    assert graph.action_texts() == [local for _, _, local in expected]
    assert graph.fallback is None


@pytest.mark.parametrize("caption", [*HAND_CHECKED, "A human waves with his right hand.", "jumping jacks"])
def test_graph_invariants(caption):
    graph = parse_caption(caption)
    motion = graph.nodes[0]
    assert motion.kind == "motion" and motion.text == caption.strip() and motion.head is None
    assert [n.kind for n in graph.nodes[1:]].count("motion") == 0
    for a in graph.action_ids():  # every action hangs off the motion node with the paper's motion-action type
        assert graph.edges.count(type(graph.edges[0])(0, a, "ARGM-MA")) == 1
    for edge in graph.edges:
        assert edge.role in ROLES
        src, dst = graph.nodes[edge.source], graph.nodes[edge.target]
        assert (src.kind, dst.kind) in {("motion", "action"), ("action", "specific")}
        assert (edge.role == "ARGM-MA") == (src.kind == "motion")
    for node in graph.nodes:  # word indices agree with the text, so features can be pooled per node
        assert node.start == node.indices[0] and node.end == node.indices[-1] + 1
        if node.kind == "specific":
            assert node.text == " ".join(graph.words[node.start : node.end]).replace(" ,", ",")
        if node.kind == "action":
            assert node.head in node.indices


def test_shared_subject_is_one_node_with_two_edges():
    graph = parse_caption("a person walks forward and then turns left")
    walks, turns = graph.action_ids()
    subject = [e.target for e in graph.edges if e.role == "ARG0"]
    assert len(subject) == 2 and subject[0] == subject[1]
    assert {e.source for e in graph.edges if e.target == subject[0]} == {walks, turns}


def test_verb_mistagged_as_noun_is_repaired():
    # the small model reads "A human waves" as adjective + plural noun: the subject-predicate split fixes it
    graph = parse_caption("A human waves with his right hand.")
    assert graph.fallback == "repaired"
    assert actions(graph) == ["waves"]
    assert roles(graph) == [("ARG0", "A human"), ("ARG2", "with his right hand")]
    assert graph.action_texts(include_agent=True) == ["A human waves with his right hand"]


def test_nominal_predicate_fallback():
    graph = parse_caption("jumping jacks")
    assert graph.fallback == "nominal" and actions(graph) == ["jumping jacks"]
    assert parse_caption("a jump to the right").action_texts() == ["jump to the right"]


def test_auxiliary_is_not_an_action_but_a_main_verb_be_is():
    assert actions(parse_caption("a man is walking")) == ["walking"]
    assert actions(parse_caption("a person is on his knees")) == ["is"]


@pytest.mark.parametrize("bad", ["", "   ", "\n\t"])
def test_empty_caption_raises(bad):
    with pytest.raises(ValueError, match="non-empty"):
        parse_caption(bad)
    with pytest.raises(ValueError, match="non-empty"):
        parse_captions(["a person walks", bad])


STAT_CAPTIONS = [
    "a person walks forward",  # 1 action
    "a person walks forward and then turns left",  # 2
    "a person jogs in place, then sits down on the floor twice",  # 2
    "someone picks up an object with his right hand",  # 1
    "a man is walking slowly in a circle",  # 1
    "a person walks forward, turns around and walks back",  # 3
    "A human waves with his right hand.",  # 1 (repaired)
    "jumping jacks",  # 1 (nominal)
    "The person first",  # 0: no predicate at all
    "a person stands up, raises his arms, lowers them, turns around and sits down",  # 5
]


def test_caption_statistics():
    stats = caption_statistics(STAT_CAPTIONS, batch_size=4)
    assert stats["n_captions"] == 10
    assert stats["n_with_action"] == 9 and stats["share_with_action"] == pytest.approx(0.9)
    assert stats["action_count_hist"] == {"0": 1, "1": 5, "2": 2, "3": 1, "4": 0, "5+": 1}
    n_actions = 5 + 2 * 2 + 3 + 5
    assert stats["node_kind_counts"]["motion"] == 10
    assert stats["node_kind_counts"]["action"] == n_actions == stats["edge_role_counts"]["ARGM-MA"]
    assert list(stats["edge_role_counts"]) == list(ROLES)
    assert stats["edge_role_counts"]["ARG0"] >= 9  # every caption with a subject contributes
    assert stats["fallback_counts"] == {"none": 8, "repaired": 1, "nominal": 1}


def _write_annotations(path: Path, texts: list[str]) -> None:
    entries = {f"{i:05d}": {"path": f"KIT/x/{i}", "duration": 1.0, "annotations": [{"seg_id": f"{i:05d}_0",
               "text": t, "start": 0.0, "end": 1.0}]} for i, t in enumerate(texts)}  # fmt: skip
    entries["M00000"] = {"path": "M/KIT/x/0", "duration": 1.0, "annotations": [{"text": "mirrored"}]}
    path.write_text(json.dumps(entries))


def test_cli_writes_report(tmp_path, capsys):
    captions, out = tmp_path / "annotations.json", tmp_path / "out" / "parses.md"
    _write_annotations(captions, STAT_CAPTIONS)
    assert main(["--captions", str(captions), "--out", str(out), "--seed", "1", "--samples", "3"]) == 0
    report = out.read_text()
    assert "9 / 10 = 90.00 %" in report and "11 annotation texts in the file" in report
    assert "| ARGM-MA |" in report and "## 3 random parses (seed 1)" in report
    assert report.count("\n**") == 3  # three rendered captions
    assert "with >= 1 action: 9 (90.00 %)" in capsys.readouterr().out


def test_cli_missing_file_names_path_and_layout(tmp_path, capsys):
    missing = tmp_path / "nope" / "annotations.json"
    assert main(["--captions", str(missing), "--out", str(tmp_path / "x.md")]) == 2
    err = capsys.readouterr().err
    assert str(missing) in err and "TMR" in err
    assert not (tmp_path / "x.md").exists()


def test_kitml_captions_mostly_have_actions():
    if not KITML.exists():
        pytest.skip(f"{KITML} not found: needs the project's shared KIT-ML captions (TMR layout)")
    texts, n_in_file = load_kitml_captions(KITML)
    assert (len(texts), n_in_file) == (6082, 12164)  # originals; the file adds the left/right-mirrored copies
    sample = random.Random(0).sample(texts, 600)  # a subset keeps the test fast; the CLI parses all of them
    assert caption_statistics(sample)["share_with_action"] >= 0.95
