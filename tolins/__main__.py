"""``python -m tolins``: the ``tolins`` command."""

import sys

from tolins.cli import main

sys.exit(main())
