"""The AFF-NeRF model: two image encoders give a shape and an appearance code; a conditional radiance field
renders colour, depth and affordance from them (conventions §4, the paper's section 3.1)."""
