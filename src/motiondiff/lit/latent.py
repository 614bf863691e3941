"""The LightningModule of GuidedMotion: three frozen motion VAEs, the caption graph attention and three latent
ε-denoisers trained together (L = L_M + L_A + L_S, paper §3.3), sampled level by level with DDIM and
classifier-free guidance, and at the action level with the local actions' energy guidance (``sample``).

Each level's latent is the posterior mean of its own VAE (Q = 2 / 4 / 8 tokens), standardised per token and dim
with statistics of the training set (``set_latent_stats``), so every level diffuses a unit-scale latent; the
local actions' latents c^k live in the same standardised space. Caption graphs (spaCy parse + token features) are
built once per caption (``set_graph_table``), never inside a step.
"""

from __future__ import annotations

import lightning as L
import torch

from motiondiff.diffusion import GaussianDiffusion, ddim_sample, make_betas
from motiondiff.diffusion.dpm_solver import dpmpp_sample
from motiondiff.diffusion.energy_guidance import DEFAULT_RHO, energy_guidance_step, guidance_weights
from motiondiff.diffusion.guidance import classifier_free_guidance
from motiondiff.lit.diffusion import MotionDiffusionModule
from motiondiff.lit.vae import MotionVAEModule
from motiondiff.models.graph import GraphBatch, action_weights, batch_graphs
from motiondiff.models.hierarchical import LEVELS, PREVIOUS, HierarchicalDenoiser
from motiondiff.text.parse import ROLES


def window_keys(batch: dict) -> list[tuple[str, int, int]] | None:
    """(clip id, window start, length) of each batch item, the key of ``latent_cache``; None without them."""
    if not all(k in batch for k in ("id", "start", "length")):
        return None
    return [(i, int(s), int(n)) for i, s, n in zip(batch["id"], batch["start"], batch["length"], strict=True)]


LATENT_SAMPLERS = {"ddim": ddim_sample, "dpmpp": dpmpp_sample}  # the samplers of the latent levels


