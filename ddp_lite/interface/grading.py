"""The grader: run hand-ins at ``ci`` and score each test cell, with the grader kept out of reach.

- :func:`grade_notebook`: one submission against its source notebook; the submission's cells run in
  a kernel of its own, each check in the grader, calling the student's functions in that kernel with
  data in and data out (:mod:`ddp_lite.interface.grading_kernel`);
- :func:`grade`: every student folder, hand-ins matched to the source notebooks by name
  (:func:`match_submissions`), each read once into a private copy before any of them runs.

A test cell scores its points when it ran without an error and printed nothing on stderr
(nbgrader's rule), and 0 when it failed, timed out, or never ran because the kernel died first.
What is not the student's doing (no kernel starts, the feedback cannot be written) stops the
grading with an error (:class:`GradingStopped`) instead of scoring anyone 0. What is done with the
scores afterwards (points given by hand, tables, CSV, feedback) is :mod:`ddp_lite.interface.grades`.
"""
from __future__ import annotations

import contextlib
import copy
import ctypes
import hashlib
import hmac
import json
import os
import re
import secrets
import shutil
import signal
import stat
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import nbformat

from ..core.files import read_regular_bytes, regular_file, write_bytes_atomic
from ..core.outpaths import check_output_folder
from ..core.printable import printable as shown
from .classroom import (exercises, nbgrader_meta, read_notebook, read_sources, source_notebooks, student_copy,
                        write_notebook)
from .source_rules import check_source, read_source
from .grading_kernel import check_imports, run_graded

__all__ = ["GradingStopped", "Score", "grade_notebook", "grade", "match_submissions"]

DISK_QUOTA = 1 << 30  # bytes one hand-in may write to disk while it runs (its folder, the temporary folder)
STATUSES = ("pass", "fail", "not run", "missing", "unreadable", "answered", "blank", "graded", "tampered")


# The modules a hand-in's grading (a forked child of the grader) uses: imported by the grader before any
# submission runs, so that no child loads them from files an earlier submission could have edited.
_GRADER_MODULES = ("nbgrader.preprocessors", "nbgrader.utils", "nbclient", "nbclient.exceptions",
                   "jupyter_client.manager", "jupyter_core.utils", "ddp_lite.interface.own_work")


class GradingStopped(RuntimeError):
    """What stops the grading instead of scoring a student 0: it is not the student's doing (no kernel
    starts, the grader's own copy of a hand-in changed)."""


@dataclass
class Score:
    """One exercise of one student: an autograded check or a hand-graded answer."""
    student: str
    notebook: str  # file stem, e.g. "01_deep_image_prior"
    exercise: str  # "01.2": notebook number, exercise number
    grade_id: str
    kind: str  # "auto" or "manual"
    points: float  # scored (autograded) or 0 until a person grades it (manual)
    max_points: float
    status: str  # one of STATUSES


def _check_ids(source) -> set:
    """grade_ids of the source's autograded check cells (locked, graded, not a solution)."""
    return {nbgrader_meta(c)["grade_id"] for c in source.cells
            if nbgrader_meta(c).get("grade") and not nbgrader_meta(c).get("solution") and c.cell_type == "code"}


