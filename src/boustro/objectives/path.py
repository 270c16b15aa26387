"""Shortest boustrophedon path (transects plus connecting moves), minimised."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .._torch import torch
from ..errors import InvalidParameterError
from ..models import Chords, TransectLengths
from .base import BaseObjective
from .registry import register_objective
from .turns import GRAZE

__all__ = ["ShortestPath", "path_length"]


def path_length(
    chords: Chords, *, start: Literal["best", "upper", "lower"] = "best"
) -> torch.Tensor:
    """Total boustrophedon path ``(*)`` over exact chords ``(*, K)``: see :class:`ShortestPath`.

    The transects that cross the polygon are driven in order of position; consecutive ones are
    joined by a straight move between their ends on the same side, the side alternating. With
    ``start="upper"`` the first move joins the ends at the transects' ``upper`` coordinate (the
    first transect is driven along its direction), with ``"lower"`` the other way round, and
    ``"best"`` takes the shorter. Layouts without any transect have length 0.
    """
    if start not in ("best", "upper", "lower"):
        raise InvalidParameterError(f"start must be 'best', 'upper' or 'lower', got {start!r}")
    length = chords.lengths
    shown = length > GRAZE
    zero = torch.zeros_like(length)
    lower = torch.where(shown, chords.lower, zero)
    upper = torch.where(shown, chords.upper, zero)
    total = torch.where(shown, length, zero).sum(dim=-1)
    pair = shown[..., 1:] & shown[..., :-1]
    gap = chords.positions[..., 1:] - chords.positions[..., :-1]
    # index of each move among the moves of its layout: 0, 1, 2, ...
    index = torch.cumsum(pair.to(torch.int64), dim=-1) - 1
    even = (index % 2) == 0
    d_up = upper[..., 1:] - upper[..., :-1]
    d_lo = lower[..., 1:] - lower[..., :-1]
    move_up = torch.sqrt(gap * gap + d_up * d_up)
    move_lo = torch.sqrt(gap * gap + d_lo * d_lo)
    pz = torch.zeros_like(move_up)
    first_up = torch.where(pair, torch.where(even, move_up, move_lo), pz).sum(dim=-1)
    first_lo = torch.where(pair, torch.where(even, move_lo, move_up), pz).sum(dim=-1)
    if start == "upper":
        return total + first_up
    if start == "lower":
        return total + first_lo
    return total + torch.minimum(first_up, first_lo)


@register_objective("shortest_path")
@dataclass(frozen=True)
class ShortestPath(BaseObjective):
    """Total path length: transects plus straight connecting moves; **minimised**.

    Needs exact :class:`~boustro.models.Chords` (the ends of the transects), hence
    ``needs_chords = True``: an optimiser evaluates it on
    :func:`~boustro.models.exact_chords` rather than on a model's lengths. Lengths are in the
    chords' frame (normalised for the library: multiply by the polygon's diameter for its units).

    Attributes:
        start: which side the first connecting move is on (``"best"``: the shorter path).
    """

    start: Literal["best", "upper", "lower"] = "best"
    name: str = "shortest_path"
    maximise: bool = False
    needs_chords: bool = True

    def __post_init__(self) -> None:
        if self.start not in ("best", "upper", "lower"):
            raise InvalidParameterError(
                f"start must be 'best', 'upper' or 'lower', got {self.start!r}"
            )

    def __call__(self, chords: TransectLengths | Chords) -> torch.Tensor:
        if not isinstance(chords, Chords):
            raise InvalidParameterError(
                "ShortestPath needs exact chords (boustro.models.exact_chords), got "
                f"{type(chords).__name__}: transect lengths alone do not say where the ends are"
            )
        return path_length(chords, start=self.start)


#: The objectives by name, as the command line and the optimisers' ``objective=`` accept them.
