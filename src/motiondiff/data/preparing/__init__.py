"""Preparing a dataset from raw motion capture: processing, generated captions, splits, writing."""
