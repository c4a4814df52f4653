"""`python -m choreo ...` (and `torchrun ... -m choreo train ...`): the command line."""

import sys

from .cli import ignore_signals_at_exit, main

code = main()
ignore_signals_at_exit()
sys.exit(code)
