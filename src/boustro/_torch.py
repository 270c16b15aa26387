"""torch, imported on first use: ``from .._torch import torch`` in place of ``import torch``.

``import torch`` costs about a second of CPU, and most of boustro's work (the certified searches,
the plans, the file formats) never touches a tensor: ``boustro --help``, a ``boustro plan`` of
the time objective or ``--keep-inside``, a batch worker's start and the web server's would all
pay it. So no module of the library imports torch when it is imported (the rule of
``docs/architecture.md``); a module that computes with tensors names :data:`torch`, a stand-in
that imports torch on its first attribute (``torch.zeros``, ``torch.Tensor``) and from then on
holds torch's namespace itself (as fast as the module). Type checkers see torch itself.

``functional`` stands in for ``torch.nn.functional`` (``from .._torch import functional as F``)
the same way. Three things run when a module is executed and so cannot wait for an attribute:
a class deriving from ``torch.autograd.Function`` (:func:`autograd_function` builds it on first
use), a decorator (:func:`once_differentiable` applies torch's in the call) and a default
argument such as ``dtype=torch.float64`` (written ``dtype=None``, resolved in the call).

A kernel that serves both a gradient and a plan takes numpy arrays as well as tensors, and
computes in the namespace of its inputs (:func:`namespace`, :func:`as_array`, :func:`broadcast`):
the plan's numpy arrays never import torch, and there is one implementation of the formula.
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import sys
import types
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

__all__ = [
    "Function",
    "as_array",
    "autograd_function",
    "broadcast",
    "functional",
    "loaded",
    "namespace",
    "once_differentiable",
    "set_threads",
    "threads",
    "torch",
]

#: torch's intra-op threads to set when the stand-in imports torch (:func:`threads`), and the
#: count torch had before: ``[wanted, default]``, empty when nothing waits.
_PENDING: list[int] = []


class _LazyModule(types.ModuleType):
    """The stand-in of the module it is named after: the first attribute that is not its own
    imports that module and copies its namespace in (later attributes are plain lookups); the
    module's own lazy attributes still reach it through :meth:`__getattr__`."""

    def __getattr__(self, name: str) -> Any:
        module = importlib.import_module(self.__name__)
        self.__dict__.update(module.__dict__)
        if self.__name__ == "torch" and len(_PENDING) == 1:
            _PENDING.append(module.get_num_threads())
            module.set_num_threads(_PENDING[0])
        return getattr(module, name)

    def __reduce__(self) -> tuple[Any, tuple[str]]:
        """Pickled as the module's import (cloudpickle, for Dask, pickles by value a function
        whose globals name the stand-in before torch is imported)."""
        return importlib.import_module, (self.__name__,)


def loaded() -> bool:
    """Whether torch has been imported in this process (by boustro or by anyone)."""
    return "torch" in sys.modules


class _LazyFunction:
    """A ``torch.autograd.Function`` subclass of ``body`` (its ``forward``, ``backward``,
    ``setup_context`` and helpers), built on the first attribute (``.apply``)."""

    def __init__(self, body: type) -> None:
        self._body = body
        self._function: type | None = None

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        if self._function is None:
            body = self._body
            namespace = {"__module__": body.__module__, "__qualname__": body.__qualname__}
            self._function = type(body.__name__, (body, torch.autograd.Function), namespace)
        return getattr(self._function, name)


def set_threads(count: int) -> None:
    """torch's intra-op threads set to ``count`` for good: at once if torch is imported, else
    when the stand-in imports it (a batch worker's start)."""
    if loaded():
        torch.set_num_threads(count)
    else:
        _PENDING[:] = [count]


@contextlib.contextmanager
def threads(count: int) -> Iterator[None]:
    """torch's intra-op threads set to ``count`` for the block, and restored after: at once if
    torch is imported, else when the stand-in imports it (a batch worker, the web server and
    ``reproduce`` set one thread without importing torch for the plans that need none)."""
    if loaded():
        previous = torch.get_num_threads()
        torch.set_num_threads(count)
        try:
            yield
        finally:
            torch.set_num_threads(previous)
        return
    outer = _PENDING[:]  # an enclosing block's or set_threads' wish, still pending
    _PENDING[:] = [count]
    try:
        yield
    finally:
        if len(_PENDING) == 2:  # torch came in the block: the outer wish, else its own count
            default = _PENDING[1]
            torch.set_num_threads(outer[0] if outer else default)
            _PENDING[:] = [outer[0], default] if outer else []
        else:
            _PENDING[:] = outer


def namespace(like: Any) -> Any:
    """The module that computes on ``like``: numpy for a numpy array, else torch."""
    return np if isinstance(like, np.ndarray) else torch


def as_array(value: Any, like: Any) -> Any:
    """``value`` as an array of ``like``'s kind (numpy array or tensor), dtype and device."""
    if isinstance(like, np.ndarray):
        return np.asarray(value, dtype=like.dtype)
    return torch.as_tensor(value, dtype=like.dtype, device=like.device)


def broadcast(*arrays: Any) -> Any:
    """The arrays broadcast against each other (numpy arrays or tensors, not mixed)."""
    if isinstance(arrays[0], np.ndarray):
        return np.broadcast_arrays(*arrays)
    return torch.broadcast_tensors(*arrays)


def once_differentiable(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``torch.autograd.function.once_differentiable``, applied to ``fn`` when it is called."""

    @functools.wraps(fn)
    def call(ctx: Any, *args: Any) -> Any:
        return torch.autograd.function.once_differentiable(fn)(ctx, *args)

    return call


def autograd_function(body: type) -> Any:
    """Class decorator: ``body`` (written ``class Name(Function)``, :data:`Function`) as a
    ``torch.autograd.Function``, subclassed on first use, so that defining it imports nothing.
    ``Name.apply(...)`` works as on the Function."""
    return _LazyFunction(body)


if TYPE_CHECKING:
    import torch
    import torch.nn.functional as functional

    Function = torch.autograd.Function
else:
    #: The base to write for an :func:`autograd_function` (type checkers see torch's Function).
    Function = object
    torch = _LazyModule("torch", "torch, imported on first use (boustro._torch)")
    functional = _LazyModule("torch.nn.functional", "imported on first use (boustro._torch)")
