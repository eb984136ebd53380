"""Image distances d(X_re, X_sy) in the feature space of each detector family.

``get_distance(name, **kwargs)`` builds one by name; ``list_distances()`` lists
them: ``eucl`` (pixel L2, eq. 2), ``hog`` (L2 between HOG vectors, eq. 3),
``wl_random`` / ``wl_learned`` (weak learners, eq. 5), ``cnn`` (CNN
activations of layers 2..N, eq. 6). See :mod:`synthaug.distances.registry`.

Example:
    >>> import torch
    >>> from synthaug.distances import get_distance
    >>> d = get_distance("hog")
    >>> x = torch.rand(1, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    >>> d(x, x.expand(3, -1, -1, -1)).tolist()
    [0.0, 0.0, 0.0]
"""

from __future__ import annotations

from synthaug.distances.registry import (
    Distance,
    DistanceEntry,
    check_pair,
    describe_distances,
    example_distance,
    get_distance,
    get_entry,
    list_distances,
    register_distance,
    safe_norm,
    unregister_distance,
)

__all__ = [
    "Distance",
    "DistanceEntry",
    "check_pair",
    "describe_distances",
    "example_distance",
    "get_distance",
    "get_entry",
    "list_distances",
    "register_distance",
    "safe_norm",
    "unregister_distance",
]
