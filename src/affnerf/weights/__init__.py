"""Trained weights shipped with the package (see MODEL_CARD.md at the repository root); the code that uses
them lives in ``affnerf.model`` and ``affnerf.predict``."""
