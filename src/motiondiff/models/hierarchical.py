"""GuidedMotion's hierarchical latent denoisers (paper §3.3): three ε-predicting networks, one per latent level,

    φ_m(z^m, t, 𝒱^m)                      motion level   (Q = 2): the motion node's embedding
    φ_a(z^a, t, [𝒱^m, 𝒱^a, z^m])         action level   (Q = 4): + the action nodes and the motion latent
    φ_s(z^s, t, [𝒱^m, 𝒱^a, 𝒱^s, z^a])    specific level (Q = 8): + the specific nodes and the action latent

where 𝒱 are the caption graph's node embeddings after the graph attention (``models.graph``). Each network is a
transformer encoder over [time token, node tokens, previous-level latent tokens, noisy latent tokens] (as MLD's
denoiser reads its condition as tokens); it returns ε for the noisy latent tokens. Classifier-free guidance drops
the caption (its node tokens become one learnt ∅ token); the previous level's latent is kept, since it is the
structure the level refines, not text.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor, nn

from motiondiff.models.backbones.encoder_layer import TransformerSize
from motiondiff.models.embeddings import TimestepEmbedder
from motiondiff.models.graph import NODE_KINDS, GraphBatch, SemanticGraphAttention
from motiondiff.models.vae import LEVEL_TOKENS

LEVELS = ("motion", "action", "specific")
PREVIOUS = {"motion": None, "action": "motion", "specific": "action"}


class LatentDenoiser(nn.Module):
    """ε(z_t, t | node tokens of the allowed kinds, previous latent) for one level."""

    def __init__(
        self,
        latent_tokens: int,
        previous_tokens: int,
        node_dim: int,
        latent_dim: int = 256,
        *,
        kinds: tuple[int, ...] = (0,),
        **size: Any,
    ):
        """``size``: TransformerSize's fields (d_model, num_layers, ...), its defaults where not given."""
        super().__init__()
        size = TransformerSize(**size)
        d_model = size.d_model
        if d_model < latent_dim:  # ε is a full-rank latent_dim vector: a narrower stream cannot carry it through
            raise ValueError(f"the latent denoiser's d_model ({d_model}) must be at least the latent width "
                             f"({latent_dim}); raise latent.d_model or lower the VAEs' latent_dim")  # fmt: skip
        self.latent_tokens, self.previous_tokens, self.kinds = latent_tokens, previous_tokens, tuple(kinds)
        self.time = TimestepEmbedder(d_model)
        self.node_in = nn.Linear(node_dim, d_model)
        self.kind_embedding = nn.Embedding(len(NODE_KINDS), d_model)
        self.null_token = nn.Parameter(torch.zeros(1, 1, d_model))  # the ∅ caption of classifier-free guidance
        self.latent_in = nn.Linear(latent_dim, d_model)
        self.latent_position = nn.Parameter(torch.randn(latent_tokens, d_model) * 0.02)
        if previous_tokens:
            self.previous_in = nn.Linear(latent_dim, d_model)
            self.previous_position = nn.Parameter(torch.randn(previous_tokens, d_model) * 0.02)
        self.transformer = nn.TransformerEncoder(size.layer(), size.num_layers, enable_nested_tensor=False)
        self.norm = nn.LayerNorm(d_model)
        self.out = nn.Linear(d_model, latent_dim)

    def forward(
        self,
        z: Tensor,
        t: Tensor,
        cond: Tensor,
        kinds: Tensor,
        previous: Tensor | None = None,
        drop_cond: Tensor | None = None,
    ) -> Tensor:
        """z (B, Q, D'), t (B,), cond (B, K, node_dim) node embeddings, kinds (B, K) kind ids (−1 padding), previous
        (B, Q_prev, D'), drop_cond (B,) bool: True uses ∅ for the caption. Returns ε (B, Q, D')."""
        b = z.shape[0]
        if z.shape[1] != self.latent_tokens:
            raise ValueError(f"this level has {self.latent_tokens} latent tokens, got z of shape {tuple(z.shape)}")
        if (previous is None) != (self.previous_tokens == 0):
            raise ValueError("pass the previous level's latent exactly when this level has one")
        t = t.expand(b) if t.ndim == 0 else t
        allowed = torch.zeros_like(kinds, dtype=torch.bool)
        for k in self.kinds:
            allowed |= kinds == k
        # Only this level's node kinds enter the transformer: the rest would be masked out anyway, and on the motion
        # level (one node of a caption's ~10-25) carrying them made a training step several times slower.
        order = torch.argsort((~allowed).to(torch.uint8), dim=1, stable=True)[:, : max(int(allowed.sum(1).max()), 1)]
        cond, kinds, allowed = (x.gather(1, order if x.ndim == 2 else order[..., None].expand(-1, -1, x.shape[-1]))
                                for x in (cond, kinds, allowed))  # fmt: skip
        node_tokens = self.node_in(cond) + self.kind_embedding(kinds.clamp(min=0))
        drop = torch.zeros(b, dtype=torch.bool, device=z.device) if drop_cond is None else drop_cond
        allowed = allowed & ~drop[:, None]
        tokens = [self.time(t)[:, None], self.null_token.expand(b, 1, -1), node_tokens]
        # the ∅ token is seen only when the caption is dropped; node tokens only when kept and of this level's kinds
        padding = [torch.zeros(b, 1, dtype=torch.bool, device=z.device), ~drop[:, None], ~allowed]
        if previous is not None:
            tokens.append(self.previous_in(previous) + self.previous_position)
            padding.append(torch.zeros(b, self.previous_tokens, dtype=torch.bool, device=z.device))
        tokens.append(self.latent_in(z) + self.latent_position)
        padding.append(torch.zeros(b, self.latent_tokens, dtype=torch.bool, device=z.device))
        h = self.transformer(torch.cat(tokens, 1), src_key_padding_mask=torch.cat(padding, 1))
        return self.out(self.norm(h[:, -self.latent_tokens :]))


class HierarchicalDenoiser(nn.Module):
    """The graph attention plus the three level denoisers; ``node_embeddings`` runs the graph once per caption."""

    def __init__(self, node_dim: int, latent_dim: int = 256, tokens: dict[str, int] | None = None, **size):
        super().__init__()
        self.tokens = dict(LEVEL_TOKENS if tokens is None else tokens)
        self.graph_attention = SemanticGraphAttention(node_dim)
        kinds = {"motion": (0,), "action": (0, 1), "specific": (0, 1, 2)}
        self.levels = nn.ModuleDict(
            {
                level: LatentDenoiser(
                    self.tokens[level],
                    self.tokens[PREVIOUS[level]] if PREVIOUS[level] else 0,
                    node_dim,
                    latent_dim,
                    kinds=kinds[level],
                    **size,
                )
                for level in LEVELS
            }
        )

    def node_embeddings(self, graphs: GraphBatch) -> tuple[Tensor, Tensor]:
        """(𝒱 (B, K, D), ẽ (B, K, K)) of the padded graphs."""
        return self.graph_attention(graphs.features, graphs.types)

    def forward(self, level: str, z: Tensor, t: Tensor, nodes: Tensor, kinds: Tensor, previous=None, drop_cond=None):
        return self.levels[level](z, t, nodes, kinds, previous, drop_cond)
