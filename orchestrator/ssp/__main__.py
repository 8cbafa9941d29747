"""``python -m orchestrator.ssp [path]``: regenerate the sonotrack ``.ssd`` (see :func:`main`)."""

import sys

from .sonotrack import main

sys.exit(main())
