"""Research studies that measure the shipped models and write docs/results (one Hydra config each in conf/study)."""
