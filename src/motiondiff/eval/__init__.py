"""Evaluation: behaviour checks of generated motion (and, later, evaluators and metrics)."""