class HierarchicalLatentModule(L.LightningModule):
    def __init__(
        self,
        vaes: dict[str, dict],
        model: dict,
        diffusion: dict,
        optim: dict,
        node_dim: int,
        text_encoder: dict,
        condition: dict | None = None,
        sampling: dict | None = None,
        dataset: str = "",
    ):
        super().__init__()
        self.save_hyperparameters()
        missing = [level for level in LEVELS if level not in vaes]
        if missing:
            raise ValueError(f"GuidedMotion needs a VAE per level; missing: {', '.join(missing)}")
        self.vaes = torch.nn.ModuleDict({level: MotionVAEModule(**vaes[level]) for level in LEVELS})
        self.vaes.requires_grad_(False)
        tokens = {level: self.vaes[level].tokens for level in LEVELS}
        latent_dim = self.vaes["motion"].vae.latent_dim
        self.denoiser = HierarchicalDenoiser(node_dim, latent_dim, tokens, **model)
        betas = make_betas(diffusion.get("schedule", "scaled_linear"), int(diffusion.get("steps", 1000)),
                           beta_start=float(diffusion.get("beta_start", 8.5e-4)),
                           beta_end=float(diffusion.get("beta_end", 0.012)))  # fmt: skip
        # the paper predicts ε; diffusion.prediction=v (with weighting=snr_v, vvMDM) is the option for small runs, whose
        # ε-denoisers ignore their conditions at high noise (docs/results/guidedmotion/weight_control_levels.md)
        self.diffusion = GaussianDiffusion(betas, prediction=str(diffusion.get("prediction", "eps")),
                                           weighting=diffusion.get("weighting"))  # fmt: skip
        self.cond_drop_prob = float((condition or {}).get("drop_prob", 0.1))
        for level in LEVELS:
            shape = (tokens[level], latent_dim)
            self.register_buffer(f"latent_mean_{level}", torch.zeros(shape))
            self.register_buffer(f"latent_std_{level}", torch.ones(shape))
        self.graph_table: dict[str, tuple] = {}  # caption -> (CaptionGraph, node features); rebuilt at setup
        # (clip id, window start, length) -> {level: standardised latent (Q, D')}. The VAEs are frozen and in eval
        # mode, so a window's latents never change: encoding them once instead of in every step makes training
        # ~10x faster (three transformer encoders over 196 frames cost more than the three small denoisers).
        self.latent_cache: dict[tuple, dict[str, torch.Tensor]] = {}

    # The motion space is the specific level's VAE's (all three are trained on the same features).
    @property
    def decoder(self) -> MotionVAEModule:
        return self.vaes["specific"]

    @property
    def mean(self) -> torch.Tensor:
        return self.decoder.mean

    @property
    def std(self) -> torch.Tensor:
        return self.decoder.std

    @property
    def representation(self):
        return self.decoder.representation

    denormalise = MotionDiffusionModule.denormalise
    joints = MotionDiffusionModule.joints
    configure_optimizers = MotionDiffusionModule.configure_optimizers

    def train(self, mode: bool = True):
        super().train(mode)
        self.vaes.eval()  # frozen: no dropout in the latents the denoisers learn
        return self

    # ---- latents and graphs -----------------------------------------------------------------------------------------
    def latent_stats(self, level: str) -> tuple[torch.Tensor, torch.Tensor]:
        return getattr(self, f"latent_mean_{level}"), getattr(self, f"latent_std_{level}")

    @torch.no_grad()
    def encode(self, level: str, features: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Normalised motion features (B, N, D) -> the level's standardised latent (B, Q, D')."""
        return self.standardise(level, self.vaes[level].encode(features, mask)[0])

    def standardise(self, level: str, latent: torch.Tensor) -> torch.Tensor:
        """A level's posterior mean -> the standardised latent the denoisers work on."""
        mean, std = self.latent_stats(level)
        return (latent - mean) / std

    @torch.no_grad()
    def set_latent_stats(self, batches) -> None:
        """Per token and dim mean/std of each level's posterior means over ``batches`` (the training set). The
        standardised latents of these windows seed ``latent_cache`` (any cached under old statistics are dropped)."""
        batches = list(batches)
        raw = {}
        for level in LEVELS:
            raw[level] = [self.vaes[level].encode(b["motion"].to(self.device), b["mask"].to(self.device))[0]
                          for b in batches]  # fmt: skip
            latents = torch.cat(raw[level])
            getattr(self, f"latent_mean_{level}").copy_(latents.mean(0))
            getattr(self, f"latent_std_{level}").copy_(latents.std(0).clamp_min(1e-4))
        self.latent_cache.clear()
        for i, b in enumerate(batches):
            keys = window_keys(b)
            if keys is not None:
                standardised = {level: self.standardise(level, raw[level][i]) for level in LEVELS}
                for row, key in enumerate(keys):
                    self.latent_cache[key] = {level: standardised[level][row].cpu() for level in LEVELS}

    def batch_latents(self, batch: dict) -> dict[str, torch.Tensor]:
        """Each level's standardised latents of a batch's windows, from ``latent_cache`` when every window is in it;
        batches without window keys (``id``/``start``/``length``) are encoded afresh."""
        keys = window_keys(batch)
        if keys is not None and all(k in self.latent_cache for k in keys):
            return {level: torch.stack([self.latent_cache[k][level] for k in keys]).to(self.device)
                    for level in LEVELS}  # fmt: skip
        latents = {level: self.encode(level, batch["motion"], batch["mask"]) for level in LEVELS}
        if keys is not None:
            for i, k in enumerate(keys):
                self.latent_cache[k] = {level: latents[level][i].detach().cpu() for level in LEVELS}
        return latents

    def set_graph_table(self, table: dict[str, tuple]) -> None:
        """caption -> (CaptionGraph, (nodes, node_dim) features), from ``motiondiff.text.graph_features``."""
        self.graph_table = dict(table)

    def graphs_of(self, texts) -> GraphBatch:
        try:
            pairs = [self.graph_table[t] for t in texts]
        except KeyError as err:
            raise RuntimeError(f"caption {err} has no caption graph: call set_graph_table first") from None
        return batch_graphs([g for g, _ in pairs], [f for _, f in pairs], ROLES).to(self.device)

    # ---- training -----------------------------------------------------------------------------------------------
    def _loss(self, batch: dict, drop_prob: float) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        b = batch["motion"].shape[0]
        latents = self.batch_latents(batch)
        graphs = self.graphs_of(batch["text"])
        nodes, _ = self.denoiser.node_embeddings(graphs)
        drop = torch.rand(b, device=self.device) < drop_prob
        parts = {}
        for level in LEVELS:
            z0 = latents[level]
            t = torch.randint(0, self.diffusion.num_steps, (b,), device=self.device)
            noise = torch.randn_like(z0)
            previous = latents[PREVIOUS[level]] if PREVIOUS[level] else None
            out = self.denoiser(level, self.diffusion.q_sample(z0, t, noise), t, nodes, graphs.kinds, previous, drop)
            parts[level] = self.diffusion.loss(out, z0, noise, t)  # ε: the plain ‖ε̂ − ε‖² mean
        return sum(parts.values()), parts

    def training_step(self, batch: dict, batch_idx: int) -> torch.Tensor:
        loss, parts = self._loss(batch, self.cond_drop_prob)
        b = batch["motion"].shape[0]
        self.log("train/loss", loss, prog_bar=True, batch_size=b)
        self.log_dict({f"train/loss_{k}": v for k, v in parts.items()}, batch_size=b)
        return loss

    def validation_step(self, batch: dict, batch_idx: int) -> None:
        state = torch.get_rng_state()
        torch.manual_seed(batch_idx)  # comparable validation losses between evaluations
        loss, parts = self._loss(batch, 0.0)
        torch.set_rng_state(state)
        b = batch["motion"].shape[0]
        self.log("val/loss", loss, prog_bar=True, batch_size=b, sync_dist=True)
        self.log_dict({f"val/loss_{k}": v for k, v in parts.items()}, batch_size=b, sync_dist=True)

    # ---- sampling -----------------------------------------------------------------------------------------------
    @torch.inference_mode()
    def sample(
        self,
        graphs: GraphBatch,
        lengths: torch.Tensor,
        guidance: float | None = None,
        steps: dict[str, int] | None = None,
        local_latents: torch.Tensor | None = None,
        local_weights: torch.Tensor | None = None,
        rho: float = DEFAULT_RHO,
        generator: torch.Generator | None = None,
        progress: bool = False,
        return_latents: bool = False,
        final_level: str = "specific",
        sampler: str | None = None,
    ):
        """Normalised features (B, max(lengths), D) for the captions in ``graphs``.

        ``local_latents`` (B, A, Q_a, D'): the standardised action-level latents c^k of the local actions, one per
        action node of each graph (in ``graphs.actions`` order; padded actions are ignored), ``local_weights`` (B, A)
        the user's w_k (default 1). Without them the action level samples with no energy guidance.
        ``final_level`` stops the hierarchy early and decodes that level's latent with its own VAE (the paper's
        Tab. 4 ablation: motion level alone, motion + action, all three). ``sampler``: ddim (the paper's) or dpmpp
        (DPM-Solver++(2M) on log-SNR steps, for fewer steps per level); None: the model's ``sampling.sampler``, else
        ddim. The energy guidance steers x_t between steps with either."""
        if final_level not in LEVELS:
            raise ValueError(f"final_level must be one of {', '.join(LEVELS)}, got {final_level!r}")
        self.eval()
        settings = dict(self.hparams.sampling or {})
        sampler = sampler or settings.get("sampler", "ddim")
        if sampler not in LATENT_SAMPLERS:
            raise ValueError(f"sampler must be one of {', '.join(LATENT_SAMPLERS)}, got {sampler!r}")
        scale = float(settings.get("guidance", 7.5) if guidance is None else guidance)
        steps = {**{level: 50 for level in LEVELS}, **dict(settings.get("steps", {})), **dict(steps or {})}
        graphs = graphs.to(self.device)
        b = graphs.features.shape[0]
        if len(lengths) != b:
            raise ValueError(f"{b} captions but {len(lengths)} lengths")
        nodes, attention = self.denoiser.node_embeddings(graphs)
        hook = None
        if local_latents is not None:
            hook = self._energy_hook(graphs, attention, local_latents.to(self.device), local_weights, rho)
        latents = {}
        for level in LEVELS[: LEVELS.index(final_level) + 1]:
            previous = latents[PREVIOUS[level]] if PREVIOUS[level] else None
            shape = (b, self.vaes[level].tokens, self.vaes[level].vae.latent_dim)
            fn = self._model_fn(level, nodes, graphs.kinds, previous, scale, hook)
            xt_hook = hook.step if (hook is not None and level == "action") else None
            latents[level] = LATENT_SAMPLERS[sampler](self.diffusion, fn, shape, steps=int(steps[level]),
                                                      generator=generator, xt_hook=xt_hook, progress=progress,
                                                      device=self.device)  # fmt: skip
        n = int(lengths.max())
        mask = torch.arange(n, device=self.device)[None] < lengths.to(self.device)[:, None]
        mean, std = self.latent_stats(final_level)
        features = self.vaes[final_level].decode(latents[final_level] * std + mean, mask)
        return (features, latents) if return_latents else features

    def _model_fn(self, level, nodes, kinds, previous, scale, hook):
        def fn(z, t):
            if hook is not None and level == "action":
                hook.z_t = z  # the energy gradient is taken at z_t, the step's input
            return classifier_free_guidance(self.denoiser.levels[level], z, t, nodes, scale, kinds=kinds,
                                            previous=previous)  # fmt: skip

        return fn

    def _energy_hook(self, graphs, attention, local_latents, local_weights, rho):
        actions = graphs.actions
        b, a = actions.shape
        if local_latents.shape[:2] != (b, a):
            raise ValueError(f"local latents must be (B={b}, A={a}, Q, D'), one per action node; got "
                             f"{tuple(local_latents.shape)}")  # fmt: skip
        e = torch.stack([action_weights(attention[i], 0, actions[i].clamp(min=0).tolist()) for i in range(b)])
        w = torch.ones(b, a) if local_weights is None else torch.as_tensor(local_weights, dtype=torch.float32)
        if w.shape != (b, a):
            raise ValueError(f"local weights must be (B={b}, A={a}), got {tuple(w.shape)}")
        lam = torch.stack([guidance_weights(e[i], w[i], rho) for i in range(b)]) * (actions >= 0)
        return _EnergyHook(local_latents, lam.to(self.device))


class _EnergyHook:
    """The x_t hook of the action level: z_{t−1} ← z_{t−1} − Σ_k λ^k ∇_{z_t} ‖z_t − c^k‖² (``energy_guidance``)."""

    def __init__(self, references: torch.Tensor, weights: torch.Tensor):
        self.references, self.weights, self.z_t = references, weights, None

    def step(self, z_prev: torch.Tensor, t_prev: int) -> torch.Tensor:
        return energy_guidance_step(z_prev, self.z_t, self.references, self.weights)
