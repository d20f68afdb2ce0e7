"""The forked kernels of `make test` (kernel_forkserver.py) against fresh ones: a notebook sees the same
working folder, environment, path and Matplotlib backend; an interrupt, a kill and a kernel's own exit reach
the kernel manager as a fresh kernel's would. Run where the session has a kernel server (`make test`)."""
import json
import os
import signal
import time

import pytest

from conftest import process_has_ended
from kernel_forkserver import SOCKET_VARIABLE

pytestmark = pytest.mark.skipif(SOCKET_VARIABLE not in os.environ, reason="no kernel server in this session (a run "
                                "of the notebooks starts one, as make test does, unless DDP_TEST_FRESH_KERNELS=1)")

PROBE = """import json, os, sys
import matplotlib.pyplot as plt
print(json.dumps({"pid": os.getpid(), "cwd": os.getcwd(), "path0": sys.path[0], "backend": plt.get_backend(),
                  "env": {k: os.environ.get(k) for k in ("DDP_PROBE", "OMP_NUM_THREADS", "MPLBACKEND")},
                  "argv0": os.path.basename(sys.argv[0]), "user_names": sorted(n for n in globals() if not n.startswith("_")),
                  "torch_loaded": "torch" in sys.modules}))"""


def _start(tmp_path, **env):
    from jupyter_client.manager import KernelManager

    kernel_env = {k: v for k, v in os.environ.items() if k not in ("MPLBACKEND",)}
    kernel_env.update(env)
    manager = KernelManager(kernel_name="python3")
    manager.start_kernel(cwd=str(tmp_path), env=kernel_env)
    client = manager.client()
    client.start_channels()
    client.wait_for_ready(timeout=60)
    return manager, client


def _run(client, code, timeout=30):
    printed = []
    reply = client.execute_interactive(code, timeout=timeout, output_hook=lambda msg: printed.append(
        msg["content"].get("text", "")) if msg["msg_type"] == "stream" else None)
    return reply["content"], "".join(printed)


def _message_for(get, msg_id, accept=lambda msg: True, timeout=20):
    """The first message from ``get`` (a channel's get_msg) answering ``msg_id`` that ``accept`` takes: a kernel
    that was slow to start has answered several kernel_info requests, whose replies wait on the channel first."""
    deadline = time.monotonic() + timeout
    while True:
        msg = get(timeout=max(0.1, deadline - time.monotonic()))
        if msg["parent_header"].get("msg_id") == msg_id and accept(msg):
            return msg


def _probe(tmp_path, **env):
    manager, client = _start(tmp_path, **env)
    try:
        _, printed = _run(client, PROBE)
        return json.loads(printed), manager.provisioner.process.pid
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)


def test_a_forked_kernel_shows_a_notebook_what_a_fresh_one_does(tmp_path):
    forked, launcher = _probe(tmp_path, DDP_PROBE="forked")
    # a variable the server may not set after the fork (read at start-up by some library): a fresh kernel
    fresh, fresh_launcher = _probe(tmp_path, DDP_PROBE="forked", KERNEL_SERVER_REFUSES="1")
    assert forked.pop("torch_loaded") and not fresh.pop("torch_loaded")  # the first was forked, the second not
    assert fresh.pop("pid") == fresh_launcher and forked.pop("pid") != launcher
    assert forked == fresh
    assert fresh["cwd"] == str(tmp_path) and fresh["env"]["DDP_PROBE"] == "forked"
    assert fresh["backend"] == "module://matplotlib_inline.backend_inline"  # ipykernel's default, MPLBACKEND unset


def test_an_interrupt_a_kill_and_an_exit_reach_the_kernel_manager(tmp_path):
    manager, client = _start(tmp_path)
    try:
        msg_id = client.execute("import time\nprint('looping', flush=True)\nwhile True:\n    time.sleep(0.05)")
        _message_for(client.get_iopub_msg, msg_id, lambda msg: "looping" in msg["content"].get("text", ""))
        manager.interrupt_kernel()  # SIGINT to the launcher's group
        reply = _message_for(client.get_shell_msg, msg_id)["content"]
        assert reply["status"] == "error" and reply["ename"] == "KeyboardInterrupt"
        _, printed = _run(client, "import os\nprint(os.getpid())")
        kernel = int(printed)
        assert kernel != manager.provisioner.process.pid  # a fork, behind its launcher
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)  # SIGKILL to the launcher's group
    for _ in range(100):
        if process_has_ended(kernel):
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"the kernel {kernel} outlived its launcher's kill")

    for code, status in (("os._exit(3)", 3), ("os.kill(os.getpid(), signal.SIGTERM)", -signal.SIGTERM)):
        manager, client = _start(tmp_path)
        try:
            client.execute(f"import os, signal\n{code}")
            assert manager.provisioner.process.wait(timeout=20) == status  # the kernel's end, as a fresh one's
        finally:
            client.stop_channels()
            manager.shutdown_kernel(now=True)
