"""``python -m framework.cli``: the ``metaik`` command."""

import sys

from . import main

sys.exit(main())
