"""``python -m twin``: the ``twin`` command."""

import sys

from twin.cli.main import main

sys.exit(main())
