"""Node features of a caption's semantic graph from the text encoder's token features (GuidedMotion §3.2):
the motion node gets the sentence feature, an action node its verb's token feature, a specific node the mean of its
words' token features.

Words (spaCy tokens of ``CaptionGraph``) are matched to the encoder's sub-word tokens by tokenizing each word-boundary
prefix of the caption: both MiniLM's WordPiece and CLIP's BPE split on whitespace and punctuation first, so the
pieces of a prefix are the first pieces of the whole caption (a word split inside, like "do|n't", gets the nearest
pieces). A word that truncation cut off uses the last kept piece. The sentence feature is the mean over the valid
tokens, the encoder's own hidden states, so every node lives in one space (MiniLM's sentence embedding is that mean,
before its L2 normalisation).
"""

from __future__ import annotations

from collections.abc import Sequence

import torch

from motiondiff.text.parse import CaptionGraph, parse_captions


def _tokenizer(encoder):
    tokenizer = getattr(encoder, "tokenizer", None) or getattr(getattr(encoder, "model", None), "tokenizer", None)
    if tokenizer is None:
        raise TypeError(f"{type(encoder).__name__} exposes no tokenizer; node features need one to align words")
    return tokenizer


def word_pieces(graph: CaptionGraph, tokenizer, num_tokens: int) -> list[range]:
    """For each word of ``graph``, the positions of its sub-word tokens in the encoder's sequence (1 + pieces: the
    start token comes first), clamped to the ``num_tokens`` valid tokens (the end token excluded)."""
    last = max(num_tokens - 2, 1)  # the last piece before the end token
    ranges, offset, before = [], 0, 0
    for word, space in zip(graph.words, graph.whitespace or [" "] * len(graph.words), strict=True):
        offset += len(word)
        count = len(tokenizer.tokenize(graph.text[:offset]))
        lo, hi = min(1 + before, last), min(1 + max(count, before + 1), last + 1)
        ranges.append(range(lo, max(hi, lo + 1)))
        before = max(count, before)
        offset += len(space)
    return ranges


@torch.no_grad()
def node_features(graphs: Sequence[CaptionGraph], encoder) -> list[torch.Tensor]:
    """(num_nodes, D) features per graph, node order as in ``graph.nodes``."""
    if not graphs:
        return []
    hidden, mask, _ = encoder.token_features([g.text for g in graphs])
    tokenizer = _tokenizer(encoder)
    out = []
    for g, h, m in zip(graphs, hidden, mask, strict=True):
        valid = int(m.sum())
        pieces = word_pieces(g, tokenizer, valid)
        rows = []
        for node in g.nodes:
            if node.kind == "motion":
                rows.append(h[:valid].mean(0))
                continue
            words = [node.head] if node.kind == "action" and node.head is not None else list(node.indices)
            positions = sorted({p for w in words for p in pieces[w]})
            rows.append(h[positions].mean(0))
        out.append(torch.stack(rows))
    return out


def graph_table(texts: Sequence[str], encoder, batch_size: int = 64) -> dict[str, tuple[CaptionGraph, torch.Tensor]]:
    """caption -> (semantic graph, node features) for every distinct caption (parsed and encoded in batches)."""

    unique = sorted(set(texts))
    table = {}
    for start in range(0, len(unique), batch_size):
        chunk = unique[start : start + batch_size]
        graphs = parse_captions(chunk)
        for text, graph, feats in zip(chunk, graphs, node_features(graphs, encoder), strict=True):
            table[text] = (graph, feats.float().cpu())
    return table
