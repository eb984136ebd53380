"""``ItemParams``: every random choice of one :class:`~synthaug.data.synthetic.SyntheticObjectDataset` item.

Drawing and rendering are two steps, as torchvision's ``make_params`` / ``transform``: the dataset's
``make_params(index)`` draws an item into a frozen :class:`ItemParams` and ``render(params)`` turns it into the
item without drawing, so a params object can be stored, compared, changed (``dataclasses.replace``) and replayed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import torch

__all__ = ["ItemParams", "BACKGROUND_SAMPLING"]


#: how a synthetic item's background is chosen (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s
#: ``background_sampling``): its own seed's (the paper) or another seed's
BACKGROUND_SAMPLING = ("seed", "other")


@dataclass(frozen=True, eq=False)
class ItemParams:
    """Every random choice of one item, drawn by :meth:`SyntheticObjectDataset.make_params`.

    :meth:`SyntheticObjectDataset.render` turns it into the item, drawing nothing: the same params give the
    same bytes (``ds.render(ds.make_params(i)) == ds[i]``), and a changed copy
    (``dataclasses.replace(p, pose={...})``) renders that change alone.

    Attributes:
        index, epoch: the item; its draws are a pure function of (dataset seed, epoch, index).
        real: a real item (index < the number of real items): the user's item, no draws.
        seed_index: the seed whose background (and, with ``capture_sampling="seed"``, capture parameters)
            the item uses; -1 for a real item.
        negative: no object (patch mode: a background patch, label 0; frame mode: the bare frame).
        pose: ``{"alpha", "beta", "gamma", "t_x", "t_y"}`` (radians; t_x, t_y fractions of the crop side), from the
            dataset's pose sampler.
        crop_xy: (x, y) corner of the patch (patch mode) or of the object's crop (frame mode) in the
            seed's background.
        object_px: frame mode: the object's size in pixels (mesh unit length); None in patch mode.
        capture: the capture parameters the dataset's capture sampler drew (``capture_sampling`` ``"kde"`` /
            ``"uniform"``: the density's vector order), or None (the seed's own, ``"seed"``).
        fields: the random effects' noise fields, ``{field name: (1, C, crop, crop) tensor}`` (not JSON: everything
            else is, ``dataclasses.asdict(p)`` without ``fields``).
        variant: which of the dataset's shapes the object has (``shape_variation``: 0 is the mesh itself).
        background_index: the seed whose background the object is composited on, where that is not
            ``seed_index``'s own (``background_sampling="other"``); None: the item's own seed's (the paper).
        framed: whether the dataset's ``object_box`` frames the item's object (drawn with ``object_box_share`` under
            1; True otherwise, and meaningless without an ``object_box``).
    """

    index: int
    epoch: int
    real: bool = False
    seed_index: int = -1
    negative: bool = False
    pose: Mapping[str, float] = field(default_factory=dict)
    crop_xy: tuple[int, int] | None = None
    object_px: float | None = None
    capture: tuple[float, ...] | None = None
    fields: Mapping[str, torch.Tensor] = field(default_factory=dict)
    variant: int = 0
    background_index: int | None = None
    framed: bool = True

    @property
    def background(self) -> int:
        """The seed whose background the item uses: ``background_index``, else its own seed's."""
        return self.seed_index if self.background_index is None else self.background_index

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ItemParams):
            return NotImplemented
        plain = [f.name for f in dataclasses.fields(self) if f.name != "fields"]
        return (all(getattr(self, n) == getattr(other, n) for n in plain)
                and self.fields.keys() == other.fields.keys()
                and all(torch.equal(v, other.fields[k]) for k, v in self.fields.items()))

    __hash__ = None  # type: ignore[assignment]  # holds dicts and tensors
