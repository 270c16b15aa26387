"""Compatibility path: ``boustro.smooth`` is :mod:`boustro.models.smooth`."""

import sys

from .models import smooth as _module

sys.modules[__name__] = _module
