"""`make lab` starts a JupyterLab that serves every numbered notebook (real server, loopback only).

The command line comes from `make -s lab-command`, the very one `make lab` runs; the test adds
only its own token and --no-browser (the machine running the tests may have a display).
"""
import json
import os
import secrets
import shlex
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
START_TIMEOUT = 20.0  # seconds until the server answers; stopping it takes at most 5 more


def _free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _lab_command(port):
    # The test may itself run under `make test`: drop the outer make's flags so they do not leak in.
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL", "GNUMAKEFLAGS")}
    out = subprocess.run(["make", "-s", "--no-print-directory", "-C", str(REPO), "lab-command",
                          f"PORT={port}", "IP=127.0.0.1"],
                         env=env, capture_output=True, text=True, timeout=10, check=True).stdout
    return shlex.split(out.strip())


def _get(url, token):
    request = urllib.request.Request(url, headers={"Authorization": f"token {token}"})
    with urllib.request.urlopen(request, timeout=5) as response:
        return response.status, response.read()


def test_make_lab_serves_every_notebook(tmp_path):
    port, token = _free_port(), secrets.token_hex(16)
    argv = _lab_command(port)
    # `make lab` keeps the notebooks' fits in a cache folder of the checkout (a re-run reads them back)
    assert argv[:2] == ["env", f"DDP_CACHE={REPO.resolve() / '.cache' / 'fits'}"], argv[:2]
    jupyter = REPO / argv[2]
    assert jupyter.is_file(), f"`make lab` would run {jupyter}, which does not exist: run `make install` first"
    assert jupyter.parent.resolve() == Path(sys.executable).parent.resolve(), (
        f"`make lab` runs {jupyter}, but this test runs under {sys.executable}: run it via `make test`")
    notebooks = sorted(p.name for p in (REPO / "notebooks").glob("[0-9][0-9]_*.ipynb"))
    assert notebooks, "no notebooks/NN_*.ipynb found"

    argv += [f"--IdentityProvider.token={token}", "--no-browser", "--ServerApp.port_retries=0"]
    env = dict(os.environ, JUPYTER_RUNTIME_DIR=str(tmp_path / "runtime"))
    log_path = tmp_path / "lab.log"
    base = f"http://127.0.0.1:{port}"
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(argv, cwd=REPO, env=env, stdin=subprocess.DEVNULL, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while True:
            assert proc.poll() is None, (
                f"`{shlex.join(argv)}` exited with {proc.returncode}:\n{log_path.read_text()[-3000:]}")
            try:
                _get(f"{base}/api/status", token)
                break
            except (urllib.error.URLError, ConnectionError, TimeoutError):
                assert time.monotonic() < deadline, (
                    f"no answer on {base} after {START_TIMEOUT:.0f} s:\n{log_path.read_text()[-3000:]}")
                time.sleep(0.25)

        status, body = _get(f"{base}/api/contents", token)  # `make lab` serves notebooks/ as root
        assert status == 200
        listed = {item["name"] for item in json.loads(body)["content"]}
        assert set(notebooks) <= listed, f"not served: {sorted(set(notebooks) - listed)}"

        status, body = _get(f"{base}/lab", token)
        assert status == 200 and b"<html" in body.lower()

        # The URL to open is printed with its token (a token we chose is shown as "...").
        assert f"{base}/lab?token=" in log_path.read_text()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        # Anything the server started (kernels, terminals) shares its process group.
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
