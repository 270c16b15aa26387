"""The learned planner's weights: saved atomically beside their settings, loaded and cached."""

from __future__ import annotations

import io
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import torch

from .._files import atomic_write
from ..errors import InvalidParameterError
from .network import LearnedPlanner, PlannerConfig

__all__ = ["DEFAULT_WEIGHTS", "as_planner", "check_weights_path", "load_planner", "save_planner"]

#: The weights shipped with the package (``torch.save(state_dict)``) and their hyperparameters.
DEFAULT_WEIGHTS = Path(__file__).parent.parent / "data" / "learned_planner.pt"


def check_weights_path(path: str | Path) -> Path:
    """``path`` as a :class:`Path`, refused if it ends in ``.json``: the settings of the planner
    are written beside the weights under that suffix (:func:`save_planner`)."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        raise InvalidParameterError(
            f"weights file {path} must not end in .json: the settings are written beside it "
            "with that suffix"
        )
    return path


def save_planner(
    model: LearnedPlanner, path: str | Path, *, metadata: dict[str, Any] | None = None
) -> tuple[Path, Path]:
    """Save ``state_dict`` (float32) to ``path`` and hyperparameters (+ metadata) to ``.json``.

    Both files are written atomically (a temporary file, then a rename), the settings last;
    missing folders are created.

    Raises:
        InvalidParameterError: ``path`` ends in ``.json`` (the settings' name), or a weight or a
            metadata number is not finite (a diverged training).
    """
    path = check_weights_path(path)
    state = {k: v.detach().to(torch.float32).clone() for k, v in model.state_dict().items()}
    if not all(bool(torch.isfinite(v).all()) for v in state.values()):
        raise InvalidParameterError("the planner's weights are not all finite; nothing saved")
    meta = {"config": asdict(model.config), **(metadata or {})}
    try:
        text = json.dumps(meta, indent=2, sort_keys=True, allow_nan=False) + "\n"
    except ValueError:
        raise InvalidParameterError(
            "the planner's metadata has a number that is not finite; nothing saved"
        ) from None
    buffer = io.BytesIO()
    torch.save(state, buffer)
    path.parent.mkdir(parents=True, exist_ok=True)
    json_path = path.with_suffix(".json")
    atomic_write(path, buffer.getvalue())
    atomic_write(json_path, text)
    return path, json_path


_CACHE: dict[tuple[tuple[str, int, int], ...], LearnedPlanner] = {}


def load_planner(path: str | Path | None = None) -> LearnedPlanner:
    """Load a planner saved by :func:`save_planner` (default: the weights shipped in the
    package), with ``torch.load(..., weights_only=True)``; in eval mode, cached by path.

    >>> planner = load_planner()
    >>> planner.config.hypotheses, planner.training
    (16, False)
    """
    path = Path(DEFAULT_WEIGHTS if path is None else path)
    json_path = path.with_suffix(".json")
    try:  # the cache knows a file by its name and its version on disk
        stats = [(f, f.stat()) for f in (path, json_path)]
        key = tuple((str(f.resolve()), st.st_mtime_ns, st.st_size) for f, st in stats)
    except FileNotFoundError as exc:
        missing = "its settings file " if exc.filename == str(json_path) else ""
        raise InvalidParameterError(
            f"no learned planner at {path} ({missing}{exc.filename} is missing): train one with "
            "'boustro train', which writes both files"
        ) from None
    if key in _CACHE:
        return _CACHE[key]
    try:
        meta = json.loads(json_path.read_text())
        state = torch.load(path, map_location="cpu", weights_only=True)
        model = LearnedPlanner(PlannerConfig(**meta["config"]))
        model.load_state_dict(state)
    except Exception as exc:  # any malformed or foreign file: one clear error
        raise InvalidParameterError(
            f"{path} (with {json_path.name}) is not a planner saved by boustro: "
            f"{type(exc).__name__}: {exc}"[:300]
        ) from None
    model.eval()
    _CACHE[key] = model
    return model


def as_planner(planner: LearnedPlanner | str | Path | None) -> LearnedPlanner:
    """``planner`` itself, or the planner saved at that path (``None``: the shipped one)."""
    if isinstance(planner, LearnedPlanner):
        return planner
    return load_planner(planner)
