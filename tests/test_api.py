"""The public API: every exported name resolves, and `import pincal` stays light."""

from __future__ import annotations

import subprocess
import sys

import pincal


def test_every_exported_name_resolves():
    missing = [n for n in pincal.__all__ if getattr(pincal, n, None) is None]
    assert not missing


def test_plotting_and_meshcat_load_lazily():
    code = "import sys, pincal; print('meshcat' in sys.modules, 'matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
