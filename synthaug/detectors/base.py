"""The detector contract shared by the three families (HOG/DPM, AdaBoost, CNN).

A detector scores fixed-size grayscale *patches*; sliding-window detection over
full frames (:mod:`synthaug.detectors.sliding`) only needs :meth:`score_map`.
Every detector serialises to plain tensors and Python types, so one file format
(:func:`save_detector` / :func:`load_detector`) serves all of them and loads
with ``torch.load(..., weights_only=True)`` — no pickled code is ever executed.

Conventions:
    - patches are float32 grayscale in [0, 1], shape ``(N, 1, window, window)``;
    - scores are real numbers, higher = more object-like; the threshold that
      separates object from background is the detector's own business (0 for
      the linear SVMs and AdaBoost, the logit for the CNN);
    - ``score_map(image)[y, x]`` is the score of the window whose top-left
      corner is at pixel ``(y * stride, x * stride)`` of ``image``.

A new family subclasses :class:`PatchDetector`, sets ``kind`` and decorates the
class with :func:`register_detector`. Modules of the built-in families are
imported lazily by :func:`load_detector` (see ``_KIND_MODULES``).
"""

from __future__ import annotations

import abc
import importlib
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import torch
from torch import Tensor

from synthaug._io import check_header

FORMAT_NAME = "synthaug.detector"
FORMAT_VERSION = 1

# kind -> module that defines and registers it, imported on first use so that
# `import synthaug.detectors.base` stays light.
_KIND_MODULES: dict[str, str] = {
    "hog": "synthaug.detectors.hog_dpm",
    "adaboost": "synthaug.detectors.adaboost",
    "cnn": "synthaug.detectors.cnn",
}

_REGISTRY: dict[str, type["PatchDetector"]] = {}

D = TypeVar("D", bound="PatchDetector")


