"""Every detector family checks its per-positive training weights the same way (``base.check_weights``)."""

from __future__ import annotations

import math

import pytest
import torch

from synthaug.detectors.adaboost import train_adaboost
from synthaug.detectors.base import check_weights
from synthaug.detectors.hog_dpm import HOGDetector
from synthaug.detectors.lightning_module import PatchDataModule
from synthaug.detectors.toy import toy_patches

BAD = {"length": torch.ones(3), "negative": torch.tensor([1.0, -0.5] + [1.0] * 6),
       "nan": torch.tensor([1.0, math.nan] + [1.0] * 6), "all zero": torch.zeros(8)}


def _hog(pos, neg, w):
    HOGDetector.fit(pos, neg, components=1, mining_rounds=0, positive_weights=w)


def _adaboost(pos, neg, w):
    train_adaboost(pos, neg, n_rounds=2, candidates=10, step=8, seed=0, positive_weights=w)


def _cnn(pos, neg, w):
    PatchDataModule.from_tensors(pos, neg, positive_weights=w, batch_size=4)


@pytest.mark.parametrize("family", [_hog, _adaboost, _cnn], ids=["hog", "adaboost", "cnn"])
@pytest.mark.parametrize("case", list(BAD))
def test_every_family_refuses_the_same_bad_positive_weights(family, case) -> None:
    pos, neg = toy_patches(8, 12, seed=1)
    with pytest.raises(ValueError, match=r"positive_weights must be finite, >= 0, not all 0 and one per positive \(8\)"):
        family(pos, neg, BAD[case])


def test_check_weights_accepts_any_shape_holding_n_only_when_flattening() -> None:
    w = torch.tensor([[1.0, 2.0], [0.0, 3.0]])
    assert check_weights(w, 4, flatten=True).tolist() == [1.0, 2.0, 0.0, 3.0]
    assert check_weights(w, 4, flatten=True).dtype == torch.float64
    with pytest.raises(ValueError, match="one per positive"):
        check_weights(w, 4)
    # per-sample loss weights may all be 0 (a batch of ignored samples); positives' weights may not
    assert check_weights(torch.zeros(2), 2, "weights", "patch", not_all_zero=False).tolist() == [0.0, 0.0]
    with pytest.raises(ValueError, match="weights must be finite, >= 0 and one per patch"):
        check_weights(torch.tensor([-1.0, 0.0]), 2, "weights", "patch", not_all_zero=False)
