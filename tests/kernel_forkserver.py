"""Notebook kernels for the tests, forked from one process that has already imported the notebooks' stack.

`make test` starts about thirty kernels in its workers: nbval's run of each notebook, the student copies, the
classroom's runs. A fresh kernel spends 4-5 CPU-s importing torch, SciPy, Matplotlib and the kit before its
first cell does anything (2 cores: about a minute of the run). Here one server process imports all of that
once and forks a kernel per request: the fork starts where a fresh kernel would be after its imports, with
the environment, working folder and standard streams of the kernel that was asked for, and runs the same
``ipykernel_launcher`` main. The notebook's own namespace is new, as in a fresh kernel (a missing import
still fails); only ``sys.modules`` is warm.

What the kernel manager sees stays a process of its own: jupyter_client launches a small launcher (this file
run with ``-I -S``: standard library only, ~20 ms) which asks the server for a kernel and then stands in for
it: the signals its process group gets (interrupt, terminate) go to the kernel's group, its exit status is
the kernel's, and the kernel kills itself (and what it started) the moment the launcher dies (the kernel
manager's SIGKILL). Where the server cannot give an exact stand-in, the launcher becomes a fresh kernel
(``exec``, same pid):

- the requested environment differs from the server's in a variable that may be read at start-up (threads,
  paths, locale, ...): only ``DDP_*``, ``PYTEST_*``, ``JPY_*``, ``MPLBACKEND``, the temporary folder, the
  shell's ``PWD``, the terminal's size and four that libraries set when a test imports them (none of which
  is read at start-up here) may differ, and ``LD_LIBRARY_PATH`` by folders that hold no library (OpenCV's
  import adds one). They are set in the fork before the kernel starts;
  ``MPLBACKEND`` is applied to Matplotlib's rcParams, as its import would, and the temporary folder is
  looked up again;
- no server (``DDP_TEST_FRESH_KERNELS=1``, or no ``os.pidfd_open``: Linux >= 5.3 only).

``DDP_TEST_KERNEL_SERVER_DEBUG=1`` prints each refusal, with the variables that differed.

Only the kernels a test process starts through jupyter_client are redirected (``redirect_kernel_launches``,
called by conftest.py in each process that runs tests); ``grade()``'s kernels, started by its supervised
children, and every ``ddp-lite`` command a test runs stay fresh processes, as a user's are.

Usage (conftest.py): ``server = start_server(notebooks_dir)`` in the process that starts the workers (it
exports the socket's path), ``redirect_kernel_launches()`` in each process that runs tests,
``server.stop()`` at the end.
"""
import json
import os
import select
import signal
import socket
import struct
import sys

SOCKET_VARIABLE = "DDP_TEST_KERNEL_SERVER"
# set in the fork before the kernel starts; any other difference from the server's environment gets a fresh kernel
RUNTIME_PREFIXES = ("DDP_", "PYTEST_", "JPY_")
RUNTIME_NAMES = ("MPLBACKEND", "TMPDIR", "TEMP", "TMP", "PWD", "OLDPWD", "COLUMNS", "LINES",
                 # set in a test process by libraries it has imported, read by none at start-up here: Intel's OpenMP
                 # and TCMalloc's (Open3D, scikit-learn and joblib set them) are not in the stack; torch's compiler
                 # reads its cache folder when it compiles
                 "KMP_DUPLICATE_LIB_OK", "KMP_INIT_AT_FORK", "TCM_ENABLE", "TORCHINDUCTOR_CACHE_DIR")
FORWARDED_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2")


def _send(conn, message: dict, fds=()):
    """One length-prefixed JSON message, and ``fds`` (file descriptors) with it."""
    data = json.dumps(message).encode()
    framed = struct.pack("!I", len(data)) + data
    if fds:
        socket.send_fds(conn, [framed], list(fds))
    else:
        conn.sendall(framed)


