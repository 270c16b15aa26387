"""Compatibility path: ``boustro.plot_plan`` is :mod:`boustro.plot.plan`."""

import sys

from .plot import plan as _module

sys.modules[__name__] = _module
