"""``python -m boustro``: the ``boustro`` command line."""

from .cli import main

raise SystemExit(main())