def _receive(conn, max_fds=0):
    """One length-prefixed JSON message (and up to ``max_fds`` file descriptors); None when the peer closed."""
    head, fds, _, _ = socket.recv_fds(conn, 4, max_fds) if max_fds else (conn.recv(4), [], 0, None)
    if len(head) < 4:
        return None, fds
    size, = struct.unpack("!I", head)
    data = b""
    while len(data) < size:
        chunk = conn.recv(size - len(data))
        if not chunk:
            return None, fds
        data += chunk
    return json.loads(data), fds


# --- the launcher: what jupyter_client starts, in place of `python -m ipykernel_launcher` ------------------

def launch(socket_path: str, kernel_args: list[str]):
    """Ask the server for a kernel run with ``kernel_args`` and stand in for it until it ends; without a
    server, or when it refuses, become a fresh kernel."""
    try:
        conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        conn.connect(socket_path)
        _send(conn, {"args": kernel_args, "cwd": os.getcwd(), "env": dict(os.environ), "launcher": os.getpid()},
              fds=(0, 1, 2))
        reply, _ = _receive(conn)
    except OSError:
        reply = None
    if not reply or "pid" not in reply:
        os.execv(sys.executable, [sys.executable, "-m", "ipykernel_launcher", *kernel_args])
    kernel = reply["pid"]  # the leader of its own process group

    def forward(signum, _frame):
        try:
            os.killpg(kernel, signum)
        except ProcessLookupError:
            pass

    for name in FORWARDED_SIGNALS:
        signal.signal(getattr(signal, name), forward)
    ended, _ = _receive(conn)  # blocks until the kernel has ended (a forwarded signal does not end the wait)
    status = ended["status"] if ended else 1
    if status < 0:  # the kernel was killed by signal -status: so is its stand-in
        signal.signal(-status, signal.SIG_DFL)
        os.kill(os.getpid(), -status)
    os._exit(status)


# --- the server: imports once, forks a kernel per request -------------------------------------------------

