"""Compatibility path: ``boustro.formats`` is :mod:`boustro.io.formats`."""

import sys

from .io import formats as _module

sys.modules[__name__] = _module