def grade_notebook(submission, source, student: str = "", timeout: int = 600, profile: str = "ci",
                   workdir=None, name: str | None = None, executed=None) -> list[Score]:
    """Score one submitted notebook against its source notebook (both NotebookNodes or paths;
    ``name``, the notebook's file stem such as "01_deep_image_prior", defaults to the source's).
    ``executed``: where to write the executed notebook with its outputs (feedback), if given.
    ``workdir``: the kernel's working folder (default: a new temporary folder, removed afterwards).

    The test cells are taken from the source (matched by ``grade_id``), so an edited or deleted check
    cannot pass; a missing solution cell just fails its check. The student's cells run in a fresh
    kernel; each check cell runs in this process and calls the student's functions in that kernel
    (:mod:`ddp_lite.interface.grading_kernel`), so nothing the submission does in its kernel changes a
    check. ``submission=None`` scores a notebook that was not handed in: every exercise 0, status "missing".
    """
    if not isinstance(source, nbformat.NotebookNode):
        name = name or Path(source).stem
        source = read_source(source)
    if not name:
        raise ValueError("name: give the notebook's file stem when source is a NotebookNode")
    check_source(source, name)
    expected = exercises(source)
    if submission is None:
        return [Score(student, name, f"{name[:2]}.{n}", m["grade_id"], "manual" if m.get("solution") else "auto",
                      0.0, float(m["points"]), "missing") for n, m in expected]
    if profile not in ("ci", "class", "paper"):
        raise ValueError(f"profile must be 'ci', 'class' or 'paper', got {profile!r}")
    if not (isinstance(timeout, int) and timeout > 0):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    nb = read_notebook(submission) if not isinstance(submission, nbformat.NotebookNode) else copy.deepcopy(submission)
    locked = {nbgrader_meta(c)["grade_id"]: c for c in student_copy(source, name).cells
              if nbgrader_meta(c).get("locked") and nbgrader_meta(c).get("grade_id")}
    for index, cell in enumerate(nb.cells):
        grade_id = nbgrader_meta(cell).get("grade_id")
        if grade_id in locked:  # nbgrader's OverwriteCells, from the source instead of a database
            nb.cells[index] = copy.deepcopy(locked[grade_id])
    checks = _check_ids(source)
    for cell in nb.cells:  # "not run" stays visible afterwards
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    env = {**os.environ, "DDP_PROFILE": profile, "MPLBACKEND": "Agg"}
    # each notebook runs its own recipe, as a student with nothing set runs it (kit; notebook 09 photo),
    # whatever the grader's shell exports; no path to the grader's folder is handed to the submission
    for variable in ("DDP_RECIPE", "PWD", "OLDPWD"):
        env.pop(variable, None)
    with contextlib.ExitStack() as stack:
        if workdir is None:
            workdir = stack.enter_context(tempfile.TemporaryDirectory(prefix="ddp-grade-"))
        own_temporary = Path(workdir) / "tmp"  # the kernel's temporary files stay in its folder, removed with it
        own_temporary.mkdir(mode=0o700, exist_ok=True)
        env.update({variable: str(own_temporary) for variable in ("TMPDIR", "TEMP", "TMP")})
        stopped, started = run_graded(nb, lambda c: nbgrader_meta(c).get("grade_id") in checks, workdir, env, timeout)
    if not started:
        # the kernel did not start: the machine's doing, not the student's (whatever the notebook names
        # as its kernel, the grader starts its own python3)
        raise GradingStopped(f"no cell of {name} ran: the kernel did not start ({type(stopped).__name__}: "
                           f"{stopped}); fix the environment and grade again") from stopped
    if isinstance(executed, list):  # the supervisor's way of getting it back
        executed.append(nb)
    elif executed is not None:
        write_notebook(nb, executed)

    from nbgrader.utils import determine_grade
    graded = {nbgrader_meta(c)["grade_id"]: c for c in nb.cells if nbgrader_meta(c).get("grade")}
    scores = []
    for number, meta in expected:
        kind = "manual" if meta.get("solution") else "auto"
        label = f"{name[:2]}.{number}"
        cell = graded.get(meta["grade_id"])
        if cell is None:
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, float(meta["points"]), "missing"))
            continue
        if kind == "manual":
            points, maximum = determine_grade(cell)  # 0 if unchanged from the student copy, None if answered
            status = "blank" if points == 0 else "answered"
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, maximum, status))
        elif cell.execution_count is None:
            scores.append(Score(student, name, label, meta["grade_id"], kind, 0.0, float(meta["points"]), "not run"))
        else:
            points, maximum = determine_grade(cell)
            scores.append(Score(student, name, label, meta["grade_id"], kind, float(points), maximum,
                                "pass" if points == maximum else "fail"))
    return scores


# What a browser, a file manager or Jupyter makes of a file name on a second download or a duplicate:
# "01_x (1).ipynb", "01_x(1).ipynb", "Copy of 01_x.ipynb", "01_x-Copy1.ipynb", "01_x - Copy (2).ipynb"
# (Windows), "01_x.ipynb.ipynb", and any of them in another case ("01_X.IPYNB").
_RENAMED = re.compile(r"^(?:Copy of )?(?P<stem>.+?)(?:\.ipynb)?(?: ?\(\d+\)|-Copy\d*| - Copy(?: \(\d+\))?)?\.ipynb$",
                      re.IGNORECASE)


def notebook_files(folder: Path) -> list[Path]:
    """A student's notebooks: every ``.ipynb`` under ``folder`` whatever the suffix's case, checkpoints left out."""
    return sorted(p for p in folder.rglob("*") if p.suffix.lower() == ".ipynb" and ".ipynb_checkpoints" not in p.parts)