def _preload(notebooks_dir):
    """Import what a kernel imports before its first cell, and every module the notebooks' cells import.
    Not ``matplotlib_inline``: its import wires itself into the IPython shell it finds, and here there is none."""
    import ast
    import importlib

    names = {"ipykernel.kernelapp", "ipykernel.ipkernel", "ipykernel.zmqshell", "debugpy"}
    for path in sorted(os.listdir(notebooks_dir)):
        if not path.endswith(".ipynb"):
            continue
        with open(os.path.join(notebooks_dir, path), encoding="utf-8") as f:
            cells = json.load(f).get("cells", [])
        for cell in cells:
            if cell.get("cell_type") != "code":
                continue
            source = "".join(cell.get("source", ""))
            lines = [line for line in source.splitlines() if not line.lstrip().startswith(("%", "!"))]
            try:
                tree = ast.parse("\n".join(lines))
            except SyntaxError:
                continue
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    names.update(alias.name for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    names.add(node.module)
    # torch, and what imports it, last: in a fresh checkout nothing is compiled yet, and the test workers import
    # torch first, at the same time; by the time the server comes to it, they have written its bytecode
    def after_torch(name):
        return name.split(".")[0] in ("torch", "ddp_lite", "data_fetch"), name.split(".")[0] != "torch", name

    for name in sorted(names, key=after_torch):
        if not name.startswith("matplotlib_inline"):
            try:
                importlib.import_module(name)
            except Exception:  # a module a notebook imports inside a try, or an exercise's: the kernel will say
                pass


def _library_folders(value) -> list:
    """The entries of an LD_LIBRARY_PATH that hold a shared library: the only ones the loader can take one from."""
    def holds_one(folder):
        try:
            return any(".so" in name for name in os.listdir(folder))
        except OSError:
            return False
    return [folder for folder in (value or "").split(":") if folder and holds_one(folder)]


def _differences(env: dict, own_env: dict) -> list:
    """The variables in which a kernel's requested environment differs from the server's in a way the fork
    cannot reproduce. LD_LIBRARY_PATH counts by the folders that hold libraries: OpenCV's import adds its own
    (`lib64` beside site-packages) to the variable, in every process that imports it, where it holds none."""
    differing = [name for name in set(env) | set(own_env) if env.get(name) != own_env.get(name)
                 and not name.startswith(RUNTIME_PREFIXES) and name not in RUNTIME_NAMES]
    if "LD_LIBRARY_PATH" in differing and \
            _library_folders(env.get("LD_LIBRARY_PATH")) == _library_folders(own_env.get("LD_LIBRARY_PATH")):
        differing.remove("LD_LIBRARY_PATH")
    return sorted(differing)


def _start_kernel(request, fds):
    """In the fork: become the kernel that was asked for. Never returns."""
    status = 1
    try:
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
            os.close(fd)
        os.setsid()  # a process group of its own: what the launcher forwards, and what dies with it
        for name in ("SIGTERM", "SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2", "SIGCHLD"):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        try:
            watched = os.pidfd_open(request["launcher"])
        except ProcessLookupError:
            os._exit(1)

        def die_with_the_launcher():
            select.select([watched], [], [])
            os.killpg(0, signal.SIGKILL)

        import threading
        threading.Thread(target=die_with_the_launcher, daemon=True, name="kernel-launcher-watch").start()
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        import tempfile
        tempfile.tempdir = None  # read TMPDIR again, as a fresh process would
        import importlib.util
        sys.argv = [importlib.util.find_spec("ipykernel_launcher").origin, *request["args"]]
        from ipykernel.kernelapp import IPKernelApp

        # its default was read from the environment when the server imported it
        app = IPKernelApp.instance(parent_handle=int(os.environ.get("JPY_PARENT_PID") or 0))
        app.initialize(request["args"])  # sets MPLBACKEND to the inline backend where the request did not set one
        import matplotlib
        if os.environ.get("MPLBACKEND"):  # what importing Matplotlib does with it; it was imported before
            matplotlib.rcParams["backend"] = os.environ["MPLBACKEND"]
        app.start()
        status = 0
    except SystemExit as stop:
        status = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    except BaseException:
        import traceback
        traceback.print_exc()
    finally:
        try:
            import atexit
            atexit._run_exitfuncs()
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(status)


def serve(socket_path: str, notebooks_dir: str):
    """Import, then answer requests until the parent closes our standard input (or dies)."""
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(socket_path)
    listener.listen(64)  # a launcher that comes during the imports waits for them, rather than import them too
    own_env = dict(os.environ)  # as the loader and the libraries found it at start-up
    del sys.path[0]  # this file's folder (tests/, whose data_fetch/ would shadow the package); a kernel's has no such entry
    _preload(notebooks_dir)
    if os.environ.get("DDP_TEST_KERNEL_SERVER_DEBUG"):
        import time
        print(f"kernel server: ready, {time.process_time():.1f} CPU-s of imports", file=sys.stderr, flush=True)
    waiting = {}  # the pidfd of a running kernel -> (its pid, the connection its launcher waits on)
    while True:
        readable, _, _ = select.select([listener, sys.stdin, *waiting], [], [])
        if sys.stdin in readable and not sys.stdin.buffer.read1(1):
            break
        for fd in [r for r in readable if isinstance(r, int)]:
            pid, conn = waiting.pop(fd)
            _, wait_status = os.waitpid(pid, 0)
            os.close(fd)
            code = os.waitstatus_to_exitcode(wait_status)
            try:
                _send(conn, {"status": code})
            except OSError:
                pass
            conn.close()
        if listener not in readable:
            continue
        conn, _ = listener.accept()
        try:
            request, fds = _receive(conn, max_fds=3)
        except (OSError, ValueError):  # a launcher gone, or not one of ours
            conn.close()
            continue
        differing = _differences((request or {}).get("env", {}), own_env)
        if os.environ.get("DDP_TEST_KERNEL_SERVER_DEBUG") and differing:
            print("kernel server: refused, differs:", differing, file=sys.stderr, flush=True)
        if request is None or len(fds) != 3 or differing:
            try:
                _send(conn, {"refused": differing or "malformed request"})
            except OSError:
                pass
            for fd in fds:
                os.close(fd)
            conn.close()
            continue
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:
            listener.close()
            conn.close()
            for fd in waiting:
                os.close(fd)
            for _, other in waiting.values():
                other.close()
            _start_kernel(request, fds)
        for fd in fds:
            os.close(fd)
        waiting[os.pidfd_open(pid)] = (pid, conn)
        try:
            _send(conn, {"pid": pid})
        except OSError:  # the launcher is gone: the kernel sees that too, and ends
            pass
    for pid, conn in waiting.values():  # the test run is over: what is left goes with it
        try:
            os.killpg(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    os._exit(0)  # nothing to save: tearing down an interpreter that holds torch would keep the run waiting a second


# --- the test side -----------------------------------------------------------------------------------------

class Server:
    def __init__(self, process, folder):
        self.process, self.folder = process, folder

    def stop(self):
        import shutil
        import subprocess

        self.process.stdin.close()  # the server ends its loop, kills the kernels left, and exits
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
        shutil.rmtree(self.folder, ignore_errors=True)


def _has_pidfds() -> bool:
    """Linux >= 5.3 with Python >= 3.9: the server and its kernels watch processes through pidfds."""
    try:
        os.close(os.pidfd_open(os.getpid()))
        return True
    except (AttributeError, OSError):
        return False


def start_server(notebooks_dir):
    """Start the server (it imports in the background) and export its socket's path for the test processes;
    None where kernels stay fresh (``DDP_TEST_FRESH_KERNELS=1``, or no ``os.pidfd_open``)."""
    import subprocess
    import tempfile

    if os.environ.get("DDP_TEST_FRESH_KERNELS") or not _has_pidfds():
        os.environ.pop(SOCKET_VARIABLE, None)
        return None
    folder = tempfile.mkdtemp(prefix="ddp-kernels-")
    socket_path = os.path.join(folder, "server")
    env = {name: value for name, value in os.environ.items() if name != SOCKET_VARIABLE}
    process = subprocess.Popen([sys.executable, __file__, "serve", socket_path, str(notebooks_dir)],
                               stdin=subprocess.PIPE, env=env)
    os.environ[SOCKET_VARIABLE] = socket_path
    return Server(process, folder)


def redirect_kernel_launches():
    """In a process that runs tests: the `python -m ipykernel_launcher` kernels that jupyter_client launches
    from this process go through the launcher (and the server), where a server was started."""
    if SOCKET_VARIABLE not in os.environ:
        return
    from jupyter_client.provisioning import local_provisioner

    launch_kernel = local_provisioner.launch_kernel
    if getattr(launch_kernel, "redirected", False):
        return
    test_process = os.getpid()

    def launch_through_the_server(cmd, **kwargs):
        socket_path = (kwargs.get("env") or os.environ).get(SOCKET_VARIABLE)
        # not in a fork of the test process: grade() grades each hand-in in one, and its kernels stay fresh
        if socket_path and os.getpid() == test_process and list(cmd[:3]) == [sys.executable, "-m", "ipykernel_launcher"]:
            cmd = [sys.executable, "-I", "-S", os.path.abspath(__file__), "launch", socket_path, *cmd[3:]]
        return launch_kernel(cmd, **kwargs)

    launch_through_the_server.redirected = True
    local_provisioner.launch_kernel = launch_through_the_server


if __name__ == "__main__":
    if sys.argv[1] == "launch":
        launch(sys.argv[2], sys.argv[3:])
    elif sys.argv[1] == "serve":
        serve(sys.argv[2], sys.argv[3])
