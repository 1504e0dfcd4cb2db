"""Trained weights shipped with the package (see MODEL_CARD.md at the repository root); code lives in ``affnerf.model``."""
