"""Trained checkpoints shipped with the package (see MODEL_CARD.md at the repository root)."""
