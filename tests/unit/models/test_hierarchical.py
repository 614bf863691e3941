"""GuidedMotion's hierarchical latent denoisers and their LightningModule: each level reads only the node kinds and
the previous latent the paper gives it, ∅ hides the caption, training reaches every part, and sampling with a local
action's energy guidance pulls the action latent towards that action's latent as its weight grows."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.lit.latent import HierarchicalLatentModule
from motiondiff.models.graph import batch_graphs
from motiondiff.models.hierarchical import LatentDenoiser
from motiondiff.text.parse import ROLES, parse_caption

SIZE = dict(d_model=32, num_layers=1, num_heads=2, ff_size=64, dropout=0.0)
VAE = {"latent_dim": 16, "d_model": 32, "num_layers": 1, "num_heads": 2, "ff_size": 64, "dropout": 0.0}
CAPTIONS = [
    "a person walks forward and raises both hands",
    "a person jumps",
    "someone bows, then kicks with the left leg",
]


def _graphs(captions, dim=8, seed=0):
    g = torch.Generator().manual_seed(seed)
    graphs = [parse_caption(c) for c in captions]
    return graphs, [torch.randn(len(x.nodes), dim, generator=g) for x in graphs]


def test_graph_batch_pads_nodes_kinds_edges_and_actions():
    graphs, feats = _graphs(CAPTIONS)
    batch = batch_graphs(graphs, feats, ROLES)
    k = max(len(g.nodes) for g in graphs)
    assert batch.features.shape == (3, k, 8) and batch.types.shape == (3, k, k)
    for i, g in enumerate(graphs):
        n = len(g.nodes)
        assert batch.kinds[i, :n].tolist() == [("motion", "action", "specific").index(x.kind) for x in g.nodes]
        assert (batch.kinds[i, n:] == -1).all() and (batch.types[i, n:] == -1).all()
        ids = g.action_ids()
        assert batch.actions[i, : len(ids)].tolist() == ids and (batch.actions[i, len(ids) :] == -1).all()
    assert batch.actions.shape[1] == max(len(g.action_ids()) for g in graphs) == 2


def test_each_level_reads_only_its_node_kinds_and_null_hides_the_caption():
    torch.manual_seed(0)
    graphs, feats = _graphs(CAPTIONS)
    batch = batch_graphs(graphs, feats, ROLES)
    z, t = torch.randn(3, 4, 16), torch.tensor([5, 500, 900])
    action = LatentDenoiser(4, 2, 8, 16, kinds=(0, 1), **SIZE).eval()
    prev = torch.randn(3, 2, 16)
    ref = action(z, t, batch.features, batch.kinds, prev)
    specific = batch.features.clone()
    specific[batch.kinds == 2] += 5.0  # the action level must not see specific nodes
    assert torch.allclose(action(z, t, specific, batch.kinds, prev), ref, atol=1e-5)
    verbs = batch.features.clone()
    verbs[batch.kinds == 1] += 5.0
    assert not torch.allclose(action(z, t, verbs, batch.kinds, prev), ref, atol=1e-3)
    assert not torch.allclose(action(z, t, batch.features, batch.kinds, prev + 1.0), ref, atol=1e-3)
    drop = torch.ones(3, dtype=torch.bool)
    assert torch.allclose(action(z, t, batch.features, batch.kinds, prev, drop),
                          action(z, t, verbs, batch.kinds, prev, drop), atol=1e-5)  # fmt: skip
    with pytest.raises(ValueError, match="previous level"):
        action(z, t, batch.features, batch.kinds)
    with pytest.raises(ValueError, match="latent tokens"):
        action(z[:, :2], t, batch.features, batch.kinds, prev)
    with pytest.raises(ValueError, match="at least the latent width"):
        LatentDenoiser(4, 2, 8, 64, d_model=32, num_layers=1, num_heads=2)


@pytest.fixture(scope="module")
def setup():
    dm = PreparedDataModule(embedded_data_root(), batch_size=8, max_frames=40, seed=0)
    dm.setup("fit")
    ds = dm.dataset("train")
    common = dict(feature_dim=dm.feature_dim, optim={"lr": 1e-3}, mean=ds.mean.tolist(), std=ds.std.tolist(),
                  max_frames=dm.max_frames, fps=dm.fps, num_joints=dm.num_joints, dataset="bandai_mini",
                  representation=dm.representation_spec())  # fmt: skip
    vaes = {level: {**common, "vae": {**VAE, "tokens": q}, "level": level}
            for level, q in (("motion", 2), ("action", 4), ("specific", 8))}  # fmt: skip
    torch.manual_seed(0)
    module = HierarchicalLatentModule(vaes, SIZE, {"steps": 100}, {"lr": 1e-3}, node_dim=8, text_encoder={})
    batches = [next(iter(dm.train_dataloader()))]
    module.set_latent_stats(batches)
    texts = sorted({t for b in batches for t in b["text"]} | set(CAPTIONS))
    graphs, feats = _graphs(texts)
    module.set_graph_table({t: (g, f) for t, g, f in zip(texts, graphs, feats, strict=True)})
    return module, batches[0]


def test_latents_are_standardised_and_training_reaches_every_part(setup):
    module, batch = setup
    for level, q in (("motion", 2), ("action", 4), ("specific", 8)):
        z = module.encode(level, batch["motion"], batch["mask"])
        assert z.shape == (8, q, 16)
        assert z.mean(0).abs().max() < 1e-4 and (z.std(0) - 1).abs().max() < 1e-3
    module.train()
    loss, parts = module._loss(batch, 0.1)
    assert set(parts) == {"motion", "action", "specific"} and torch.isfinite(loss)
    loss.backward()
    for name in ("graph_attention.W.weight", "levels.motion.out.weight", "levels.action.previous_in.weight",
                 "levels.specific.node_in.weight"):  # fmt: skip
        assert module.denoiser.get_parameter(name).grad.abs().sum() > 0, name
    assert all(p.grad is None for p in module.vaes.parameters())  # the VAEs stay frozen
    assert not module.vaes.training


def test_each_level_learns_the_configured_target_eps_by_default(setup):
    """The paper's ε target by default; diffusion.prediction=v trains the same denoisers on v (vvMDM's weighting)."""
    module, batch = setup
    assert module.diffusion.prediction == "eps" and module.diffusion.weighting == "none"
    v_module = HierarchicalLatentModule(dict(module.hparams.vaes), SIZE, {"steps": 100, "prediction": "v"},
                                        {"lr": 1e-3}, node_dim=8, text_encoder={})  # fmt: skip
    assert v_module.diffusion.prediction == "v" and v_module.diffusion.weighting == "snr_v"
    v_module.load_state_dict(module.state_dict())
    v_module.set_graph_table(module.graph_table)
    z0 = module.batch_latents(batch)["motion"]
    noise, t = torch.randn_like(z0), torch.full((z0.shape[0],), 70)
    for m in (module, v_module):  # the loss is the diffusion's weighted loss on that target
        out = torch.randn_like(z0)
        target = m.diffusion.target(z0, noise, t)
        w = m.diffusion.loss_weight(t)
        expected = (w * ((target - out) ** 2).flatten(1).mean(1)).mean()
        torch.testing.assert_close(m.diffusion.loss(out, z0, noise, t), expected)
    torch.manual_seed(1)
    eps_loss, _ = module._loss(batch, 0.0)
    torch.manual_seed(1)
    v_loss, _ = v_module._loss(batch, 0.0)
    assert torch.isfinite(v_loss) and not torch.isclose(eps_loss, v_loss)


def _window_keys(batch) -> set:
    return {(i, int(s), int(n)) for i, s, n in zip(batch["id"], batch["start"], batch["length"], strict=True)}


def test_cached_latents_equal_fresh_encodings_and_key_on_the_window(setup):
    module, batch = setup
    module.latent_cache.clear()
    first = module.batch_latents(batch)  # encodes and fills the cache
    assert set(module.latent_cache) == _window_keys(batch)
    cached = module.batch_latents({**batch, "motion": torch.zeros_like(batch["motion"])})  # served from the cache
    for level in ("motion", "action", "specific"):
        fresh = module.encode(level, batch["motion"], batch["mask"])
        assert torch.allclose(first[level], fresh) and torch.allclose(cached[level], fresh, atol=1e-6)
    moved = {**batch, "start": batch["start"] + 1, "motion": torch.zeros_like(batch["motion"])}
    other = module.batch_latents(moved)  # another window of the same clips is encoded, not looked up
    assert not torch.allclose(other["action"], first["action"])
    shifted = {**batch, "start": batch["start"] + 2}  # the same clips under other keys
    module.set_latent_stats([shifted])  # new statistics: every latent cached before is dropped, these windows cached
    assert set(module.latent_cache) == _window_keys(shifted)
    restandardised = module.batch_latents(shifted)
    assert torch.allclose(restandardised["action"].mean(0), torch.zeros(4, 16), atol=1e-5)
    module.set_latent_stats([batch])


@pytest.mark.parametrize("sampler", ["ddim", "dpmpp"])
def test_energy_guidance_pulls_the_action_latent_towards_a_local_action(setup, sampler):
    module, _ = setup
    graphs = module.graphs_of([CAPTIONS[0]])
    lengths = torch.tensor([30])
    target = torch.randn(1, 2, 4, 16, generator=torch.Generator().manual_seed(3))  # c^k of the 2 local actions
    distances = []
    for w in (0.0, 1.0, 20.0):
        weights = torch.tensor([[w, 0.0]])
        feats, latents = module.sample(graphs, lengths, steps={"motion": 5, "action": 5, "specific": 5},
                                       local_latents=target, local_weights=weights, rho=0.05, sampler=sampler,
                                       generator=torch.Generator().manual_seed(0), return_latents=True)  # fmt: skip
        distances.append(float((latents["action"] - target[:, 0]).norm()))
        assert feats.shape == (1, 30, module.hparams.vaes["motion"]["feature_dim"]) and torch.isfinite(feats).all()
    assert distances[0] > distances[1] > distances[2]
    if sampler == "dpmpp":
        with pytest.raises(ValueError, match="sampler must be one of ddim, dpmpp"):
            module.sample(graphs, lengths, steps={"motion": 2, "action": 2, "specific": 2}, sampler="ddpm")
        return
    few = {"motion": 2, "action": 2, "specific": 2}
    for level, levels in (("motion", {"motion"}), ("action", {"motion", "action"})):  # Tab. 4's ablation rows
        feats, latents = module.sample(graphs, lengths, steps=few, final_level=level, return_latents=True,
                                       generator=torch.Generator().manual_seed(0))  # fmt: skip
        assert set(latents) == levels and feats.shape == (1, 30, module.hparams.vaes["motion"]["feature_dim"])
        mean, std = module.latent_stats(level)
        mask = torch.ones(1, 30, dtype=torch.bool)
        assert torch.allclose(feats, module.vaes[level].decode(latents[level] * std + mean, mask), atol=1e-5)
    with pytest.raises(ValueError, match="final_level"):
        module.sample(graphs, lengths, steps=few, final_level="verb")
    with pytest.raises(ValueError, match="one per action node"):
        module.sample(graphs, lengths, steps={"motion": 2, "action": 2, "specific": 2}, local_latents=target[:, :1])


def test_guided_pipeline_samples_captions_in_batches_in_the_given_order(setup, monkeypatch):
    """GuidedMotionPipeline.sample_features: one batch is the latent model's own sample, de-normalised and cut to each
    caption's length; smaller batches keep the order and concatenate the level latents; a NaN motion is one error."""
    from motiondiff.lit.generation import NonFiniteOutput
    from motiondiff.pipelines.guided import GuidedMotionPipeline

    module, _ = setup
    graphs, feats = _graphs(CAPTIONS)
    lengths = torch.tensor([20, 12, 16])
    steps = {"motion": 2, "action": 2, "specific": 2}
    pipe = GuidedMotionPipeline(module)
    out = pipe.sample_features(graphs, lengths, node_features=feats, steps=steps,
                               generator=torch.Generator().manual_seed(0))  # fmt: skip
    direct = module.sample(batch_graphs(graphs, feats, ROLES), lengths, steps=steps,
                           generator=torch.Generator().manual_seed(0))  # fmt: skip
    direct = module.denormalise(direct).numpy()
    assert [len(f) for f in out] == [20, 12, 16]
    for i, n in enumerate(lengths.tolist()):
        np.testing.assert_array_equal(out[i], direct[i, :n])
    split, latents = pipe.sample_features(graphs, lengths, node_features=feats, steps=steps, final_level="action",
                                          return_latents=True, batch_size=2)  # fmt: skip
    assert [len(f) for f in split] == [20, 12, 16]
    assert {k: tuple(v.shape) for k, v in latents.items()} == {"motion": (3, 2, 16), "action": (3, 4, 16)}
    nan = torch.full((3, 20, direct.shape[-1]), float("nan"))
    monkeypatch.setattr(module, "sample", lambda *args, **kwargs: (nan, {}))
    with pytest.raises(NonFiniteOutput, match="the GuidedMotion motion holds"):
        pipe.sample_features(graphs, lengths, node_features=feats, steps=steps)


