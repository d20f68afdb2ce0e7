"""Running a submission for grading without trusting it: its code in a kernel, the checks in the grader.

A check cell (``assert check_psnr(psnr)``) never runs in the student's kernel, where the
submission could have redefined ``check_psnr``, patched the module it comes from, installed an input
transformer or an exception handler that swallows the failure. :func:`run_graded` executes every
other cell in a fresh kernel (always the grader's ``python3``, whatever kernelspec the notebook
names), and each check cell, taken from the instructor's source, in the grader's own process: its
imports are the grader's, and every other name it uses (the student's function) is a
:class:`RemoteFunction`. Calling one sends the arguments to the kernel as data, the student's
function runs there, and its return value (and the arguments, so that a check can see whether they
were modified) come back as data: an ``.npz`` read with ``allow_pickle=False`` whose JSON structure
may name only numbers, strings, lists, tuples, dicts, arrays and cameras (:func:`encode`,
:func:`decode`). So the kernel can only give answers; whether they are right is decided where it
cannot reach. The check's printout and error become the check cell's outputs, scored by nbgrader's
rule as before.
"""
from __future__ import annotations

# The kernel imports this module for every call (answer_call): at the top only numpy, the standard library
# and two files of core that use nothing more (array_archive, files); nbformat and nbclient, which the
# grader's side needs, take a second to import.
import ast
import builtins
import contextlib
import io
import json
import os
import traceback
from pathlib import Path

import numpy as np

from ..core.array_archive import archive_bytes, array_node
from ..core.files import read_regular_bytes, write_bytes_atomic

__all__ = ["encode", "decode", "answer_call", "RemoteFunction", "StudentError", "run_graded", "check_imports"]


class StudentError(Exception):
    """What the student's function raised in its kernel (its type name and message), or why its answer
    could not be read."""


def _pack(value, arrays: list):
    if value is None or isinstance(value, (bool, str)):
        return value
    if type(value) is int:
        return value
    if type(value) is float:
        return {"float": repr(value)}
    if type(value).__module__ == "torch" and hasattr(value, "detach"):  # a tensor: its values
        value = value.detach().cpu().numpy()
    if isinstance(value, (np.ndarray, np.generic)):
        return array_node(value, arrays, lambda what: TypeError(f"{what} is not an answer the grader can read"))
    if type(value).__name__ == "Camera" and type(value).__module__ == "ddp_lite.core.camera":
        return {"camera": [_pack(np.asarray(value.K), arrays), _pack(np.asarray(value.cam_from_world), arrays),
                           int(value.width), int(value.height)]}
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise TypeError("a dict whose keys are not all strings is not an answer the grader can read")
        return {"dict": [[k, _pack(v, arrays)] for k, v in value.items()]}
    if isinstance(value, (list, tuple)):
        return {"tuple" if isinstance(value, tuple) else "list": [_pack(v, arrays) for v in value]}
    raise TypeError(f"a {type(value).__qualname__} is not an answer the grader can read "
                    f"(numbers, arrays, lists, tuples, dicts, strings)")


def encode(value) -> bytes:
    """``value`` (numbers, strings, None, arrays, tensors, lists, tuples, str-keyed dicts, cameras) as
    ``.npz`` bytes; TypeError for anything else."""
    arrays: list = []
    return archive_bytes("structure", _pack(value, arrays), arrays)


def _unpack(node, archive):
    if node is None or isinstance(node, (bool, str, int)):
        return node
    if not isinstance(node, dict) or len(node) != 1:
        raise ValueError(f"unexpected {type(node).__name__}")
    (tag, body), = node.items()
    if tag == "float" and isinstance(body, str):
        return float(body)
    if tag in ("array", "scalar") and type(body) is int:
        array = archive[f"a{body}"]
        return array[()] if tag == "scalar" else array
    if tag in ("list", "tuple") and isinstance(body, list):
        items = [_unpack(v, archive) for v in body]
        return items if tag == "list" else tuple(items)
    if tag == "dict" and isinstance(body, list) and all(isinstance(i, list) and len(i) == 2 and isinstance(i[0], str)
                                                        for i in body):
        return {k: _unpack(v, archive) for k, v in body}
    if tag == "camera" and isinstance(body, list) and len(body) == 4:
        from ..core.camera import Camera
        K, pose = _unpack(body[0], archive), _unpack(body[1], archive)
        return Camera(K, pose, body[2], body[3])
    raise ValueError(f"unexpected {tag!r}")


