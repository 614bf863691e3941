"""Motion-generation metrics: the plain functions against hand-computed values, the Metrics against the functions,
and one DDP run (2 CPU processes, gloo) whose synced result must equal the single-process one."""

from __future__ import annotations

import os
import socket

import numpy as np
import pytest
import scipy.linalg
import torch
import torch.distributed as dist
import torch.multiprocessing as mp

from motiondiff.metrics import (
    FID,
    KID,
    ActionAccuracy,
    Diversity,
    MMDist,
    MultiModality,
    PrecisionRecall,
    RPrecision,
    Smoothness,
    diversity,
    frechet_distance,
    gaussian_statistics,
    kid,
    knn_precision_recall,
    mm_dist,
    mmd2_unbiased,
    multimodality,
    polynomial_kernel,
    r_precision,
    r_precision_counts,
    smoothness,
)


def _t(x) -> torch.Tensor:
    return torch.as_tensor(np.asarray(x), dtype=torch.float64)


# ---- FID ----------------------------------------------------------------------------------------------------------
def test_frechet_distance_of_diagonal_gaussians_matches_the_closed_form():
    mu1, mu2 = np.array([0.0, 1.0, -2.0]), np.array([1.0, 1.0, 0.5])
    s1, s2 = np.array([1.0, 4.0, 0.25]), np.array([9.0, 1.0, 0.25])
    # |Δμ|² = 1 + 0 + 6.25; Σ (s1 + s2 - 2√(s1 s2)) = (1 + 9 - 6) + (4 + 1 - 4) + 0 = 5
    assert frechet_distance(mu1, np.diag(s1), mu2, np.diag(s2)) == pytest.approx(7.25 + 5.0, abs=1e-10)


def test_frechet_distance_of_commuting_full_covariances():
    # Σ1 = Q diag(a) Qᵀ and Σ2 = Q diag(b) Qᵀ share eigenvectors, so (Σ1 Σ2)^½ = Q diag(√(ab)) Qᵀ
    q, _ = np.linalg.qr(np.random.default_rng(0).standard_normal((4, 4)))
    a, b = np.array([1.0, 2.0, 3.0, 4.0]), np.array([4.0, 0.5, 3.0, 1.0])
    mu1, mu2 = np.array([1.0, 2.0, 3.0, 4.0]), np.array([0.0, 2.0, 5.0, 4.0])
    expected = 1.0 + 4.0 + np.sum(a + b - 2.0 * np.sqrt(a * b))
    got = frechet_distance(mu1, q @ np.diag(a) @ q.T, mu2, q @ np.diag(b) @ q.T)
    assert got == pytest.approx(expected, abs=1e-9)


def test_fid_of_identical_feature_sets_is_zero():
    feats = torch.randn(500, 16, generator=torch.Generator().manual_seed(0))
    metric = FID()
    metric.update(feats, real=True)
    metric.update(feats, real=False)
    assert abs(float(metric.compute())) < 1e-6


def test_frechet_distance_retries_with_a_ridge_when_sqrtm_fails(monkeypatch):
    real_sqrtm, seen = scipy.linalg.sqrtm, []

    def flaky_sqrtm(a):
        seen.append(a)
        return np.full_like(a, np.inf) if len(seen) == 1 else real_sqrtm(a)

    monkeypatch.setattr(scipy.linalg, "sqrtm", flaky_sqrtm)
    s1, s2 = np.diag([1.0, 4.0]), np.diag([4.0, 1.0])
    got = frechet_distance(np.zeros(2), s1, np.zeros(2), s2, eps=1e-6)
    assert len(seen) == 2 and np.allclose(seen[1], (s1 + 1e-6 * np.eye(2)) @ (s2 + 1e-6 * np.eye(2)), atol=0)
    assert got == pytest.approx((1 + 4 - 2 * 2) + (4 + 1 - 2 * 2), abs=1e-5)


