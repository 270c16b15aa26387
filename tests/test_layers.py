"""The core never pulls in plotting, file formats, projections or the command line."""

import subprocess
import sys


def test_core_import_is_light():
    code = (
        "import sys, boustro; "
        "bad = [m for m in ('matplotlib', 'shapely', 'pyproj', 'boustro.cli', 'boustro.io') "
        "if m in sys.modules]; print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
