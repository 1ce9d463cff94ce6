"""`python -m scoursph ...` is the `scoursph` command."""

import sys

from .cli import main

sys.exit(main())
