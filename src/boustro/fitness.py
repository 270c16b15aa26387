"""Compatibility path: ``boustro.fitness`` is :mod:`boustro.objectives.smith`."""

import sys

from .objectives import smith as _module

sys.modules[__name__] = _module
