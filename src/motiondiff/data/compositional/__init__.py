"""Compositional multi-action data joined from real single-action clips, with generated captions."""