def match_submissions(files, names) -> tuple[dict, list[str], list]:
    """Match handed-in notebook files to source notebook names.

    Args:
        files: the student's ``.ipynb`` paths.
        names: the source notebooks' file names ("01_deep_image_prior.ipynb", ...).

    Returns:
        (``{name: path}``, notes on renamed files taken for a source, the files matched to nothing).
        The exact name wins; else a renamed copy ("01_x (1).ipynb", "Copy of 01_x.ipynb",
        "01_x-Copy1.ipynb", "01_x - Copy.ipynb", another case), the most recently modified one when
        there are several.
    """
    files = [Path(f) for f in files]
    matched, notes = {}, []
    for name in names:
        exact = [f for f in files if f.name == name]
        if exact:
            matched[name] = exact[0]
            continue
        renamed = [f for f in files if (m := _RENAMED.match(f.name)) and (m.group("stem") + ".ipynb").lower() == name.lower()]
        if renamed:
            matched[name] = max(renamed, key=lambda f: (f.stat().st_mtime, f.name))
            notes.append(f"graded {matched[name].name!r} as {name}"
                         + (f" (the newest of {len(renamed)} copies)" if len(renamed) > 1 else ""))
    used = set(matched.values())
    return matched, notes, [f for f in files if f not in used]


def _inside(path: Path, folder: Path) -> bool:
    """``path`` resolves to a place inside ``folder`` (no link out of it on the way)."""
    real, home = os.path.realpath(path), os.path.realpath(folder)
    return os.path.commonpath([real, home]) == home


class _Snapshot:
    """The hand-ins and source notebooks as read before any submission runs, kept where no submission can
    reach them: in one temporary file that has no name on disk (``tempfile.TemporaryFile``: nothing to find,
    replace with a FIFO or link elsewhere), in a grader that other processes of its user cannot open through
    ``/proc`` (:func:`_undumpable`), each copy's SHA-256 in memory. ``bytes(path)`` reads a copy back and
    checks it against its hash; :meth:`restore` writes a changed original back from it."""

    def __init__(self, paths):
        self.file = tempfile.TemporaryFile(prefix="ddp-grade-copies-")
        self.where: dict = {}  # path: (offset, length, SHA-256)
        offset, fd = 0, self.file.fileno()
        for path in paths:
            try:  # a link (no hand-in: writing back would put a file in its place), a FIFO, a folder: never read
                data = read_regular_bytes(path, "notebook", links=False)
            except (OSError, ValueError):
                continue
            view = memoryview(data)
            while view:
                view = view[os.pwrite(fd, view, offset + len(data) - len(view)):]
            self.where[Path(path)] = (offset, len(data), hashlib.sha256(data).hexdigest())
            offset += len(data)

    def __contains__(self, path) -> bool:
        return Path(path) in self.where

    def close(self) -> None:
        self.file.close()

    def bytes(self, path) -> bytes:
        offset, length, digest = self.where[Path(path)]
        chunks, done = [], 0
        while done < length:
            chunk = os.pread(self.file.fileno(), length - done, offset + done)
            if not chunk:
                break
            chunks.append(chunk)
            done += len(chunk)
        data = b"".join(chunks)
        if hashlib.sha256(data).hexdigest() == digest:
            return data
        with contextlib.suppress(OSError, ValueError):  # the copy was reached (root, or no Linux): the original?
            data = read_regular_bytes(path, "notebook", links=False)
            if hashlib.sha256(data).hexdigest() == digest:
                os.pwrite(self.file.fileno(), data, offset)
                return data
        raise GradingStopped(f"the grader's own copy of {shown(path)} and the file itself changed during grading (a "
                             f"submission reached both); grade again, in an account of its own")

    def restore(self) -> list[str]:
        """Write back every original whose bytes differ from what was read (or that is gone, or was replaced
        by a link, a folder, a FIFO or any other special file); what was done, one line per file."""
        done = []
        for path, (_, _, digest) in self.where.items():
            with contextlib.suppress(OSError, ValueError):
                if hashlib.sha256(read_regular_bytes(path, "notebook", links=False)).hexdigest() == digest:
                    continue
            try:
                data = self.bytes(path)
                if path.is_dir() and not path.is_symlink():
                    shutil.rmtree(path)
                elif os.path.lexists(path) and not stat.S_ISREG(os.lstat(path).st_mode):
                    path.unlink()  # a link, a FIFO, a socket: removed, not written through
                write_bytes_atomic(path, data, overwrite_readonly=True)
                done.append(f"changed {shown(path)} while they ran; it was written back as read before grading")
            except OSError as error:
                done.append(f"changed {shown(path)} while they ran and it could not be written back ({error})")
        return done