def test_fid_metric_on_samples_of_two_gaussians_is_close_to_the_analytic_value():
    mu1, mu2 = np.array([0.0, 0.0, 0.0, 0.0]), np.array([1.0, -0.5, 0.0, 2.0])
    var1, var2 = np.array([1.0, 2.0, 0.5, 1.0]), np.array([2.0, 1.0, 0.5, 3.0])
    analytic = frechet_distance(mu1, np.diag(var1), mu2, np.diag(var2))
    n = 20000
    rng = np.random.default_rng(0)
    real = mu1 + np.sqrt(var1) * rng.standard_normal((n, 4))
    fake = mu2 + np.sqrt(var2) * rng.standard_normal((n, 4))
    metric = FID()
    for chunk in np.array_split(np.arange(n), 7):  # several updates, as in an evaluation loop
        metric.update(_t(real[chunk]), real=True)
        metric.update(_t(fake[chunk]), real=False)
    # the estimate's spread is dominated by |Δμ̂|²: sd ≈ 2 √(Δμᵀ(Σ1 + Σ2)Δμ / n) = 2 √(19.75 / 20000) ≈ 0.063,
    # the covariance terms add less and the bias is O(D/n); 0.3 is ~5 sd
    assert float(metric.compute()) == pytest.approx(analytic, abs=0.3)
    assert analytic == pytest.approx(5.25 + (3 - 2 * np.sqrt(2)) * 2 + 4 - 2 * np.sqrt(3), abs=1e-12)


def test_fid_needs_two_samples_per_set():
    metric = FID()
    metric.update(torch.randn(1, 3), real=True)
    metric.update(torch.randn(5, 3), real=False)
    with pytest.raises(ValueError, match="at least 2 real samples, got 1"):
        metric.compute()
    with pytest.raises(ValueError, match="at least 2 samples, got 1"):
        gaussian_statistics(np.ones((1, 3)))
    with pytest.raises(ValueError, match="no samples"):
        only_real = FID()
        only_real.update(torch.randn(5, 3), real=True)
        only_real.compute()
    assert gaussian_statistics(np.eye(3))[1].shape == (3, 3)


# ---- R-Precision and MM Dist ------------------------------------------------------------------------------------
def test_r_precision_is_one_when_texts_equal_their_motions():
    emb = torch.randn(64, 8, generator=torch.Generator().manual_seed(1))
    metric = RPrecision(top_k=3, pool_size=32)
    metric.update(emb, emb.clone())
    assert {k: float(v) for k, v in metric.compute().items()} == {"top1": 1.0, "top2": 1.0, "top3": 1.0}


def test_r_precision_hand_built_ranks():
    text = np.array([[0.0], [1.0], [2.0], [3.0]])
    # per motion, texts by distance: m0=0.1 -> t0 first (rank 0); m1=2.2 -> t2, t3, t1 (rank 2);
    # m2=1.4 -> t1, t2 (rank 1); m3=10 -> t3 first (rank 0)
    motion = np.array([[0.1], [2.2], [1.4], [10.0]])
    # the official direction ranks motions per text: t0=0 -> m0 (rank 0); t1=1 -> m2, m0, m1 (rank 2);
    # t2=2 -> m1, m2 (rank 1); t3=3 -> m1, m2, m0, m3 (rank 3)
    assert r_precision_counts(text, motion, top_k=3).tolist() == [1, 2, 3]
    assert r_precision(text, motion, top_k=3, pool_size=4) == {"top1": 0.25, "top2": 0.5, "top3": 0.75}
    # ranking texts per motion (the transposed matrix, the papers' wording) gives other numbers here
    assert r_precision_counts(motion, text, top_k=3).tolist() == [2, 3, 4]


def test_r_precision_breaks_ties_by_row_order():
    # both motions are 1 from both texts: the stable sort puts t0 first for both, so only m0 is a top-1 hit
    assert r_precision_counts(np.array([[0.0], [2.0]]), np.array([[1.0], [1.0]]), top_k=2).tolist() == [1, 2]


