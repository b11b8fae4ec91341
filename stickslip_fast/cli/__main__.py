"""``python -m stickslip_fast.cli``: the same as the ``stickslip-fast`` command."""

import sys

from .commands import main

sys.exit(main())