_PR_GET_DUMPABLE, _PR_SET_DUMPABLE = 3, 4


@contextlib.contextmanager
def _undumpable():
    """While grading, this process is not "dumpable" (Linux): its ``/proc/<pid>/fd``, ``mem`` and ``environ``
    belong to root, so a hand-in's process, running as the same user, cannot open the grader's files through
    them (a process with ``CAP_SYS_PTRACE``, root's, still can: then a copy found changed is read again from
    its original, if that is unchanged). A kernel the grader starts is a new program, dumpable again."""
    libc = None
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
    before = libc.prctl(_PR_GET_DUMPABLE, 0, 0, 0, 0) if libc is not None else -1
    if before > 0:
        libc.prctl(_PR_SET_DUMPABLE, 0, 0, 0, 0)
    try:
        yield
    finally:
        if before > 0:
            libc.prctl(_PR_SET_DUMPABLE, before, 0, 0, 0)


def grade(submissions_dir, source_dir="notebooks", timeout: int = 600, profile: str = "ci", log=print,
          executed_dir=None, details: bool = False, guarded=(), disk_quota: int = DISK_QUOTA) -> list[Score]:
    """Grade every student folder in ``submissions_dir`` (``<dir>/<student>/**/NN_name.ipynb``).

    A notebook is matched to its source by file name (a renamed download such as "01_x (1).ipynb"
    too, see :func:`match_submissions`); a notebook that is missing scores 0, one that crashes or
    times out scores 0 for what did not run, an unreadable file scores 0 ("unreadable", the log says
    why), and none stops the others. What is not the student's doing (no kernel, an unwritable
    ``executed_dir``) raises instead: every output path is checked before the first notebook runs.
    ``executed_dir``: write each executed notebook to ``<executed_dir>/<student>/`` (feedback).
    ``details``: log a line per student and notebook; else one line per student.

    Every hand-in and source notebook is copied (a file with no name on disk) and hashed before the first
    submission runs, and graded from that copy; each hand-in runs in a temporary folder of its own (its
    ``TMPDIR`` too), with at most ``disk_quota`` bytes written to disk, and each check runs in this process
    (:func:`grade_notebook`). After each student, a hand-in or source notebook that changed on disk is
    written back and the student named in the log. A hand-in that changed the grader's own files (the code
    it runs, ``guarded``: the instructor's points file, the outputs) is scored 0, "tampered"; anything else
    it changed or left behind (the working folder, the temporary folder) is named in the log, not scored.
    Names from the submissions (folders, files) are logged with control characters escaped.
    """
    if isinstance(disk_quota, bool) or not isinstance(disk_quota, int) or disk_quota < (1 << 20):
        raise ValueError(f"disk_quota must be a whole number of bytes, at least 1 MiB, got {disk_quota!r}")
    raw_log = log

    def log(message):  # a student's folder named with a terminal escape is shown, not obeyed
        raw_log(shown(message))
    submissions_dir = Path(submissions_dir)
    if not submissions_dir.is_dir():
        raise ValueError(f"submissions_dir {str(submissions_dir)!r} is not a folder")
    students = sorted(p for p in submissions_dir.iterdir() if p.is_dir() and not p.name.startswith("."))
    if not students:
        raise ValueError(f"submissions_dir {str(submissions_dir)!r} has no student folders (<dir>/<student>/*.ipynb)")
    sources = source_notebooks(source_dir)
    if executed_dir is not None:
        check_output_folder(executed_dir, "executed_dir (--executed)")
        for student in students:
            check_output_folder(Path(executed_dir) / student.name, "executed_dir (--executed)")
    source_nbs = read_sources(sources)  # every malformed one named before any student runs
    # the checks' modules are loaded now, before a submission could edit their files
    for module in check_imports(c.source for nb in source_nbs.values() for c in nb.cells
                                if nbgrader_meta(c).get("grade") and not nbgrader_meta(c).get("solution")):
        with contextlib.suppress(ImportError):
            __import__(module)
    for module in _GRADER_MODULES:  # what a graded child would import later, from files a submission can reach
        __import__(module)
    matched = {}
    for student in students:
        handed_in, notes, unmatched = match_submissions(notebook_files(student), list(source_nbs))
        matched[student] = (handed_in, notes, unmatched)
    guard = _GraderFiles(guarded)  # the grader's code is loaded by now: its files are known
    with contextlib.ExitStack() as stack:
        stack.enter_context(_undumpable())
        kept = _Snapshot(list(sources) + [p for handed_in, _, _ in matched.values() for p in handed_in.values()])
        stack.callback(kept.close)
        if _subreaper(True):  # a hand-in's detached processes come back to the grader, to be killed
            stack.callback(_subreaper, False)
        return _grade_students(students, sources, source_nbs, matched, kept, timeout, profile, log, executed_dir,
                               details, guard, int(disk_quota))


