"""Procedural part-annotated families, one module per category.

Each module exposes ``generate(rng: numpy.random.Generator) -> ObjectAsset``: it draws the category's shape
parameters (at least five continuous ones and a discrete style or two) and its appearance from ``rng`` and builds
the parts in the category's canonical orientation (conventions §1, §3). Centring and fitting into the canonical cube are
done afterwards by :func:`affnerf.objects.registry.make_object`.
"""
