"""Fitting Θ per seed: search space, batched objective, optimisers, the per-seed loop."""