def test_r_precision_pools_drop_a_trailing_partial_pool():
    rng = np.random.default_rng(2)
    text = rng.standard_normal((70, 6))
    motion = text + 0.8 * rng.standard_normal((70, 6))
    expected = r_precision_counts(text[:32], motion[:32]) + r_precision_counts(text[32:64], motion[32:64])
    got = r_precision(text, motion, top_k=3, pool_size=32)
    assert [got[f"top{k}"] for k in (1, 2, 3)] == pytest.approx((expected / 64).tolist(), abs=1e-15)
    assert 0 < got["top1"] < 1  # not a trivial case
    scrambled = motion.copy()
    scrambled[64:] = rng.standard_normal((6, 6)) * 100  # the 6 trailing pairs are not used
    assert r_precision(text, scrambled, pool_size=32) == got

    metric = RPrecision(pool_size=32)
    for sl in (slice(0, 5), slice(5, 40), slice(40, 70)):  # pools cross update boundaries: order is what counts
        metric.update(_t(text[sl]), _t(motion[sl]))
    assert {k: float(v) for k, v in metric.compute().items()} == pytest.approx(got, abs=1e-6)


def test_r_precision_with_fewer_pairs_than_a_pool_uses_one_pool_of_all():
    rng = np.random.default_rng(3)
    text = rng.standard_normal((31, 6))
    motion = text + 0.8 * rng.standard_normal((31, 6))
    got = r_precision(text, motion, top_k=2, pool_size=32)
    assert list(got) == ["top1", "top2"]
    assert [got["top1"], got["top2"]] == pytest.approx((r_precision_counts(text, motion, 2) / 31).tolist())
    with pytest.raises(ValueError, match="at least 2 samples"):
        r_precision(text[:1], motion[:1])


def test_mm_dist_hand_case():
    text, motion = np.array([[0.0, 0.0], [1.0, 1.0]]), np.array([[3.0, 4.0], [1.0, 2.0]])  # distances 5 and 1
    assert mm_dist(text, motion) == 3.0
    metric = MMDist()
    metric.update(_t(text[:1]), _t(motion[:1]))
    metric.update(_t(text[1:]), _t(motion[1:]))
    assert float(metric.compute()) == pytest.approx(3.0)
    with pytest.raises(ValueError, match="pair row by row"):
        metric.update(torch.zeros(2, 2), torch.zeros(3, 2))


# ---- Diversity and MultiModality --------------------------------------------------------------------------------
def test_diversity_follows_the_protocol_draws():
    feats = np.random.default_rng(4).standard_normal((50, 5))
    rng = np.random.default_rng(7)
    first, second = rng.choice(50, 30, replace=False), rng.choice(50, 30, replace=False)
    loop = np.mean([np.sqrt(np.sum((feats[i] - feats[j]) ** 2)) for i, j in zip(first, second, strict=True)])
    assert diversity(feats, 30, np.random.default_rng(7)) == pytest.approx(loop, abs=1e-12)
    assert diversity(feats, 30, 7) == diversity(feats, 30, np.random.default_rng(7))  # a seed or a generator

    metric = Diversity(num_pairs=30, seed=7)
    metric.update(_t(feats[:20]))
    metric.update(_t(feats[20:]))
    assert float(metric.compute()) == pytest.approx(loop, abs=1e-12)
    assert float(metric.compute()) == float(metric.compute())  # seeded: deterministic


def test_diversity_of_a_simplex_counts_only_pairs_of_distinct_samples():
    # N one-hot vectors: every two distinct ones are √2 apart, so diversity = √2 (1 - share of pairs (i, i));
    # with S = N both draws are permutations, whose coincidences number ~Poisson(1)
    n = 400
    rng = np.random.default_rng(5)
    first, second = rng.choice(n, n, replace=False), rng.choice(n, n, replace=False)
    expected = np.sqrt(2.0) * np.mean(first != second)
    assert diversity(np.eye(n), 1000, 5) == pytest.approx(expected, abs=1e-12)  # num_pairs > N: S = N
    assert diversity(np.ones((10, 3)), 5, 0) == 0.0


