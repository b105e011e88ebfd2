"""``python -m pincal.cli``: the pincal command."""

from pincal.cli import main

main()