def test_local_actions_from_given_motions_steer_the_sample(setup, monkeypatch):
    from motiondiff.guided.local_actions import LocalActionError, local_actions_for
    from motiondiff.pipelines import guided

    module, batch = setup
    motions = [module.denormalise(batch["motion"][k, :20]) for k in (0, 1)]  # two real clips as the local actions
    graph, local = local_actions_for(module, CAPTIONS[0], motions=motions)
    assert local.texts == ["walks forward", "raises both hands"] and local.sources == ["given", "given"]
    assert local.latents.shape == (2, 4, 16)
    expected = module.encode("action", batch["motion"][:1, :20], torch.ones(1, 20, dtype=torch.bool))
    assert torch.allclose(local.latents[:1], expected, atol=1e-5)

    # node features without loading a text model: the module was built with 8-d random ones
    feats = module.graph_table[CAPTIONS[0]][1]
    monkeypatch.setattr(guided, "_node_features", lambda graphs, encoder: [feats] * len(graphs))
    pipe = guided.GuidedMotionPipeline(module)
    pipe._encoder = "the graph table's features"
    kwargs = dict(steps={"motion": 3, "action": 3, "specific": 3}, rho=0.05)
    out = {w: pipe.sample_features(lengths=torch.tensor([20, 20]), **pipe.caption_copies(graph, local, 2, [w, 0.0]),
                                   generator=torch.Generator().manual_seed(0), **kwargs) for w in (0.0, 5.0)}  # fmt: skip
    assert len(out[0.0]) == 2 and out[0.0][0].shape == (20, module.hparams.vaes["motion"]["feature_dim"])
    assert not np.allclose(out[0.0][0], out[5.0][0])
    with pytest.raises(LocalActionError, match="one per action"):
        pipe.caption_copies(graph, local, 1, [1.0])
    with pytest.raises(LocalActionError, match=">= 0"):
        pipe.caption_copies(graph, local, 1, [1.0, -1.0])
    with pytest.raises(LocalActionError, match="2 action node"):
        local_actions_for(module, CAPTIONS[0], texts=["walks forward"], motions=motions[:1])