def test_multimodality_of_identical_repeats_is_zero_and_offsets_do_not_matter():
    rng = np.random.default_rng(6)
    same = np.repeat(rng.standard_normal((8, 1, 4)), 12, axis=1)
    assert multimodality(same, 10, 0) == 0.0
    feats = rng.standard_normal((8, 12, 4))
    shifted = feats + 100.0 * rng.standard_normal((8, 1, 4))  # one offset per condition
    assert multimodality(shifted, 10, 3) == pytest.approx(multimodality(feats, 10, 3), abs=1e-9)
    assert multimodality(2.5 * feats, 10, 3) == pytest.approx(2.5 * multimodality(feats, 10, 3), abs=1e-12)


def test_multimodality_draws_per_condition_and_matches_a_loop():
    feats = np.random.default_rng(8).standard_normal((5, 12, 3))
    rng = np.random.default_rng(9)
    dists = []
    for c in range(5):
        first, second = rng.choice(12, 10, replace=False), rng.choice(12, 10, replace=False)
        dists += [np.linalg.norm(feats[c, i] - feats[c, j]) for i, j in zip(first, second, strict=True)]
    assert multimodality(feats, 10, 9) == pytest.approx(np.mean(dists), abs=1e-12)

    metric = MultiModality(num_pairs=10, seed=9)
    metric.update(_t(feats[:2]))
    metric.update(_t(feats[2:]))
    assert float(metric.compute()) == pytest.approx(np.mean(dists), abs=1e-12)


def test_multimodality_of_a_simplex_of_repeats_is_its_expected_value():
    # repeats are one-hot (√2 apart when distinct); first[i] and second[i] coincide with probability 1/R, so
    # E = √2 (1 - 1/R) = √2 · 0.9; over 2000 x 10 pairs the share of coincidences has sd √(0.09 / 20000) ≈ 0.002
    feats = np.broadcast_to(np.eye(10), (2000, 10, 10))
    assert multimodality(feats, 10, 0) == pytest.approx(np.sqrt(2.0) * 0.9, abs=0.01 * np.sqrt(2.0))


def test_multimodality_needs_enough_repeats():
    with pytest.raises(ValueError, match="num_pairs=10"):
        multimodality(np.zeros((3, 9, 2)), 10, 0)
    with pytest.raises(ValueError, match="num_pairs=10"):
        MultiModality(num_pairs=10).update(torch.zeros(3, 9, 2))


# ---- action accuracy --------------------------------------------------------------------------------------------
def test_action_accuracy_hand_case():
    logits = torch.tensor([[2.0, 0.1, 0.0], [0.0, 3.0, 1.0], [0.5, 0.2, 0.1], [0.0, 0.0, 9.0]])
    target = torch.tensor([0, 1, 2, 2])  # the third sample is predicted 0: 3 of 4 right
    metric = ActionAccuracy(num_classes=3)
    metric.update(logits[:2], target[:2])
    metric.update(logits[2:], target[2:])
    assert float(metric.compute()) == pytest.approx(0.75)
    labels = ActionAccuracy(num_classes=3)
    labels.update(torch.tensor([0, 1, 1, 2, 0]), torch.tensor([0, 1, 2, 2, 1]))
    assert float(labels.compute()) == pytest.approx(0.6)
    assert ActionAccuracy.higher_is_better and not ActionAccuracy.full_state_update


# ---- KID ----------------------------------------------------------------------------------------------------------
def test_mmd2_unbiased_matches_a_double_loop():
    rng = np.random.default_rng(10)
    x, y = rng.standard_normal((5, 3)), rng.standard_normal((4, 3)) + 0.3
    k = lambda a, b: (a @ b / 3 + 1.0) ** 3  # noqa: E731
    within_x = sum(k(x[i], x[j]) for i in range(5) for j in range(5) if i != j) / (5 * 4)
    within_y = sum(k(y[i], y[j]) for i in range(4) for j in range(4) if i != j) / (4 * 3)
    across = sum(k(x[i], y[j]) for i in range(5) for j in range(4)) / (5 * 4)
    assert mmd2_unbiased(x, y, polynomial_kernel) == pytest.approx(within_x + within_y - 2 * across, abs=1e-12)


