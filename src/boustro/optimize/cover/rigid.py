"""Holes that every plan of a box of layouts cuts, from the box's rigid motions (see
:class:`~boustro.optimize.cover.bands.BandStats`, field ``rigid``); the loop is compiled by
numba with the rest of :mod:`~boustro.optimize.cover.bands`."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

__all__ = ["RigidBoxes"]


class RigidBoxes(NamedTuple):
    """The holes' vertices ``xy (V, 2)`` (hole ``h``: rows ``start[h]:start[h + 1]``) and the
    boxes' half-widths ``delta`` (angle) and ``eta`` (offset), ``(L,)``: for ``rigid``."""

    xy: NDArray[np.float64]
    start: NDArray[np.int64]
    delta: NDArray[np.float64]
    eta: NDArray[np.float64]


def _rigid_cuts(
    hxy, hstart, cs, sn, d, s, ox, oy, k0, nb, delta, eta, i_start, i_m, i_lo, i_hi, tol, rigid
):
    """``rigid[h]``: hole ``h`` is cut by every plan of the box (:class:`BandStats`)."""
    for h in range(hstart.shape[0] - 1):
        n_lo, n_hi, u_lo, u_hi, rho = np.inf, -np.inf, np.inf, -np.inf, 0.0
        for v in range(hstart[h], hstart[h + 1]):
            x, y = hxy[v, 0] - ox, hxy[v, 1] - oy
            nv, uv = -sn * x + cs * y, cs * x + sn * y
            n_lo, n_hi = min(n_lo, nv), max(n_hi, nv)
            u_lo, u_hi = min(u_lo, uv), max(u_hi, uv)
            rho = max(rho, math.sqrt(x * x + y * y))
        m = delta * rho + eta + tol
        ka = max(math.ceil((n_lo + m - d) / s), k0)
        kb = min(math.floor((n_hi - m - d) / s), k0 + nb - 1)
        for k in range(ka, kb + 1):
            c = d + k * s
            if not (n_lo + m < c < n_hi - m):
                continue
            b = k - k0
            found = False
            for j in range(i_start[b], i_start[b] + i_m[b]):
                if i_lo[j] <= u_lo - m and i_hi[j] >= u_hi + m:
                    found = True
                    break
            if found:
                rigid[h] = True
                break