# ------------------------------------------------------------------ the supervisor: one hand-in, out of reach
#
# Each hand-in is graded in a child of the grader (a fork: the checks' modules are the ones the grader
# imported before any submission ran) that starts a session of its own, so a signal the student's kernel
# sends to its parent or its process group reaches that child, never the grader. The grader owns the
# clock (a hard limit, then SIGKILL to the child's session and to every process left of it: the grader is
# a child subreaper, so a detached process comes back to it and is killed too), owns the result (sent
# through a pipe, signed with a key only the grader and that child hold, read only once every process of
# the hand-in is gone), owns the disk (the hand-in's own folder is its TMPDIR too; no file it writes may
# grow past the quota, RLIMIT_FSIZE, and what it writes in all, its folder and what is new in the temporary
# folder, is measured while it runs: past the quota it is killed) and watches its own files (its code, the
# files it was handed: a change while the hand-in ran is named and the notebook scored 0, "tampered"; a
# change or a new file anywhere else it looks, the working folder and the temporary folder, is named).

_PR_SET_CHILD_SUBREAPER = 36


def _subreaper(on: bool) -> bool:
    """Make this process the reaper of its orphaned descendants (Linux); whether it could."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        return ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_CHILD_SUBREAPER, int(on), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _children() -> set:
    """This process's child process ids (Linux /proc; empty elsewhere)."""
    found = set()
    me = os.getpid()
    try:
        with open(f"/proc/{me}/task/{me}/children") as handle:
            found.update(int(p) for p in handle.read().split())
    except OSError:
        for entry in os.listdir("/proc") if os.path.isdir("/proc") else ():
            if entry.isdigit():
                try:
                    with open(f"/proc/{entry}/stat") as handle:
                        if int(handle.read().rsplit(")", 1)[1].split()[1]) == me:
                            found.add(int(entry))
                except (OSError, ValueError, IndexError):
                    pass
    return found


def _kill_leftovers(before: set, session: int) -> int:
    """SIGKILL the hand-in's session and every child of this process that was not there ``before`` (a
    killed one's own children come back to this subreaper and are killed in the next round); reap them.
    How many processes were killed."""
    with contextlib.suppress(OSError):
        os.killpg(session, signal.SIGKILL)
    killed = 0
    for _ in range(200):
        left = _children() - before
        if not left:
            break
        for pid in left:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
                killed += 1
        time.sleep(0.02)
        for pid in left:
            with contextlib.suppress(ChildProcessError, OSError):
                os.waitpid(pid, os.WNOHANG)
    return killed


def _folder_state(folder: str, limit: int = 20000) -> dict:
    """``{relative path: (size, mtime_ns)}`` of ``folder``'s files (at most ``limit``, three levels deep,
    ``__pycache__`` left out): what the grader compares around each hand-in, to name what changed."""
    state = {}
    for here, dirs, names in os.walk(folder):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        if os.path.relpath(here, folder).count(os.sep) >= 2:
            dirs[:] = []
        for name in names:
            path = os.path.join(here, name)
            with contextlib.suppress(OSError):
                info = os.lstat(path)
                state[os.path.relpath(path, folder)] = (info.st_size, info.st_mtime_ns)
            if len(state) >= limit:
                return state
    return state


def _state_change(before: dict, after: dict, new: bool = True) -> str | None:
    """What changed between two states (:func:`_folder_state`, :meth:`_GraderFiles.state`): the files
    deleted, changed and (``new``) new, a few of each named, escaped."""
    gone = sorted(set(before) - set(after))
    changed = sorted(k for k in set(before) & set(after) if before[k] != after[k])
    added = sorted(set(after) - set(before)) if new else []
    parts = [f"{what} {', '.join(shown(n) for n in names[:3])}{f' (and {len(names) - 3} more)' if len(names) > 3 else ''}"
             for what, names in (("deleted", gone), ("changed", changed), ("new", added)) if names]
    return "; ".join(parts) or None


