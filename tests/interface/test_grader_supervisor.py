"""The grader owns its clock, its files and its results: each hand-in is graded by a supervised child in a
session of its own, killed (with every process it left) at the limit, in a working folder of its own; a
student's signal to its parent or group stops only that hand-in; a change to the grader's working folder is
named and scored 0; a student's folder name never becomes a spreadsheet formula. The tiny one-exercise source
of test_grader_trust, at `ci`: a kernel start per hand-in."""
import csv
import os
import time

import nbformat

from ddp_lite.interface import classroom, grading
from ddp_lite.interface import grades
from conftest import process_has_ended
from test_grader_trust import RIGHT, _hand_in, _source


def test_a_hand_in_cannot_stop_hang_outlive_or_rewrite_the_grader(tmp_path, monkeypatch):
    source_path = _source(tmp_path)
    student = classroom.student_copy(nbformat.read(source_path, as_version=4))
    grader_home = tmp_path / "grader"
    grader_home.mkdir()
    precious = grader_home / "points.csv"
    precious.write_text("student,exercise,points\n")
    monkeypatch.chdir(grader_home)
    late = tmp_path / "grades.csv"
    swallow = ("import time\ndef fscore(precision, recall):\n    while True:\n        try:\n"
               "            time.sleep(100)\n        except KeyboardInterrupt:\n            pass")
    _hand_in(tmp_path, "a_hangs_in_its_function", student, swallow)
    _hand_in(tmp_path, "b_hangs_in_a_cell", student, RIGHT + "\nimport time\nwhile True:\n    try:\n"
             "        time.sleep(100)\n    except KeyboardInterrupt:\n        pass")
    _hand_in(tmp_path, "c_deletes", student, RIGHT + f"\nimport os\nos.remove({str(precious)!r})")
    detached_pid = tmp_path / "detached.pid"
    # the detached process says who it is at once, then waits far longer than a hand-in's grading takes (a
    # machine under load included) before it would write: the grader must have killed it by then
    _hand_in(tmp_path, "d_detaches", student, RIGHT + (
        "\nimport subprocess, sys\nsubprocess.Popen([sys.executable, '-c', "
        f"\"import os, time; open({str(detached_pid)!r}, 'w').write(str(os.getpid())); time.sleep(60); "
        f"open({str(late)!r}, 'w').write('=rewritten')\"], start_new_session=True)"))
    _hand_in(tmp_path, "e_kills_its_parent", student, RIGHT + "\nimport os, signal\nos.kill(os.getppid(), signal.SIGTERM)")
    _hand_in(tmp_path, "f_kills_its_group", student,
             RIGHT + "\nimport os, signal\nos.killpg(os.getpgid(os.getppid()), signal.SIGTERM)")
    _hand_in(tmp_path, "g_honest", student)
    log = []
    started = time.monotonic()
    # each hanging hand-in costs two timeouts (the interrupt it swallows, then the kill); the slowest honest cell
    # here imports NumPy in a fresh kernel, 0.13-0.25 s alone: well under the limit on a loaded 2-core machine
    scores = grading.grade(tmp_path / "hand-in", source_path.parent, timeout=2, log=log.append, guarded=[precious])
    took = time.monotonic() - started
    table = {s.student: (s.points, s.status) for s in scores}
    assert table["a_hangs_in_its_function"][0] == 0 and table["b_hangs_in_a_cell"][0] == 0, (table, log)
    assert table["c_deletes"] == (0, "tampered"), (table, log)
    assert any(line.startswith("c_deletes/") and "points.csv" in line for line in log), log
    assert table["d_detaches"] == (2, "pass"), (table, log)
    assert table["e_kills_its_parent"] == (0, "not run") and table["f_kills_its_group"] == (0, "not run"), (table, log)
    assert any(line.startswith("e_kills_its_parent/") and "SIGTERM" in line for line in log), log
    assert table["g_honest"] == (2, "pass"), (table, log)  # graded after all of them
    assert took < 120, took
    time.sleep(1)
    if detached_pid.exists() and detached_pid.read_text():  # absent: killed before it could even say its pid
        pid = int(detached_pid.read_text())
        assert process_has_ended(pid), f"the process the hand-in detached ({pid}) outlived its grading"
    assert not late.exists()


def test_a_folder_name_never_becomes_a_spreadsheet_formula(tmp_path):
    scores = [grading.Score(name, "01_fs", "01.1", "ex1", "auto", 2.0, 2.0, "pass")
              for name in ("=HYPERLINK(\"http://x\",\"y\")", "+1", "-2", "@SUM(A1)", "\tx", "\rx", "ada")]
    grades.write_csv(scores, tmp_path / "grades.csv")
    rows = list(csv.DictReader(open(tmp_path / "grades.csv", encoding="utf-8", newline="")))
    assert [r["student"] for r in rows] == ["'=HYPERLINK(\"http://x\",\"y\")", "'+1", "'-2", "'@SUM(A1)", "'\tx", "'\\rx",
                                            "ada"]
    assert os.path.getsize(tmp_path / "grades.csv") > 0