def test_kid_of_identical_sets_is_near_zero_and_of_shifted_sets_clearly_positive():
    rng = np.random.default_rng(11)
    x = rng.standard_normal((1000, 16))
    same = kid(x, x, num_subsets=10, subset_size=300)
    shifted = kid(x, x + 0.5, num_subsets=10, subset_size=300)
    # random subsets of one set share ~300²/1000 = 90 samples, and each shared one puts its k(x, x) ≈ 9 (vs
    # E k(x, y) ≈ 1.2) into the cross term only: the estimate sits near -2 · 90 · 7.8 / 300² ≈ -0.016, not at 0
    assert abs(same["mean"]) < 0.03
    assert shifted["mean"] > 0.5 and shifted["mean"] > 10 * shifted["std"]
    # subsets as large as the sets are whole permutations: every subset gives the same, closed-form value
    full = kid(x[:200], x[:200], num_subsets=3, subset_size=1000)
    gram = polynomial_kernel(x[:200], x[:200])
    m = 200
    closed = 2 * ((gram.sum() - np.trace(gram)) / (m * (m - 1)) - gram.sum() / m**2)
    assert full["mean"] == pytest.approx(closed, abs=1e-12) and full["std"] < 1e-12


def test_kid_metric_equals_the_function():
    rng = np.random.default_rng(12)
    real, fake = rng.standard_normal((120, 6)), rng.standard_normal((90, 6)) + 0.2
    metric = KID(num_subsets=10, subset_size=50, seed=3)
    metric.update(_t(real), real=True)
    metric.update(_t(fake[:40]), real=False)
    metric.update(_t(fake[40:]), real=False)
    got = {k: float(v) for k, v in metric.compute().items()}
    assert got == pytest.approx(kid(real, fake, num_subsets=10, subset_size=50, rng=3), abs=1e-12)


# ---- precision and recall ---------------------------------------------------------------------------------------
def test_precision_recall_of_identical_and_of_far_away_sets():
    x = np.random.default_rng(13).standard_normal((200, 8))
    assert knn_precision_recall(x, x, k=3) == {"precision": 1.0, "recall": 1.0}
    assert knn_precision_recall(x, x + 1000.0, k=3) == {"precision": 0.0, "recall": 0.0}


def test_precision_recall_hand_built_1d_case():
    real = np.array([[0.0], [1.0], [2.0], [3.0]])  # k=1 radii: 1, 1, 1, 1
    fake = np.array([[0.25], [0.5], [5.4], [9.0]])  # k=1 radii: 0.25, 0.25, 3.6, 3.6
    # precision: 0.25 and 0.5 lie in real balls; 5.4 (2.4 from 3) and 9 do not -> 2/4
    # recall: 0 is exactly 0.25 from 0.25 (the ball is closed: inside), 2 and 3 lie within 3.6 of 5.4,
    # 1 is 0.5 from 0.5 and 4.4 from 5.4 -> 3/4
    assert knn_precision_recall(real, fake, k=1) == {"precision": 0.5, "recall": 0.75}
    metric = PrecisionRecall(k=1)
    metric.update(_t(real), real=True)
    metric.update(_t(fake), real=False)
    assert {k: float(v) for k, v in metric.compute().items()} == {"precision": 0.5, "recall": 0.75}
    with pytest.raises(ValueError, match="at least 4 samples"):
        knn_precision_recall(real, fake[:3], k=3)


# ---- smoothness ---------------------------------------------------------------------------------------------------
def test_smoothness_of_motion_without_acceleration_is_one():
    t = np.arange(20.0)[:, None]
    assert smoothness(np.full((20, 3), 4.2)) == 1.0
    assert smoothness(np.hstack([3.0 * t - 7.0, -2.0 * t, 0 * t])) == 1.0