class _GraderFiles:
    """The grader's own files, whose change while a hand-in ran scores it "tampered": the files of every
    module the grader has loaded (its code and the checks', and their compiled copies), new files in the
    folders those live in (a ``.pth`` or a module dropped beside them runs in the next grading), and the
    ``guarded`` files and folders the caller names (the instructor's points file, the outputs)."""

    def __init__(self, guarded=()):
        import site
        files, folders = set(), set()
        for module in list(sys.modules.values()):
            for attribute in ("__file__", "__cached__"):
                path = getattr(module, attribute, None)
                if isinstance(path, str) and os.path.isfile(path):
                    files.add(os.path.abspath(path))
            package = getattr(module, "__path__", None)
            for path in package if isinstance(package, list) else ():  # a package's own folders
                if isinstance(path, str) and os.path.isdir(path):
                    folders.add(os.path.abspath(path))
        with contextlib.suppress(AttributeError):  # where a .pth file would run in every later Python
            folders.update(os.path.abspath(p) for p in site.getsitepackages() + [site.getusersitepackages()]
                           if os.path.isdir(p))
        # never the working or the temporary folder as such: the instructor's notes and other programs' files
        folders -= {os.path.abspath(os.getcwd()), os.path.abspath(tempfile.gettempdir())}
        for path in guarded:
            path = os.path.abspath(path)
            if os.path.isdir(path):
                folders.add(path)
                for here, _, names in os.walk(path):
                    files.update(os.path.join(here, n) for n in names)
            else:
                files.add(path)  # missing now (an output not written yet): its appearance is a change
        self.files, self.folders = sorted(files), sorted(folders)

    def state(self) -> dict:
        """``{path: (size, mtime_ns, inode, mode)}`` of the files (None where missing) and ``{folder/: names}``."""
        state: dict = {}
        for path in self.files:
            try:
                info = os.lstat(path)
                state[path] = (info.st_size, info.st_mtime_ns, info.st_ino, info.st_mode)
            except OSError:
                state[path] = None
        for folder in self.folders:
            with contextlib.suppress(OSError):
                for name in os.listdir(folder):
                    if name != "__pycache__":
                        state.setdefault(os.path.join(folder, name), "present")
        return state

    def change(self, before: dict) -> str | None:
        """What changed since ``before`` (:meth:`state`), or None."""
        after = self.state()
        before = {k: v for k, v in before.items() if v is not None}
        return _state_change(before, {k: v for k, v in after.items() if v is not None})


def _temporary_entries() -> dict:
    """``{path: inode}`` of the temporary folder's entries that this user owns (what a hand-in could leave)."""
    folder, found, me = tempfile.gettempdir(), {}, os.getuid()
    with contextlib.suppress(OSError):
        with os.scandir(folder) as entries:
            for entry in entries:
                with contextlib.suppress(OSError):
                    info = entry.stat(follow_symlinks=False)
                    if info.st_uid == me:
                        found[entry.path] = info.st_ino
    return found


def _disk_use(paths, limit: int = 20000) -> int:
    """Bytes on disk (allocated blocks) under ``paths``, links not followed, at most ``limit`` entries
    counted (a hand-in that makes more is over any quota anyway: counted as 1 MiB each beyond)."""
    total, seen = 0, 0
    for top in paths:
        stack = [top]
        while stack:
            path = stack.pop()
            try:
                info = os.lstat(path)
            except OSError:
                continue
            seen += 1
            if seen > limit:
                return total + (1 << 20) * (seen - limit + len(stack))
            total += getattr(info, "st_blocks", 0) * 512 or info.st_size
            if stat.S_ISDIR(info.st_mode):
                with contextlib.suppress(OSError):
                    stack.extend(os.path.join(path, name) for name in os.listdir(path))
    return total


def _mib(size: int) -> str:
    return f"{size / (1 << 20):.0f} MiB"


def _child_grade(write_fd: int, key: bytes, submission, source, student, timeout, profile, workdir, name,
                 quota: int, close_fds) -> None:
    """In the forked child: grade, send the signed result, never return."""
    code = 0
    try:
        os.setsid()  # a session of its own: the student's signals to its group stop this child, not the grader
        for number in (signal.SIGTERM, signal.SIGINT):
            signal.signal(number, signal.SIG_DFL)
        for fd in close_fds:  # the grader's copies: nothing of this hand-in holds them
            with contextlib.suppress(OSError):
                os.close(fd)
        with contextlib.suppress(ImportError, ValueError, OSError):
            import resource  # no file this hand-in writes grows past the quota (the kernel inherits the limit)
            hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]
            limit = quota if hard == resource.RLIM_INFINITY else min(quota, hard)
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
        os.chdir(workdir)
        tempfile.tempdir = os.path.join(workdir, "tmp")  # what this child's own libraries write goes there too
        executed: list = []
        try:
            scores = grade_notebook(submission, source, student, timeout, profile, workdir=workdir, name=name,
                                    executed=executed)
            payload = {"scores": [asdict(score) for score in scores],
                       "executed": nbformat.writes(executed[0]) if executed else None}
        except GradingStopped as error:
            payload = {"stopped": str(error)}
        except Exception as error:  # noqa: BLE001 - the notebook is not gradable: the grader scores it so
            payload = {"error": f"{type(error).__name__}: {error}"}
        data = json.dumps(payload).encode()
        message = hmac.new(key, data, hashlib.sha256).hexdigest().encode() + b"\n" + data
        view = memoryview(message)
        while view:
            view = view[os.write(write_fd, view):]
    except BaseException:  # noqa: BLE001 - the grader reads no result and says so
        code = 3
    finally:
        os._exit(code)


