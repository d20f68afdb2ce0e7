"""benchmarks/suite_cpu.py: each process below the command found and its CPU time read, kinds named from the
command line and the parent, and the command's exit status passed on."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import suite_cpu  # noqa: E402

WORKER = "/x/.venv/bin/python -u -c import sys;exec(eval(sys.stdin.readline()))"


@pytest.mark.parametrize("command, parent, kind", [
    ("/x/.venv/bin/python -m pytest tests -n 2", "shell", "pytest controller"),
    (WORKER, "pytest controller", "pytest worker"),
    (WORKER, "pytest worker", "grader child"),  # a fork keeps the worker's command line
    ("/x/.venv/bin/python -m ipykernel_launcher -f /tmp/k.json", "pytest worker", "kernel (a worker's)"),
    ("/x/.venv/bin/python -m ipykernel_launcher -f /tmp/k.json", "grader child", "kernel (a grader child's)"),
    ("/x/.venv/bin/python /x/tests/kernel_forkserver.py serve /tmp/k/server /x/notebooks", "pytest controller",
     "kernel server"),
    ("/x/.venv/bin/python /x/tests/kernel_forkserver.py serve /tmp/k/server /x/notebooks", "kernel server",
     "kernel (a worker's, forked)"),  # a fork keeps the server's command line
    ("/x/.venv/bin/python -I -S /x/tests/kernel_forkserver.py launch /tmp/k/server -f /tmp/k.json", "pytest worker",
     "kernel (a worker's)"),
    ("/x/.venv/bin/python /x/.venv/bin/ddp-lite complete --rgb a.png", "pytest worker", "ddp-lite command"),
    ("/x/.venv/bin/python -c from multiprocessing.spawn import spawn_main", "pytest worker", "dask / multiprocessing"),
    ("/x/.venv/bin/python -m pip wheel --no-deps .", "pytest worker", "installer (pip, uv)"),
    ("make test", None, "shell"),
    ("/bin/sh -c echo '.venv/bin/python -m pytest tests'; .venv/bin/python -m pytest tests", "shell", "shell"),
    ("/usr/bin/git status", "pytest worker", "other"),
    ("/x/.venv/bin/python /tmp/pytest-of-root/pytest-3/test_x0/script.py", "pytest worker", "other"),
])
def test_each_process_is_named_by_its_command_line_and_parent(command, parent, kind):
    assert suite_cpu.process_kind(command, parent) == kind


def test_a_grandchilds_cpu_time_is_read_and_the_exit_status_passed_on():
    # the grandchild spins until its own clock says 0.6 s of CPU: the sampler must see nearly all of it (it loses
    # at most the last interval, 0.05 s here), under the child that started it
    spin = "import time\nwhile time.process_time() < 0.6:\n    pass"
    child = f"import subprocess, sys\nsubprocess.run([sys.executable, '-c', {spin!r}])\nsys.exit(3)"
    result = suite_cpu.measure([sys.executable, "-c", child], interval=0.05)
    assert result["returncode"] == 3
    processes = result["processes"]
    spinners = [p for p in processes.values() if p["parent"] in processes]  # the one process below the child
    assert len(spinners) == 1 and 0.5 <= spinners[0]["cpu_s"] <= 0.9, result["processes"]
    assert 0 <= result["idle_s"] and len(result["idle_by_tenth"]) == 10
    printed = suite_cpu.report(result)
    assert "other" in printed and "exit status 3" in printed


def test_a_bad_interval_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as stop:
        suite_cpu.main(["--interval", "0", "--command", "true"])
    assert stop.value.code == 2 and "--interval" in capsys.readouterr().err
