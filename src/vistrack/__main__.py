"""``python -m vistrack``: the ``vistrack`` command."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
