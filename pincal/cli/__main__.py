"""``python -m pincal.cli``: the pincal command."""

from pincal.cli import main

if __name__ == "__main__":  # worker processes (Dask spawns them) import this module again
    main()
