"""Assertions shared by the CLI bad-input tests."""

from __future__ import annotations


def assert_clean_failure(res, name: str) -> None:
    """A refused input: exit 1 (or 2, click refused the path), one line naming ``name``."""
    assert res.exit_code in (1, 2), res.output  # 2: click refused the path itself
    assert "Traceback" not in res.output, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit), res.exception
    err = res.stderr.strip()
    assert err and len(err) < 1000, err
    if res.exit_code == 1:
        assert len(err.splitlines()) == 1, err
        assert name in err, err
