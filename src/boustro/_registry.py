"""Named variants of an extension point, registered by the file that defines them.

Objectives, optimisers and mission formats are each a :class:`Registry`: a ``dict`` from a
canonical name to the variant, filled by a decorator in the module that defines the variant, and
by :meth:`Registry.discover`, which imports every module of the variant's package so that a new
file in that package is registered without editing any other (see ``docs/architecture.md``).
Names are canonical in snake case; lookups accept kebab case too (``fewest-transects``).
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from collections.abc import Callable
from typing import Any, TypeVar

from .errors import InvalidParameterError

__all__ = ["Registry", "canonical_name"]

T = TypeVar("T")


def canonical_name(name: object, kind: str = "name") -> str:
    """``name`` in snake case (``"fewest-transects"`` -> ``"fewest_transects"``).

    >>> canonical_name("Fewest-Transects")
    'fewest_transects'
    """
    if not isinstance(name, str) or not name.strip():
        raise InvalidParameterError(f"a {kind} name must be a non-empty string, got {name!r}")
    return name.strip().lower().replace("-", "_")


class Registry(dict[str, T]):
    """Variants by canonical name; ``kind`` names them in error messages.

    ``package`` is the dotted name of the package whose modules define variants; each module
    registers its own with :meth:`register` at import, and :meth:`discover` imports them all.
    Names are stored in snake case (``snake_case=False`` keeps them as given).

    >>> shapes = Registry("shape")
    >>> @shapes.register("unit-square")
    ... def unit_square():
    ...     return [(0, 0), (1, 0), (1, 1), (0, 1)]
    >>> sorted(shapes), shapes.get_variant("unit_square") is unit_square
    (['unit_square'], True)
    """

    def __init__(self, kind: str, package: str | None = None, *, snake_case: bool = True) -> None:
        super().__init__()
        self.kind = kind
        self.package = package
        self.snake_case = snake_case

    def key(self, name: object) -> str:
        """The registry's spelling of ``name`` (snake case unless the registry keeps names)."""
        if self.snake_case:
            return canonical_name(name, self.kind)
        if not isinstance(name, str) or not name:
            raise InvalidParameterError(
                f"a {self.kind} name must be a non-empty string, got {name!r}"
            )
        return name

    def register(self, name: str, value: T | None = None, *, replace: bool = False) -> Any:
        """Register ``value`` as ``name``, or return a decorator that registers what it wraps.

        Raises:
            InvalidParameterError: an empty name, or a name already taken (unless ``replace``).
        """
        key = self.key(name)

        def add(item: T) -> T:
            if key in self and not replace:
                raise InvalidParameterError(f"{self.kind} {key!r} is already registered")
            self[key] = item
            return item

        if value is None:
            return add
        return add(value)

    def get_variant(self, name: str) -> T:
        """The variant registered as ``name`` (snake or kebab case).

        Raises:
            InvalidParameterError: no such variant; the message lists the known ones.
        """
        key = self.key(name)
        if key not in self:
            known = ", ".join(sorted(self)) or "(none)"
            raise InvalidParameterError(f"unknown {self.kind} {name!r}; expected one of {known}")
        return self[key]

    def discover(self) -> list[str]:
        """Import every module of :attr:`package` not imported yet; returns their names."""
        if self.package is None:
            return []
        package = sys.modules.get(self.package) or importlib.import_module(self.package)
        found = []
        for info in pkgutil.iter_modules(package.__path__, self.package + "."):
            if info.name.rpartition(".")[2].startswith("__") or info.name in sys.modules:
                continue
            importlib.import_module(info.name)
            found.append(info.name)
        return found

    def names(self, predicate: Callable[[T], bool] | None = None) -> list[str]:
        """Registered names (sorted), optionally only those whose variant passes ``predicate``."""
        return sorted(k for k, v in self.items() if predicate is None or predicate(v))
