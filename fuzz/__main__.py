"""``python -m fuzz``: see ``fuzz.run``."""
import sys

from .run import main

sys.exit(main())