def decode(data: bytes):
    """The value :func:`encode` wrote; ValueError for anything else (no pickle is ever loaded)."""
    with np.load(io.BytesIO(data), allow_pickle=False) as archive:
        structure = json.loads(archive["structure"].tobytes().decode())
        return _unpack(structure, archive)


def answer_call(namespace: dict, name: str, folder) -> None:
    """Kernel side: call ``namespace[name]`` with the arguments (positional, keyword and, if given, the
    check's forbidden callables) in ``folder/args.npz``; write its return value and the arguments after
    the call, or what it raised, and the forbidden callables it called, to ``folder/answer.npz``."""
    folder = Path(folder)
    args, kwargs, *forbidden = decode((folder / "args.npz").read_bytes())
    seen: set = set()
    try:
        if forbidden:  # the check's forbidden callables: watched for while the function runs (own_work)
            from .own_work import call_watched
            value = call_watched(namespace[name], args, kwargs, tuple(forbidden[0]), seen)
        else:
            value = namespace[name](*args, **kwargs)
        data = encode({"value": [value], "args": list(args), "seen": sorted(seen)})
    except BaseException as error:  # the student's error is the answer: the grader reports it
        data = encode({"error": [type(error).__name__, str(error)], "seen": sorted(seen)})
    write_bytes_atomic(folder / "answer.npz", data)


class RemoteFunction:
    """A name of the student's kernel that the grader calls as a function; ``run(code)`` executes code in
    the kernel and returns None or why it failed."""

    def __init__(self, name: str, run, folder: Path):
        self.name, self._run, self._folder = name, run, folder

    def __call__(self, *args, **kwargs):
        return self.call_watched(args, kwargs, (), set())

    def call_watched(self, args, kwargs, forbidden, seen: set):
        """The call, with the forbidden callables (dotted names) it made in the kernel added to ``seen``."""
        args_file, answer_file = self._folder / "args.npz", self._folder / "answer.npz"
        answer_file.unlink(missing_ok=True)
        write_bytes_atomic(args_file, encode([list(args), kwargs] + ([list(forbidden)] if forbidden else [])))
        failure = self._run("from ddp_lite.interface.grading_kernel import answer_call as __ddp_answer\n"
                            f"__ddp_answer(globals(), {self.name!r}, {str(self._folder)!r})\ndel __ddp_answer")
        try:
            answer = decode(read_regular_bytes(answer_file, "the answer", links=False))  # the kernel's folder
        except Exception as error:
            raise StudentError(failure or f"no answer from {self.name} ({type(error).__name__})") from None
        if not isinstance(answer, dict):
            raise StudentError(f"{self.name} gave no readable answer")
        seen.update(str(name) for name in answer.get("seen", []) if isinstance(name, str))
        if "error" in answer:
            kind, message = answer["error"]
            raise StudentError(f"{kind}: {message}" if str(message).strip() else str(kind))
        for given, after in zip(args, answer.get("args", [])):  # a check may look at what the call did to its input
            if isinstance(given, np.ndarray) and isinstance(after, np.ndarray) and after.shape == given.shape:
                np.copyto(given, after, casting="unsafe")
        return answer["value"][0]


class _StudentNames(dict):
    """A check cell's names: what it binds itself, the grader's builtins, else the student's function."""

    def __init__(self, make):
        super().__init__()
        self._make = make

    def __missing__(self, name):
        if hasattr(builtins, name):
            raise KeyError(name)  # falls through to the builtins
        return self._make(name)


