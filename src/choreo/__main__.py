"""`python -m choreo ...` (and `torchrun ... -m choreo train ...`): the command line."""

import sys

from .cli import main

sys.exit(main())
