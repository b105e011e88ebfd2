"""`pincal view --live` (issue 16): loopback only, and the server dies with pincal.

Checked from outside with ``ss -ltnp`` (iproute2): every listening socket of the
meshcat server is on 127.0.0.1, and none remains after pincal ends by Enter, SIGTERM
or SIGKILL.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

ROOT = Path(__file__).resolve().parents[2]
needs_ss = pytest.mark.skipif(shutil.which("ss") is None, reason="needs ss (iproute2)")


def listeners(pid: int) -> list[str]:
    """Local addresses of the TCP sockets process ``pid`` listens on."""
    out = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=True).stdout
    return [line.split()[3] for line in out.splitlines() if f"pid={pid}," in line]


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, IndexError):
        return False
    return state != "Z"  # a zombie holds no sockets and runs no code


def server_of(pincal: int) -> int:
    children = [
        int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()
        and _ppid(p) == pincal and b"ZMQWebSocketBridge" in _cmdline(p)
    ]  # fmt: skip
    assert len(children) == 1, children
    return children[0]


def _ppid(p: Path) -> int:
    try:
        return int(p.joinpath("stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return -1


def _cmdline(p: Path) -> bytes:
    try:
        return p.joinpath("cmdline").read_bytes()
    except OSError:
        return b""


def start_live(*extra: str) -> tuple[subprocess.Popen, int, str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "pincal.cli", "view", "wedge3", "--random", "2", "--live",
         *extra],
        env={**os.environ, "PYTHONPATH": str(ROOT)}, stdin=subprocess.PIPE,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stderr is not None
    deadline = time.monotonic() + 180
    line = ""
    while "meshcat viewer at" not in line:
        line = proc.stderr.readline()
        assert line or proc.poll() is None, "pincal view --live ended early"
        assert time.monotonic() < deadline
    url = re.search(r"http://\S+", line).group(0)  # type: ignore[union-attr]
    return proc, server_of(proc.pid), url


def gone(server: int, timeout: float = 10.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if not alive(server) and not listeners(server):
            return True
        time.sleep(0.2)
    return False


@needs_ss
@pytest.mark.slow
@pytest.mark.parametrize("how", ["enter", "SIGTERM", "SIGKILL"])
def test_live_server_listens_on_loopback_only_and_dies_with_pincal(how):
    proc, server, url = start_live()
    try:
        assert url.startswith("http://127.0.0.1:")
        socks = listeners(server)
        assert len(socks) >= 2, socks  # the web page and the command socket
        assert all(s.startswith("127.0.0.1:") for s in socks), socks  # not 0.0.0.0, not [::]
        if how == "enter":
            proc.communicate("\n", timeout=60)
            assert proc.returncode == 0
        else:
            proc.send_signal(getattr(signal, how))
            proc.wait(timeout=60)
        assert gone(server), f"server {server} still alive / listening: {listeners(server)}"
    finally:
        if proc.poll() is None:
            proc.kill()
        if alive(server):
            os.kill(server, signal.SIGKILL)


@pytest.mark.parametrize("host", ["::1", "localhost", "300.1.1.1"])
def test_live_host_must_be_an_ipv4_address(host):
    res = CliRunner().invoke(main, ["view", "wedge3", "--random", "2", "--live", "--host", host])
    assert res.exit_code == 1 and "Traceback" not in res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: VisualizationError: --host")
    assert "127.0.0.1 (loopback, the default)" in line


def test_live_help_says_loopback():
    res = CliRunner().invoke(main, ["view", "--help"])
    text = " ".join(res.output.split())
    assert "loopback interface only" in text and "--host" in text
