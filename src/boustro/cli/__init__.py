"""The ``boustro`` command line: a thin layer over the public API, one module per subcommand.

Each subcommand module defines ``register(subparsers)``, which adds its parser and sets
``func`` to a ``run(args) -> int``. Errors of the library's hierarchy (bad input) print one line
``boustro: error: ...`` on stderr and exit with status 2; nothing is half-written.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence
from typing import NoReturn

from .._version import __version__
from ..errors import BoustroError

__all__ = ["build_parser", "main"]

#: Subcommand modules, in the order ``--help`` lists them.
SUBCOMMANDS = ("score", "optimize", "plan", "batch", "serve", "train", "reproduce")


class _Parser(argparse.ArgumentParser):
    """An argument parser whose refusal is one line on stderr, exit status 2, as every other
    error of the command line (argparse prints its whole usage block first; for ``plan`` that
    is 17 lines before the one that says what is wrong). Subcommands' parsers are of this class
    too (argparse makes them of their parent's)."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        self.exit(2, f"{self.prog}: error: {text} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="boustro",
        description="Plan and optimise boustrophedon (lawnmower) coverage paths over polygons.",
        epilog="Run 'boustro COMMAND --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"boustro {__version__}")
    _add_verbosity(parser, default=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    for command in sub.choices.values():  # `boustro plan F -q` as well as `boustro -q plan F`
        _add_verbosity(command, default=False)
    return parser


def _add_verbosity(parser: argparse.ArgumentParser, default: bool) -> None:
    """``-v``/``-q`` on ``parser``; a subcommand's copies set nothing unless given (SUPPRESS),
    so they never undo the same option given before the subcommand."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0 if default else argparse.SUPPRESS,
        help="more logging",
    )
    group.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=False if default else argparse.SUPPRESS,
        help="no progress bars, warnings only",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``boustro`` script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    level = logging.WARNING if args.quiet else (logging.DEBUG if args.verbose else logging.INFO)
    logging.basicConfig(level=level, format="boustro: %(message)s")
    # rasterio logs GDAL's errors at INFO before raising them (as boustro's one-line error,
    # e.g. an unreadable --dem): said once, unless -v.
    logging.getLogger("rasterio").setLevel(logging.WARNING if level > logging.DEBUG else level)
    try:
        return int(args.func(args))
    except BoustroError as exc:
        print(f"boustro: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(
            f"boustro: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
            file=sys.stderr,
        )
        return 2
    except KeyboardInterrupt:
        print("boustro: interrupted", file=sys.stderr)
        return 130
