"""``python -m conesim``: the ``conesim`` command line."""

import sys

from conesim.envs.cli import main

sys.exit(main())