class PatchDetector(abc.ABC):
    """A binary object/background scorer of ``window x window`` grayscale patches.

    Subclasses implement :meth:`score_patches`, :meth:`state_dict` and
    :meth:`from_state_dict`; they should override :meth:`score_map` with a dense
    computation (shared features per image, convolution over them) — the
    default here crops every window and calls :meth:`score_patches`, which is
    correct but slow.

    Attributes:
        kind: registry name of the family (``"hog"``, ``"adaboost"``, ``"cnn"``).
        window: side of the square patch in pixels (40 in the paper).
        stride: pixel step between neighbouring windows of :meth:`score_map`.
        box_in_window: ``(x, y, w, h)`` of the object inside a training patch,
            in window pixels, or None for the whole window; sliding-window
            detection reports this box. Saved and restored by
            :func:`save_detector` / :func:`load_detector` for every family.
        box_regressor: a :class:`~synthaug.detectors.boxes.BoxRegressor` that maps each
            detection's box to the annotators' box (fitted on the training labels by
            ``synthaug train``), or None; saved and restored with the detector.
    """

    kind: ClassVar[str]
    window: int = 40
    stride: int = 4
    box_in_window: tuple[float, float, float, float] | None = None
    box_regressor: Any = None

    @abc.abstractmethod
    def score_patches(self, patches: Tensor) -> Tensor:
        """Score a batch of patches.

        Args:
            patches: float grayscale patches in [0, 1].

        Returns:
            One real score per patch, higher = more object-like.

        Shape:
            - patches: (N, 1, window, window)
            - output: (N,)
        """

    def score_map(self, image: Tensor) -> Tensor:
        """Score every window of an image on a grid of step :attr:`stride`.

        Args:
            image: float grayscale image in [0, 1].

        Returns:
            ``out[y, x]`` = score of the window with top-left ``(y*stride, x*stride)``;
            empty (0 rows or columns) when the image is smaller than the window.

        Shape:
            - image: (1, 1, H, W)
            - output: ((H - window) // stride + 1, (W - window) // stride + 1)
        """
        image = check_image(image)
        h_out, w_out = score_map_shape(image.shape[-2], image.shape[-1], self.window, self.stride)
        if h_out == 0 or w_out == 0:
            return image.new_zeros(max(h_out, 0), max(w_out, 0))
        # (1, window*window, L) -> (L, 1, window, window)
        cols = torch.nn.functional.unfold(image, kernel_size=self.window, stride=self.stride)
        patches = cols[0].T.reshape(-1, 1, self.window, self.window)
        scores = torch.cat([self.score_patches(chunk) for chunk in patches.split(4096)])
        return scores.reshape(h_out, w_out)

    @abc.abstractmethod
    def state_dict(self) -> dict[str, Any]:
        """Everything needed to rebuild the detector, as tensors and plain Python types."""

    @classmethod
    @abc.abstractmethod
    def from_state_dict(cls: type[D], state: dict[str, Any]) -> D:
        """Rebuild a detector from :meth:`state_dict` output.

        Raises:
            KeyError or ValueError: when ``state`` lacks a field or has a wrong
                shape; :func:`load_detector` turns either into a ValueError
                naming the file.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}(kind={self.kind!r}, window={self.window}, stride={self.stride})"


def check_image(image: Tensor) -> Tensor:
    """Validate and normalise an image to float32 ``(1, 1, H, W)``.

    Args:
        image: ``(H, W)``, ``(1, H, W)`` or ``(1, 1, H, W)`` grayscale tensor.

    Returns:
        The same values as float32, shape ``(1, 1, H, W)`` (a view when possible).

    Example:
        >>> check_image(torch.zeros(4, 6)).shape
        torch.Size([1, 1, 4, 6])
    """
    if not isinstance(image, Tensor):
        raise ValueError(f"image must be a torch.Tensor, got {type(image).__name__}")
    if image.dim() == 2:
        image = image[None, None]
    elif image.dim() == 3 and image.shape[0] == 1:
        image = image[None]
    if image.dim() != 4 or image.shape[0] != 1 or image.shape[1] != 1:
        raise ValueError(f"image must be (H, W) or (1, 1, H, W) grayscale, got shape {tuple(image.shape)}")
    if not image.dtype.is_floating_point:
        raise ValueError(f"image must be a float tensor in [0, 1], got dtype {image.dtype}")
    return image.float()


def check_patches(patches: Tensor, window: int) -> Tensor:
    """Validate a batch of patches, returning it as float32 ``(N, 1, window, window)``.

    Example:
        >>> check_patches(torch.zeros(3, 1, 40, 40), 40).shape
        torch.Size([3, 1, 40, 40])
    """
    if not isinstance(patches, Tensor):
        raise ValueError(f"patches must be a torch.Tensor, got {type(patches).__name__}")
    if patches.dim() == 3:
        patches = patches[:, None]
    if patches.dim() != 4 or patches.shape[1] != 1 or patches.shape[-2:] != (window, window):
        raise ValueError(f"patches must be (N, 1, {window}, {window}), got shape {tuple(patches.shape)}")
    if not patches.dtype.is_floating_point:
        raise ValueError(f"patches must be float in [0, 1], got dtype {patches.dtype}")
    return patches.float()


def check_weights(weights: Any, n: int, name: str = "positive_weights", per: str = "positive", *,
                  flatten: bool = False, not_all_zero: bool = True) -> Tensor:
    """``weights`` as a float64 tensor of ``n`` training weights, one per ``per``: finite, >= 0 and (with
    ``not_all_zero``) not all zero; ``flatten`` accepts any shape holding ``n`` values. ValueError naming
    ``name`` otherwise. The one check of every family's per-positive weights (HOG's SVM, AdaBoost's starting
    weights, the CNN's loss).

    Example:
        >>> check_weights([1, 0, 2], 3).tolist()
        [1.0, 0.0, 2.0]
        >>> check_weights([0, 0], 2)
        Traceback (most recent call last):
        ...
        ValueError: positive_weights must be finite, >= 0, not all 0 and one per positive (2), got (2,)
    """
    given = torch.as_tensor(weights).detach()
    w = (given.flatten() if flatten else given).to(torch.float64)
    zero = not_all_zero and n > 0 and w.shape == (n,) and not bool((w != 0).any())
    if w.shape != (n,) or not bool(torch.isfinite(w).all()) or bool((w < 0).any()) or zero:
        rule = ", not all 0" if not_all_zero else ""
        raise ValueError(f"{name} must be finite, >= 0{rule} and one per {per} ({n}), got {tuple(given.shape)}")
    return w


def to_float_patches(patches: Tensor, window: int) -> Tensor:
    """Accept uint8 (0..255) or float (0..1) patches, ``(N, w, w)`` or ``(N, 1, w, w)``.

    Seed sets store patches as uint8 ``(N, 40, 40)``; detectors work on float32
    ``(N, 1, 40, 40)`` in [0, 1].

    Example:
        >>> to_float_patches(torch.full((2, 40, 40), 255, dtype=torch.uint8), 40).amax().item()
        1.0
    """
    if not isinstance(patches, Tensor):
        raise ValueError(f"patches must be a torch.Tensor, got {type(patches).__name__}")
    if patches.dtype == torch.uint8:
        patches = patches.float() / 255.0
    return check_patches(patches, window)


def score_map_shape(height: int, width: int, window: int, stride: int) -> tuple[int, int]:
    """Number of window positions ``(h', w')`` of :meth:`PatchDetector.score_map`.

    Example:
        >>> score_map_shape(512, 640, 40, 4)
        (119, 151)
        >>> score_map_shape(30, 640, 40, 4)
        (0, 151)
    """
    h = (height - window) // stride + 1 if height >= window else 0
    w = (width - window) // stride + 1 if width >= window else 0
    return h, w


def box_in_window_from_boxes(boxes_xywh: Tensor, *, window: int = 40, object_fraction: float = 0.7) -> tuple[float, float, float, float]:
    """Typical object box inside a seed patch, for :attr:`PatchDetector.box_in_window`.

    Seed patches (:mod:`synthaug.data.seedset`) centre the object and scale its
    box's longest side to ``object_fraction * window`` pixels; the box reported
    for a detection is then the median-aspect box, centred.

    Args:
        boxes_xywh: the seeds' boxes in frame pixels, ``(N, 4)``.
        window: patch side.
        object_fraction: the seed set's ``object_fraction``.

    Example:
        >>> box_in_window_from_boxes(torch.tensor([[0., 0., 20., 10.], [5., 5., 30., 15.]]))
        (6.0, 13.0, 28.0, 14.0)
    """
    boxes = torch.as_tensor(boxes_xywh, dtype=torch.float64).reshape(-1, 4)
    if boxes.shape[0] == 0 or not bool((boxes[:, 2:] > 0).all()):
        raise ValueError(f"boxes_xywh must be a non-empty (N, 4) with positive sizes, got shape {tuple(boxes.shape)}")
    if not 0 < object_fraction <= 1:
        raise ValueError(f"object_fraction must be in (0, 1], got {object_fraction}")
    longest = boxes[:, 2:].amax(1, keepdim=True)
    rel = (boxes[:, 2:] / longest * object_fraction * window).median(0).values  # (w, h) in window pixels
    w, h = float(rel[0]), float(rel[1])
    return ((window - w) / 2, (window - h) / 2, w, h)


def register_detector(cls: type[D]) -> type[D]:
    """Class decorator: make a :class:`PatchDetector` subclass loadable by its ``kind``.

    Raises:
        ValueError: if ``cls`` is not a PatchDetector subclass, has no ``kind``,
            or its kind is already taken by another class.
    """
    if not (isinstance(cls, type) and issubclass(cls, PatchDetector)):
        raise ValueError(f"register_detector expects a PatchDetector subclass, got {cls!r}")
    kind = getattr(cls, "kind", None)
    if not isinstance(kind, str) or not kind:
        raise ValueError(f"{cls.__name__}.kind must be a non-empty string, got {kind!r}")
    other = _REGISTRY.get(kind)
    if other is not None and (other.__module__, other.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"detector kind {kind!r} is already registered by {other.__module__}.{other.__qualname__}")
    _REGISTRY[kind] = cls
    return cls


def get_detector_class(kind: str) -> type[PatchDetector]:
    """The registered class of a detector kind, importing its module on demand.

    Raises:
        ValueError: for an unknown kind, listing the known ones.
    """
    if kind not in _REGISTRY and kind in _KIND_MODULES:
        _import_optional(_KIND_MODULES[kind])
    if kind not in _REGISTRY:
        raise ValueError(f"unknown detector kind {kind!r}; available: {list_detectors()}")
    return _REGISTRY[kind]


def list_detectors() -> list[str]:
    """Kinds whose implementation is importable (built-in ones are imported to check).

    Example:
        >>> "hog" in list_detectors()
        True
    """
    for module in _KIND_MODULES.values():
        _import_optional(module)
    return sorted(_REGISTRY)


def _import_optional(module: str) -> bool:
    try:
        importlib.import_module(module)
    except ModuleNotFoundError as e:
        # only "this module does not exist (yet)" is tolerated; a missing
        # dependency *inside* an existing module is a real error.
        if e.name and (e.name == module or module.startswith(e.name + ".")):
            return False
        raise
    return True


def save_detector(detector: PatchDetector, path: str | Path) -> Path:
    """Write a detector to one file (``torch.save`` of plain tensors and Python types).

    The write is atomic (temporary file + rename), so a crash never leaves a
    half-written checkpoint under ``path``.

    Args:
        detector: any registered :class:`PatchDetector`.
        path: destination file (``.pt`` by convention); parent folders are created.

    Returns:
        The path written.
    """
    if not isinstance(detector, PatchDetector):
        raise ValueError(f"save_detector expects a PatchDetector, got {type(detector).__name__}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "kind": detector.kind,
        "window": int(detector.window),
        "stride": int(detector.stride),
        "box_in_window": None if detector.box_in_window is None else [float(v) for v in detector.box_in_window],
        "state": detector.state_dict(),
        "box_regressor": None if detector.box_regressor is None else detector.box_regressor.state_dict(),
    }
    tmp = path.with_name(f".{path.name}.tmp")
    torch.save(payload, tmp)
    tmp.replace(path)
    return path


def load_detector(path: str | Path, *, map_location: str | torch.device = "cpu") -> PatchDetector:
    """Load a detector written by :func:`save_detector`, with ``weights_only=True``.

    Args:
        path: checkpoint file.
        map_location: where tensors are loaded (CPU by default).

    Returns:
        The rebuilt detector, of the class registered for the file's ``kind``.

    Raises:
        FileNotFoundError: if ``path`` does not exist.
        ValueError: naming the file, if it is not a readable torch file, not a
            synthaug detector, of an unknown kind or version, or if its state does
            not rebuild a detector (missing field, wrong shape).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"detector checkpoint not found: {path}")
    try:
        payload = torch.load(path, map_location=map_location, weights_only=True)
    except Exception as e:  # torch raises many types for truncated/garbage files, and refuses pickled code
        from synthaug._checks import torch_load_error

        raise ValueError(f"{path} is not a readable synthaug detector checkpoint ({torch_load_error(e)})") from e
    payload = check_header(payload, format=FORMAT_NAME, version=FORMAT_VERSION, what="detector checkpoint", source=path)
    kind = payload.get("kind")
    try:
        cls = get_detector_class(kind)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from e
    state = payload.get("state")
    if not isinstance(state, dict):
        raise ValueError(f"{path}: checkpoint has no state dict (got {type(state).__name__})")
    try:
        detector = cls.from_state_dict(state)
    except (KeyError, ValueError, TypeError, RuntimeError) as e:
        raise ValueError(f"{path}: state does not match a {kind!r} detector ({type(e).__name__}: {e})") from e
    box = payload.get("box_in_window")
    if box is not None:
        if not (isinstance(box, (list, tuple)) and len(box) == 4):
            raise ValueError(f"{path}: box_in_window must be 4 numbers [x, y, w, h], got {box!r}")
        detector.box_in_window = tuple(float(v) for v in box)
    reg = payload.get("box_regressor")
    if reg is not None:
        from synthaug.detectors.box_cnn import regressor_from_state_dict

        if not isinstance(reg, dict):
            raise ValueError(f"{path}: box_regressor must be a state dict, got {type(reg).__name__}")
        try:
            detector.box_regressor = regressor_from_state_dict(reg)
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from e
    return detector
