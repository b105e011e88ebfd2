"""Build the API reference (static HTML) from pincal's docstrings with pdoc.

    pip install -e ".[docs]"
    python scripts/build_api_reference.py --out api-reference

Every public module of every stage is documented from its ``__init__``'s face
(``__all__``); the Google-style docstrings are rendered as such. Any warning pdoc
emits (a name in ``__all__`` that does not resolve, a docstring it cannot parse) fails
the build, so CI sees a broken reference. Open ``OUT/index.html``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy.testing  # noqa: F401  (see main: imported before pdoc's import guard)
import pdoc
import pdoc.render

import pincal

#: the stages in data-flow order (pincal/__init__.py); the CLI is documented by --help
STAGES = ("executor", "model", "machines", "sensitivity", "measure", "design", "identification",
          "compensation", "validation", "io", "workflow", "export", "report", "viz", "errors")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("api-reference"), help="output folder")
    args = ap.parse_args(argv)
    # the plotting / meshcat names are loaded on first use; put them in the module's
    # namespace so pdoc documents them where users import them from
    for name in pincal._LAZY:
        setattr(pincal, name, getattr(pincal, name))
    # numpy 2.0's numpy.testing runs `lscpu` when imported (its SVE check), which pdoc's
    # guard against subprocesses at import reports as a warning; it is imported above,
    # so the guard sees only what pincal's own modules do when imported.
    pdoc.render.configure(docformat="google", search=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc("pincal", *(f"pincal.{s}" for s in STAGES), output_directory=args.out)
    problems = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    for p in problems:
        print(f"api reference: {p}", file=sys.stderr)
    pages = sorted(args.out.rglob("*.html"))
    print(f"api reference: {len(pages)} pages in {args.out}/ (open {args.out / 'index.html'})")
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main())
