"""GuidedMotion sampling with local actions (see local_actions.py)."""
