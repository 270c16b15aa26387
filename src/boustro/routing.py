"""Compatibility path: ``boustro.routing`` is :mod:`boustro.plan.routing`."""

import sys

from .plan import routing as _module

sys.modules[__name__] = _module
