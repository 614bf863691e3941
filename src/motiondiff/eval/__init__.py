"""Evaluation of generation: the papers' protocol (generate for real clips, evaluator features, replications and
confidence intervals), the official evaluators' inputs, the in-training callback that keeps the best-FID checkpoint,
sample videos for the dashboards and the result tables. The metric arithmetic itself is `motiondiff.metrics`."""