def check_imports(sources) -> list[str]:
    """The modules the check cells ``sources`` import: imported by the grader before any submission runs,
    so that a submission that edits files cannot change the checks the grader then loads."""
    modules = []
    for source in sources:
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Import):
                modules += [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules.append(node.module)
    return list(dict.fromkeys(modules))


def _run_check(cell, remote) -> None:
    """Execute the check cell's source here, with the student's names remote; its outputs as a cell's."""
    import nbformat
    stdout, stderr = io.StringIO(), io.StringIO()
    error = None
    namespace = _StudentNames(remote)
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            exec(compile(cell.source, "<check cell>", "exec"), {"__name__": "__grader_check__"}, namespace)
    except Exception as raised:  # the check's failure, an assert
        error = raised
    outputs = []
    for name, text in (("stdout", stdout.getvalue()), ("stderr", stderr.getvalue())):
        if text:
            outputs.append(nbformat.v4.new_output("stream", name=name, text=text))
    if error is not None:
        outputs.append(nbformat.v4.new_output("error", ename=type(error).__name__, evalue=str(error),
                                              traceback=traceback.format_exception_only(type(error), error)))
    cell.outputs = outputs


def run_graded(nb, is_check, workdir, env: dict, timeout: int):
    """Run ``nb`` (modified in place): the cells for which ``is_check(cell)`` is False in a fresh
    ``python3`` kernel started in ``workdir`` with environment ``env``, each check cell in this process
    against the kernel's state at that point (see the module docstring).

    Returns (the exception that stopped the run early or None, whether the kernel started)."""
    from nbclient import NotebookClient
    from nbclient.exceptions import DeadKernelError

    from jupyter_core.utils import ensure_async

    class GradingClient(NotebookClient):
        """At a cell's timeout the kernel is interrupted (the cell fails, the next ones run); if the cell
        is still running one more timeout later (its code swallowed the KeyboardInterrupt), the kernel is
        killed and the run stops there: the grader owns the clock, not the student's code."""
        interrupted = None

        async def _async_handle_timeout(self, timeout, cell=None):
            if self.interrupted is not cell:
                self.interrupted = cell
                return await super()._async_handle_timeout(timeout, cell)
            await ensure_async(self.km.shutdown_kernel(now=True))
            raise DeadKernelError(f"a cell ignored the interrupt at its {timeout} s timeout; the kernel was killed")

    nb.metadata.pop("kernelspec", None)  # the notebook's choice of kernel is the student's: not followed
    # A kernel's start can fail for a moment's reason: the TCP ports its manager picked taken by another
    # process before the kernel binds them ("Address already in use", "Kernel died before replying to
    # kernel_info"), which kernels starting side by side do now and then. No cell has run then: start again.
    for attempt in range(KERNEL_START_TRIES):
        stopped, started = _run_in_kernel(GradingClient, nb, is_check, workdir, env, timeout)
        if started or attempt + 1 == KERNEL_START_TRIES:
            return stopped, started


KERNEL_START_TRIES = 3


def _run_in_kernel(GradingClient, nb, is_check, workdir, env: dict, timeout: int):
    """One try of :func:`run_graded`: (the exception that stopped the run or None, whether the kernel started)."""
    import nbformat
    from jupyter_core.utils import run_sync
    from nbclient.exceptions import DeadKernelError

    # shut down "immediate" (killed, its process group with it): a graded kernel has nothing to save, and
    # a graceful shutdown waits for it to exit on its own
    client = GradingClient(nb, timeout=timeout, allow_errors=True, interrupt_on_timeout=True, kernel_name="python3",
                           shutdown_kernel="immediate", resources={"metadata": {"path": str(workdir)}})
    calls = Path(workdir) / ".grader-calls"
    calls.mkdir(exist_ok=True)

    dead: list = []  # what killed the kernel during a check: the check's later calls fail with it at once

    def run(code: str) -> str | None:
        if dead:  # (nbclient would take a second per call to find the kernel gone)
            raise DeadKernelError(str(dead[0]))
        helper = nbformat.v4.new_code_cell(code)
        nb.cells.append(helper)  # nbclient files a cell's outputs by its index: a cell of its own, dropped after
        try:
            client.execute_cell(helper, len(nb.cells) - 1, store_history=False)
        except DeadKernelError as error:
            dead.append(error)
            raise
        finally:
            nb.cells.pop()
        errors = [o for o in helper.outputs if o.get("output_type") == "error"]
        return f"{errors[0].ename}: {errors[0].evalue}" if errors else None

    stopped, started = None, False
    try:
        with client.setup_kernel(env=env):
            started = True
            for index, cell in enumerate(nb.cells):
                if cell.cell_type != "code":
                    continue
                if is_check(cell):
                    _run_check(cell, lambda name: RemoteFunction(name, run, calls))
                    cell.execution_count = index + 1
                    if not run_sync(client.km.is_alive)():
                        raise DeadKernelError("the kernel died during a check")
                else:
                    client.execute_cell(cell, index)
    except Exception as error:  # the kernel died or did not start: the cells after keep no count
        stopped = error
    return stopped, started
