"""Compatibility path: ``boustro._compiled`` is :mod:`boustro.models._kernels`."""

import sys

from .models import _kernels as _module

sys.modules[__name__] = _module
