"""Where the examples write their pictures: the folder given as the first argument, else
$VIBROFEM_EXAMPLES_OUT, else the current folder."""

from __future__ import annotations

import os
import sys
from pathlib import Path


def out_dir() -> Path:
    d = Path(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("VIBROFEM_EXAMPLES_OUT", "."))
    d.mkdir(parents=True, exist_ok=True)
    return d
