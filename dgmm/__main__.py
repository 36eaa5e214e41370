"""``python -m dgmm``: the dgmm command line (see :mod:`dgmm.cli`)."""
import sys

from dgmm.cli import main

sys.exit(main())
