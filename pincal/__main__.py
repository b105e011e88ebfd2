"""``python -m pincal``: the pincal command (as ``python -m pincal.cli`` and ``pincal``)."""

from pincal.cli import main

main(prog_name="pincal")