@dataclass
class _Outcome:
    """One supervised hand-in: its scores and executed notebook, or why there are none (``trouble``) and the
    status its checks get for it; ``notes``: what it did that is named in the log but not scored."""
    scores: list | None = None
    executed: object = None
    trouble: str | None = None
    status: str = "not run"
    notes: tuple = ()


def _supervised(submission, source, student: str, timeout: int, profile: str, name: str, guard: _GraderFiles,
                quota: int, close_fds=()) -> _Outcome:
    """Grade one hand-in in a supervised child (see above); raises GradingStopped for what is not the
    student's doing."""
    key = secrets.token_bytes(32)
    workdir = tempfile.mkdtemp(prefix="ddp-grade-")  # the hand-in's own working folder, and its TMPDIR
    os.mkdir(os.path.join(workdir, "tmp"), 0o700)
    limit = 2 * timeout * (sum(c.cell_type == "code" for c in submission.cells) + 2) + 60
    before_children = _children()
    before_grader, here = guard.state(), os.getcwd()
    before_here, before_temporary = _folder_state(here), _temporary_entries()

    def new_temporary() -> list:
        return [path for path, inode in _temporary_entries().items()
                if before_temporary.get(path) != inode and path != workdir]

    read_fd, write_fd = os.pipe()
    try:
        pid = os.fork()
        if pid == 0:
            os.close(read_fd)
            _child_grade(write_fd, key, submission, source, student, timeout, profile, workdir, name, quota, close_fds)
        os.close(write_fd)
        chunks: list = []
        reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: os.read(read_fd, 1 << 16), b"")),
                                  daemon=True)
        reader.start()
        deadline, status, killed_at_limit, over_quota = time.monotonic() + limit, None, False, 0
        measured = time.monotonic()
        while status is None:
            done, code = os.waitpid(pid, os.WNOHANG)
            if done:
                status = code
                continue
            if time.monotonic() > measured + 0.5:  # what it wrote so far: its folder, and what is new in /tmp
                measured = time.monotonic()
                used = _disk_use([workdir] + new_temporary())
                if used > quota:
                    over_quota = used
            if over_quota or time.monotonic() > deadline:
                killed_at_limit = not over_quota
                with contextlib.suppress(OSError):
                    os.killpg(pid, signal.SIGKILL)
                _, status = os.waitpid(pid, 0)
            else:
                time.sleep(0.05)
        _kill_leftovers(before_children, pid)  # every process of the hand-in gone before its result is read
        reader.join(5)
    finally:
        with contextlib.suppress(OSError):
            os.close(read_fd)
        shutil.rmtree(workdir, ignore_errors=True)
    notes = []
    left = new_temporary()
    if left:
        notes.append(f"new in the temporary folder {shown(tempfile.gettempdir())} while it ran (its own, or another "
                     f"program's of this user): "
                     + ", ".join(f"{shown(os.path.basename(p))} ({_mib(_disk_use([p]))})" for p in left[:5])
                     + (f" (and {len(left) - 5} more)" if len(left) > 5 else ""))
    elsewhere = _state_change(before_here, _folder_state(here))
    if elsewhere:
        notes.append(f"while it ran, in the working folder {shown(here)} (not the grader's files, not scored): "
                     f"{elsewhere}")
    tampered = guard.change(before_grader)
    data = b"".join(chunks)
    mac, _, payload = data.partition(b"\n")
    result = None
    if data and hmac.compare_digest(mac, hmac.new(key, payload, hashlib.sha256).hexdigest().encode()):
        result = json.loads(payload)
    if result is not None and "stopped" in result:
        raise GradingStopped(result["stopped"])
    if result is not None and "error" in result:
        raise ValueError(result["error"])  # scored unreadable by the caller
    if tampered:
        return _Outcome(trouble=f"while it ran, the grader's own files changed: {tampered}", status="tampered",
                        notes=tuple(notes))
    if over_quota:
        return _Outcome(trouble=f"it wrote {_mib(over_quota)} to disk, more than a hand-in's quota of {_mib(quota)}, "
                                f"and was stopped", notes=tuple(notes))
    if killed_at_limit:
        return _Outcome(trouble=f"it ran past the grader's limit of {limit} s and was killed", notes=tuple(notes))
    if result is None:
        if os.WIFSIGNALED(status):
            return _Outcome(trouble=f"its grading was stopped by {signal.Signals(os.WTERMSIG(status)).name} (sent "
                                    f"by its own code)", notes=tuple(notes))
        if data:
            return _Outcome(trouble="its result was tampered with on the way to the grader", status="tampered",
                            notes=tuple(notes))
        raise GradingStopped(f"grading {shown(student)}/{name} failed in the grader (exit {os.WEXITSTATUS(status)}, "
                             f"no result); grade again")
    scores = [Score(**fields) for fields in result["scores"]]
    executed = nbformat.reads(result["executed"], as_version=4) if result.get("executed") else None
    return _Outcome(scores, executed, notes=tuple(notes))


