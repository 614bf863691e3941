"""GuidedMotion's graph attention over a caption's semantic graph (paper §3.2, eqs. 6-8 and the node embeddings).

For connected nodes i, j with edge type r_ij (one of the 12 roles of ``motiondiff.text.parse.ROLES``):

    h = W v                                    (W: D x D, shared by all nodes)
    h~_ij = [h_i, h_j]                         (2D)
    e_ij = LeakyReLU_0.2(M^T h~_ij) + LeakyReLU_0.2(R_ij M_r^T h~_ij)
                                               (M: 2D x 1 shared by all edge types, M_r: 2D x N one column per type,
                                                R_ij the one-hot type, so R_ij M_r^T h~_ij picks column r_ij)
    e~_ij = softmax over the neighbours j of i of e_ij
    V_i = ELU(sum_j e~_ij h_j) + v_i           (ELU as in GAT, skip connection against over-smoothing)

Neighbourhoods are the graph's edges taken both ways with the same type and no self-loops (the skip connection
carries the node itself); a node without neighbours keeps V_i = ELU(0) + v_i = v_i. The guiding weight of local
action k is the motion node's attention on it, e~^k = e~_{motion, action k} (softmax over the motion node's
neighbours, i.e. its actions, so the weights of one caption sum to 1).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import torch
from torch import Tensor, nn
from torch.nn import functional as F

NO_EDGE = -1
NODE_KINDS = ("motion", "action", "specific")  # index = kind id in GraphBatch.kinds


def edge_type_matrix(num_nodes: int, edges: Sequence, roles: Sequence[str]) -> torch.Tensor:
    """(n, n) long matrix of edge-type indices into ``roles`` (NO_EDGE where unconnected), symmetric. ``edges``:
    objects with .source, .target, .role (``motiondiff.text.parse.Edge``) or (source, target, role) tuples."""
    types = torch.full((num_nodes, num_nodes), NO_EDGE, dtype=torch.long)
    index = {r: k for k, r in enumerate(roles)}
    for edge in edges:
        s, t, role = (edge.source, edge.target, edge.role) if hasattr(edge, "role") else edge
        if role not in index:
            raise ValueError(f"edge role {role!r} is not one of the {len(roles)} roles: {', '.join(roles)}")
        if s == t or not (0 <= s < num_nodes and 0 <= t < num_nodes):
            raise ValueError(f"edge {s} -> {t} does not join two different nodes of a {num_nodes}-node graph")
        types[s, t] = types[t, s] = index[role]
    return types


class SemanticGraphAttention(nn.Module):
    """One graph-attention layer with shared and per-edge-type scores; returns (V, e~) for node features v
    (B, n, D) and edge types (B, n, n) from ``edge_type_matrix`` (padding nodes: no edges)."""

    def __init__(self, dim: int, num_edge_types: int = 12, negative_slope: float = 0.2):
        super().__init__()
        self.W = nn.Linear(dim, dim, bias=False)
        self.M = nn.Parameter(torch.empty(2 * dim))
        self.M_r = nn.Parameter(torch.empty(2 * dim, num_edge_types))
        self.negative_slope = negative_slope
        bound = (1.0 / (2 * dim)) ** 0.5
        nn.init.uniform_(self.M, -bound, bound)
        nn.init.uniform_(self.M_r, -bound, bound)

    def scores(self, h: torch.Tensor, types: torch.Tensor) -> torch.Tensor:
        """e_ij (B, n, n) for every pair; meaningful where types >= 0."""
        d = h.shape[-1]
        # [h_i, h_j]·m = h_i·m[:D] + h_j·m[D:], so no (B, n, n, 2D) tensor is built
        shared = (h @ self.M[:d])[:, :, None] + (h @ self.M[d:])[:, None, :]
        typed = (h @ self.M_r[:d])[:, :, None, :] + (h @ self.M_r[d:])[:, None, :, :]  # (B, n, n, N)
        typed = typed.gather(-1, types.clamp(min=0)[..., None]).squeeze(-1)
        return F.leaky_relu(shared, self.negative_slope) + F.leaky_relu(typed, self.negative_slope)

    def forward(self, v: torch.Tensor, types: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        if v.dim() == 2:
            node_embeddings, attention = self.forward(v[None], types[None])
            return node_embeddings[0], attention[0]
        connected = types >= 0
        h = self.W(v)
        e = self.scores(h, types).masked_fill(~connected, float("-inf"))
        # a node without neighbours: all -inf gives NaN in softmax; its weights are 0 instead
        attention = torch.softmax(e, dim=-1).nan_to_num(0.0) * connected
        return F.elu(attention @ h) + v, attention


def action_weights(attention: torch.Tensor, motion: int, actions: Sequence[int]) -> torch.Tensor:
    """e~^k: the motion node's attention on each action node (the local actions' guiding weights)."""
    return attention[..., motion, list(actions)]


@dataclass
class GraphBatch:
    """Padded caption graphs: node features (B, K, D), kind ids (B, K) into NODE_KINDS (−1: padding), edge types
    (B, K, K) from ``models.graph.edge_type_matrix`` (−1: none), the motion node's index and action nodes' indices
    (B, A) (−1: padding), in each graph's action order."""

    features: Tensor
    kinds: Tensor
    types: Tensor
    actions: Tensor

    @property
    def valid(self) -> Tensor:
        return self.kinds >= 0

    def to(self, device) -> GraphBatch:
        return GraphBatch(*(t.to(device) for t in (self.features, self.kinds, self.types, self.actions)))

    def index(self, rows) -> GraphBatch:
        return GraphBatch(self.features[rows], self.kinds[rows], self.types[rows], self.actions[rows])


def batch_graphs(graphs: Sequence, features: Sequence[torch.Tensor], roles: Sequence[str]) -> GraphBatch:
    """Pad caption graphs (``motiondiff.text.parse.CaptionGraph``) and their node features ((n_i, D) each, node
    order as in the graph) into one GraphBatch."""
    if len(graphs) != len(features):
        raise ValueError(f"{len(graphs)} graphs but {len(features)} feature tensors")
    k = max(len(g.nodes) for g in graphs)
    a = max(1, max(len(g.action_ids()) for g in graphs))
    b, d = len(graphs), features[0].shape[-1]
    out = GraphBatch(
        torch.zeros(b, k, d),
        torch.full((b, k), -1, dtype=torch.long),
        torch.full((b, k, k), NO_EDGE, dtype=torch.long),
        torch.full((b, a), -1, dtype=torch.long),
    )
    for i, (graph, feats) in enumerate(zip(graphs, features, strict=True)):
        n = len(graph.nodes)
        if feats.shape[0] != n:
            raise ValueError(f"graph {i} has {n} nodes but {feats.shape[0]} feature rows")
        out.features[i, :n] = feats
        out.kinds[i, :n] = torch.tensor([NODE_KINDS.index(node.kind) for node in graph.nodes])
        out.types[i, :n, :n] = edge_type_matrix(n, graph.edges, roles)
        ids = graph.action_ids()
        out.actions[i, : len(ids)] = torch.tensor(ids, dtype=torch.long)
    return out
