"""GuidedMotion's graph attention and energy guidance against the paper's formulas, computed by hand."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.diffusion.energy_guidance import energy, energy_guidance_step, guidance_weights
from motiondiff.models.graph import NO_EDGE, SemanticGraphAttention, action_weights, edge_type_matrix
from motiondiff.text.parse import ROLES

ROLE = {r: k for k, r in enumerate(ROLES)}


def leaky(x, slope=0.2):
    return x if x > 0 else slope * x


def elu(x):
    return np.where(x > 0, x, np.exp(x) - 1)


def small_graph():
    """motion 0 -- action 1 (ARGM-MA), motion 0 -- action 2 (ARGM-MA), action 1 -- specific 3 (ARGM-DIR)."""
    edges = [(0, 1, "ARGM-MA"), (0, 2, "ARGM-MA"), (1, 3, "ARGM-DIR")]
    return edge_type_matrix(4, edges, ROLES)


def test_edge_type_matrix_is_symmetric_and_checked():
    types = small_graph()
    assert types[0, 1] == types[1, 0] == ROLE["ARGM-MA"] and types[3, 1] == ROLE["ARGM-DIR"]
    assert types[0, 3] == NO_EDGE and (types.diagonal() == NO_EDGE).all()
    with pytest.raises(ValueError, match="not one of the 12 roles"):
        edge_type_matrix(2, [(0, 1, "ARG9")], ROLES)
    with pytest.raises(ValueError, match="does not join two different nodes"):
        edge_type_matrix(2, [(0, 2, "ARG0")], ROLES)


def test_attention_and_node_embeddings_match_the_formulas_by_hand():
    torch.manual_seed(0)
    d = 3
    layer = SemanticGraphAttention(d)
    v = torch.randn(4, d)
    types = small_graph()
    out, att = layer(v, types)

    W = layer.W.weight.detach().numpy().astype(np.float64)
    M = layer.M.detach().numpy().astype(np.float64)
    M_r = layer.M_r.detach().numpy().astype(np.float64)
    vv = v.numpy().astype(np.float64)
    h = vv @ W.T  # h = W v
    expected_att = np.zeros((4, 4))
    for i in range(4):
        nbrs = [j for j in range(4) if types[i, j] >= 0]
        e = []
        for j in nbrs:
            ht = np.concatenate([h[i], h[j]])  # h~_ij = [h_i, h_j]
            R = np.zeros(len(ROLES))
            R[types[i, j]] = 1.0  # one-hot edge type
            e.append(leaky(M @ ht) + leaky(R @ (M_r.T @ ht)))
        e = np.exp(np.array(e) - max(e))
        expected_att[i, nbrs] = e / e.sum()
    expected = elu(expected_att @ h) + vv
    np.testing.assert_allclose(att.detach().numpy(), expected_att, atol=1e-6)
    np.testing.assert_allclose(out.detach().numpy(), expected, atol=1e-5)
    assert att[0, [1, 2]].sum().item() == pytest.approx(1.0)  # the motion node spreads its attention over actions
    np.testing.assert_allclose(action_weights(att, 0, [1, 2]).detach().numpy(), expected_att[0, [1, 2]], atol=1e-6)


def test_edge_type_changes_the_score_and_isolated_nodes_keep_their_features():
    torch.manual_seed(1)
    layer = SemanticGraphAttention(4)
    v = torch.randn(3, 4)
    a = edge_type_matrix(3, [(0, 1, "ARG0"), (0, 2, "ARG0")], ROLES)
    b = edge_type_matrix(3, [(0, 1, "ARG0"), (0, 2, "ARGM-TMP")], ROLES)
    assert not torch.allclose(layer(v, a)[1][0], layer(v, b)[1][0])
    isolated = edge_type_matrix(3, [(0, 1, "ARG0")], ROLES)
    out, att = layer(v, isolated)
    assert torch.equal(att[2], torch.zeros(3)) and torch.allclose(out[2], v[2])  # ELU(0) + v


def test_batched_padded_graphs_equal_single_graphs():
    torch.manual_seed(2)
    layer = SemanticGraphAttention(5)
    v = torch.randn(2, 4, 5)
    types = torch.stack([small_graph(), edge_type_matrix(4, [(0, 1, "ARGM-MA")], ROLES)])
    out, att = layer(v, types)
    for b in range(2):
        single_out, single_att = layer(v[b], types[b])
        assert torch.allclose(out[b], single_out, atol=1e-6) and torch.allclose(att[b], single_att, atol=1e-6)


def test_guidance_step_is_the_analytic_gradient_of_the_energy():
    gen = torch.Generator().manual_seed(0)
    z_t = torch.randn(2, 4, 8, generator=gen)  # (B, Q, D') latents
    z_prev = torch.randn(2, 4, 8, generator=gen)
    refs = torch.randn(2, 3, 4, 8, generator=gen)  # K = 3 local actions
    lam = torch.tensor([[0.01, 0.02, 0.0], [0.005, 0.0, 0.03]])
    stepped = energy_guidance_step(z_prev, z_t, refs, lam)

    z = z_t.clone().requires_grad_(True)
    total = sum((lam[:, k] * energy(z, refs[:, k])).sum() for k in range(3))
    (grad,) = torch.autograd.grad(total, z)
    torch.testing.assert_close(stepped, z_prev - grad)
    # by hand for one element: 2 · sum_k lambda_k (z - c_k)
    by_hand = z_prev[1, 2, 5] - 2 * sum(lam[1, k] * (z_t[1, 2, 5] - refs[1, k, 2, 5]) for k in range(3))
    assert stepped[1, 2, 5].item() == pytest.approx(by_hand.item(), abs=1e-6)


def test_guidance_weights_scale_with_attention_and_user_weight():
    att = torch.tensor([0.25, 0.75])
    lam = guidance_weights(att, [0.0, 2.0], rho=0.01)
    torch.testing.assert_close(lam, torch.tensor([0.0, 0.015]))
    torch.testing.assert_close(guidance_weights(att), 0.01 * att)
    with pytest.raises(ValueError, match="one per action"):
        guidance_weights(att, [1.0, 1.0, 1.0])
    # a larger weight moves the latent closer to that action's reference
    z = torch.zeros(1, 2, 3)
    ref = torch.ones(1, 2, 2, 3)
    ref[:, 1] = -1.0
    near = [energy(energy_guidance_step(z, z, ref, guidance_weights(att, [w, 1.0])[None]), ref[:, 0]).item()
            for w in (0.0, 1.0, 2.0)]  # fmt: skip
    assert near[0] > near[1] > near[2]
