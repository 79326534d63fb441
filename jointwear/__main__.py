"""``python -m jointwear`` works like the ``jointwear`` script."""

import sys

from jointwear.cli import main

sys.exit(main())