def _grade_students(students, sources, source_nbs, matched, kept, timeout, profile, log, executed_dir,
                    details, guard, quota) -> list[Score]:
    scores = []
    for number, student in enumerate(students, 1):
        handed_in, notes, unmatched = matched[student]
        for note in notes:
            log(f"{student.name}: {note}")
        if unmatched:
            log(f"{student.name}: not graded, no notebook of that name: "
                + ", ".join(repr(str(p.relative_to(student))) for p in unmatched))
        mine = []
        for source_path in sources:
            source = source_nbs[source_path.name]
            path = handed_in.get(source_path.name)
            result = None
            if path is not None:
                try:
                    if os.path.islink(path) or not _inside(path, student):  # the source's solutions, say
                        raise ValueError(f"{path.name} is a symbolic link to {os.path.realpath(path)}; a hand-in "
                                         f"must be the student's own file")
                    if path not in kept:  # a FIFO, a folder, a vanished file: scored, not read
                        regular_file(path, "notebook")
                        raise OSError(f"{path} could not be read")
                    data = kept.bytes(path)
                    submission = nbformat.reads(data.decode("utf-8"), as_version=4)
                    nbformat.validate(submission)
                    outcome = _supervised(submission, source, student.name, timeout, profile, source_path.stem,
                                          guard, quota, close_fds=(kept.file.fileno(),))
                    for note in outcome.notes:
                        log(f"{student.name}/{path.name}: {note}")
                    result = outcome.scores
                    if outcome.trouble is not None:
                        log(f"{student.name}/{path.name}: scored 0, {outcome.trouble}")
                        result = [replace(s, points=0.0, status=outcome.status if s.kind == "auto" else "blank")
                                  for s in grade_notebook(None, source, student.name, name=source_path.stem)]
                    elif executed_dir and outcome.executed is not None:
                        write_notebook(outcome.executed, Path(executed_dir) / student.name / source_path.name)
                except GradingStopped:
                    raise  # not the student's doing: stop, score nobody 0
                except Exception as error:  # the student's file is not a gradable notebook: 0, go on
                    why = f"{type(error).__name__}: {error}"
                if result is None:
                    log(f"{student.name}/{path.name}: unreadable, scored 0 ({why.splitlines()[0][:300]})")
                    mine.extend(replace(s, status="unreadable")
                                for s in grade_notebook(None, source, student.name, name=source_path.stem))
                    continue
            else:
                result = grade_notebook(None, source, student.name, name=source_path.stem)
            if details:
                auto = [s for s in result if s.kind == "auto"]
                log(f"{shown(student.name):<16} {source_path.stem:<26} {sum(s.points for s in auto):g}/"
                    f"{sum(s.max_points for s in auto):g}" + ("  (not handed in)" if path is None else ""))
            mine.extend(result)
        for line in kept.restore():
            log(f"{student.name}: their notebooks {line}")
        auto = [s for s in mine if s.kind == "auto"]
        log(f"[{number}/{len(students)}] {student.name}: {sum(s.points for s in auto):g}/"
            f"{sum(s.max_points for s in auto):g} autograded points, {len(handed_in)}/{len(sources)} notebooks handed in")
        scores.extend(mine)
    return scores
