"""``python -m kinetwork.cli``: the ``kinetwork`` command."""

import sys

from . import main

sys.exit(main())
