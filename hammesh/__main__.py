"""``python -m hammesh`` = the ``hammesh`` command."""

import sys

from hammesh.cli import main

sys.exit(main())
