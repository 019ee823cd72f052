import sys

from deckpound.cli import main

sys.exit(main())