def test_smoothness_of_constant_acceleration():
    t = np.arange(15.0)[:, None]
    # x = a t² / 2 has second difference a at every frame: feature 0 has a = 0.5, feature 1 has a = -2
    motion = np.hstack([0.25 * t**2, -(t**2)])
    assert smoothness(motion, alpha=2.0) == pytest.approx((np.exp(-1.0) + np.exp(-4.0)) / 2, abs=1e-15)


def test_smoothness_metric_honours_lengths():
    rng = np.random.default_rng(14)
    motion = rng.standard_normal((3, 30, 4))
    lengths = torch.tensor([30, 12, 3])
    padded = motion.copy()
    padded[1, 12:] = 1e6  # padding after each clip's length must not count
    padded[2, 3:] = -1e6
    metric = Smoothness(alpha=0.5)
    metric.update(_t(padded), lengths)
    expected = np.mean([smoothness(motion[i, :n], 0.5) for i, n in enumerate([30, 12, 3])])
    assert float(metric.compute()) == pytest.approx(expected, abs=1e-12)
    with pytest.raises(ValueError, match="clip 1 has length 2"):
        metric.update(_t(motion[:2]), torch.tensor([30, 2]))
    with pytest.raises(ValueError, match="at least 3 frames"):
        smoothness(motion[0, :2])


def test_metric_directions():
    assert FID.higher_is_better is False and KID.higher_is_better is False and MMDist.higher_is_better is False
    assert RPrecision.higher_is_better and PrecisionRecall.higher_is_better and Smoothness.higher_is_better
    assert Diversity.higher_is_better is None and MultiModality.higher_is_better is None
    for cls in (FID, KID, MMDist, RPrecision, PrecisionRecall, Smoothness, Diversity, MultiModality):
        assert cls.full_state_update is False


# ---- DDP sync -----------------------------------------------------------------------------------------------------
_SPLIT = 37  # rank 0 gets the first 37 of 100 samples, rank 1 the rest: uneven, to exercise padded gathers


def _sync_data() -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(15)
    return {
        "real": torch.randn(100, 6, generator=g, dtype=torch.float64),
        "fake": torch.randn(100, 6, generator=g, dtype=torch.float64) + 0.3,
        "motion": torch.randn(100, 25, 4, generator=g, dtype=torch.float64),
        "lengths": torch.randint(3, 26, (100,), generator=g),
    }


def _run_metrics(parts: list[slice]) -> dict[str, float]:
    data = _sync_data()
    fid, smooth, div, rprec = FID(), Smoothness(alpha=0.7), Diversity(num_pairs=60, seed=1), RPrecision(pool_size=16)
    for sl in parts:
        fid.update(data["real"][sl], real=True)
        fid.update(data["fake"][sl], real=False)
        smooth.update(data["motion"][sl], data["lengths"][sl])
        div.update(data["fake"][sl])
        rprec.update(data["real"][sl], data["fake"][sl])
    out = {"fid": fid.compute(), "smoothness": smooth.compute(), "diversity": div.compute()}
    out |= {f"r_precision_{k}": v for k, v in rprec.compute().items()}
    return {k: float(v) for k, v in out.items()}


def _sync_worker(rank: int, world_size: int, port: int, out_path: str) -> None:
    os.environ["MASTER_ADDR"], os.environ["MASTER_PORT"] = "127.0.0.1", str(port)
    dist.init_process_group("gloo", rank=rank, world_size=world_size)
    try:
        mine = slice(0, _SPLIT) if rank == 0 else slice(_SPLIT, 100)
        results = _run_metrics([slice(mine.start, mine.start + 10), slice(mine.start + 10, mine.stop)])
        if rank == 0:
            torch.save(results, out_path)
    finally:
        dist.destroy_process_group()


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_metrics_sync_across_two_processes(tmp_path):
    out_path = tmp_path / "rank0.pt"
    mp.spawn(_sync_worker, args=(2, _free_port(), str(out_path)), nprocs=2, join=True)
    synced = torch.load(out_path)
    single = _run_metrics([slice(0, 100)])
    assert synced.keys() == single.keys()
    for name, value in single.items():
        assert synced[name] == pytest.approx(value, abs=1e-6), name
