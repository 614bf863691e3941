"""Command-line entry points (train.py, sample.py at the repo root are thin Hydra wrappers around these)."""
