"""Methods scored by the evaluation protocol: AFF-NeRF and the baselines, each behind the same interface."""