def test_no_hand_in_can_sink_the_grading_of_the_others(tmp_path, monkeypatch):
    """One grading, six hand-ins: one replaces the grader's private copies with FIFOs and writes into the
    grader's open files through /proc; one fills the temporary folder; one changes the instructor's note and
    leaves a file in the working folder (neither is the grader's); one drops a module beside the grader's
    code; one sits in a folder whose name holds terminal escapes; the honest one after them all is graded."""
    import shutil
    import sys
    import tempfile
    import threading
    import uuid

    source_path = _source(tmp_path)
    student = classroom.student_copy(nbformat.read(source_path, as_version=4))
    grader_home = tmp_path / "grader"
    grader_home.mkdir()
    (grader_home / "notes.md").write_text("the instructor's note\n")
    monkeypatch.chdir(grader_home)
    package = tmp_path / "modules" / "ddp_test_grader_module"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path / "modules"))
    __import__("ddp_test_grader_module")  # loaded by the grader: its folder is the grader's code
    temporary = tempfile.gettempdir()
    filled = os.path.join(temporary, f"ddp-test-filled-{uuid.uuid4().hex}")
    _hand_in(tmp_path, "a_fifos", student, RIGHT + (
        "\nimport glob, os\n"
        f"for folder in glob.glob({os.path.join(temporary, 'ddp-grade-copies-*')!r}):\n"
        "    for name in os.listdir(folder):\n"
        "        os.remove(os.path.join(folder, name)); os.mkfifo(os.path.join(folder, name))\n"
        "child = os.getppid()\n"
        "grader = int(open(f'/proc/{child}/stat').read().rsplit(')', 1)[1].split()[1])\n"
        "for pid in (child, grader):\n"
        "    try:\n"
        "        fds = os.listdir(f'/proc/{pid}/fd')\n"
        "    except OSError:\n"
        "        continue\n"
        "    for fd in fds:\n"
        "        try:\n"
        f"            if os.readlink(f'/proc/{{pid}}/fd/{{fd}}').startswith({temporary!r}):\n"
        "                with open(f'/proc/{pid}/fd/{fd}', 'r+b') as f:\n"
        "                    if f.read(1) == b'{':  # a notebook: the grader's copies\n"
        "                        f.seek(0); f.write(b'x' * 100000)\n"
        "        except OSError:\n"
        "            pass"))
    _hand_in(tmp_path, "b_fills_the_temporary_folder", student, RIGHT + (
        f"\nimport os, time\nos.makedirs({filled!r})\nfor i in range(40):\n"
        f"    with open(os.path.join({filled!r}, str(i)), 'wb') as f:\n"
        "        f.write(os.urandom(4 << 20))\n    time.sleep(0.05)"))
    _hand_in(tmp_path, "c_writes_beside_the_grader", student, RIGHT + (
        f"\nopen({str(grader_home / 'notes.md')!r}, 'a').write('changed\\n')\n"
        f"open({str(grader_home / 'new.txt')!r}, 'w').write('new')"))
    _hand_in(tmp_path, "d_drops_a_module", student, RIGHT + f"\nopen({str(package / 'evil.py')!r}, 'w').write('')")
    escaped = "e_\x1b[2J\x1b]0;pwned\x07\u202eevil\nfake line"
    _hand_in(tmp_path, escaped, student)
    _hand_in(tmp_path, "f_honest", student)

    def unblock():  # an old grader stuck on a FIFO is let go, so that a failure is a failure, not a hang
        time.sleep(240)
        for folder in __import__("glob").glob(os.path.join(temporary, "ddp-grade-copies-*")):
            for name in os.listdir(folder):
                try:
                    os.close(os.open(os.path.join(folder, name), os.O_WRONLY | os.O_NONBLOCK))
                except OSError:
                    pass
    threading.Thread(target=unblock, daemon=True).start()
    log = []
    try:
        scores = grading.grade(tmp_path / "hand-in", source_path.parent, timeout=60, log=log.append,
                               disk_quota=48 << 20)
    finally:
        shutil.rmtree(filled, ignore_errors=True)
        sys.modules.pop("ddp_test_grader_module", None)
    table = {s.student: (s.points, s.status) for s in scores}
    assert table["a_fifos"] == (2, "pass") and table["f_honest"] == (2, "pass"), (table, log)
    assert table["b_fills_the_temporary_folder"] == (0, "not run"), (table, log)
    assert any(line.startswith("b_fills_the_temporary_folder/") and "quota" in line for line in log), log
    assert any(line.startswith("b_fills_the_temporary_folder/") and os.path.basename(filled) in line for line in log), log
    assert table["c_writes_beside_the_grader"] == (2, "pass"), (table, log)
    assert any(line.startswith("c_writes_beside_the_grader/") and "notes.md" in line and "new.txt" in line
               and "not scored" in line for line in log), log
    assert table["d_drops_a_module"] == (0, "tampered"), (table, log)
    assert any(line.startswith("d_drops_a_module/") and "evil.py" in line for line in log), log
    assert table[escaped] == (2, "pass"), (table, log)
    shown = [line for line in log if "] e_" in line]
    assert shown and all("\x1b" not in line and "\u202e" not in line and "\n" not in line and "\x07" not in line
                         for line in log), log
    assert any("e_\\x1b[2J" in line and "\\u202eevil\\nfake line" in line for line in shown), shown
    assert "\x1b" not in grades.format_grades(scores) and "\\x1b[2J" in grades.format_grades(scores)
