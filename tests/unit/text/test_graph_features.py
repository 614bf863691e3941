"""Node features of a semantic graph come from the right sub-word tokens of the embedded MiniLM encoder."""

from __future__ import annotations

import pytest
import torch

from motiondiff.text.encoders import build_text_encoder
from motiondiff.text.graph_features import node_features, word_pieces
from motiondiff.text.parse import parse_caption


@pytest.fixture(scope="module")
def encoder():
    return build_text_encoder("minilm")


def test_words_map_to_their_word_pieces(encoder):
    graph = parse_caption("A person somersaults forward, then waves.")
    hidden, mask, tokens = encoder.token_features([graph.text])
    pieces = word_pieces(graph, encoder.model.tokenizer, int(mask[0].sum()))
    for word, span in zip(graph.words, pieces, strict=True):
        joined = "".join(tokens[0][p].removeprefix("##") for p in span)
        assert joined == word.lower(), (word, [tokens[0][p] for p in span])


def test_node_features_pool_the_right_tokens(encoder):
    graph = parse_caption("a person walks forward and then turns left")
    (feats,) = node_features([graph], encoder)
    hidden, mask, tokens = encoder.token_features([graph.text])
    h, valid = hidden[0], int(mask[0].sum())
    assert feats.shape == (len(graph.nodes), encoder.dim)
    torch.testing.assert_close(feats[0], h[:valid].mean(0))  # motion node: the sentence (mean of the tokens)
    walks = graph.nodes[graph.action_ids()[0]]
    assert tokens[0][walks.head + 1] == "walks"  # one piece per word here: position = word index + 1 ([CLS])
    torch.testing.assert_close(feats[graph.action_ids()[0]], h[walks.head + 1])
    subject = next(i for i, n in enumerate(graph.nodes) if n.kind == "specific" and n.text == "a person")
    torch.testing.assert_close(feats[subject], h[[1, 2]].mean(0))  # mean of "a" and "person"


def test_batch_equals_one_by_one(encoder):
    graphs = [parse_caption("someone jumps"), parse_caption("a man picks up a box with his right hand")]
    together = node_features(graphs, encoder)
    for g, f in zip(graphs, together, strict=True):
        torch.testing.assert_close(node_features([g], encoder)[0], f, atol=1e-5, rtol=1e-4)
