"""Bad sequence runs: an output folder that would overwrite what the run reads, a damaged manifest or finished
view refused naming the file, and a damaged finished view fitted again, never fused. The refusals use
``bad_input_harness``.
"""
from __future__ import annotations

import numpy as np

from bad_input_harness import H, W, CaseList, colmap_workspace, desk_scene, refusal_test, tiny, tum_capture
from ddp_lite.data.colmap import read_colmap
from ddp_lite.data.formats import read_scene
from ddp_lite.data.tum import read_tum
from ddp_lite.sequences import sequence_files
from ddp_lite.sequences.sequence import run_sequence
from ddp_lite.sequences.sequence_files import MANIFEST, read_manifest

CASES = CaseList()
case = CASES.case

def _run(scene, out):
    return lambda: run_sequence(scene, out, tiny(iterations=1), fuse=False, log=lambda *a: None)


# --------------------------------------------------------------------------- serious: outputs over inputs

case("sequence out = the TUM capture", ValueError, "out")(
    lambda tmp: _run(read_tum(tum_capture(tmp)), tmp / "capture"))
case("sequence out = the TUM capture's depth folder", ValueError, "out")(
    lambda tmp: _run(read_tum(tum_capture(tmp)), tmp / "capture" / "depth"))
case("sequence out = a folder holding the capture", ValueError, "out")(
    lambda tmp: _run(read_tum(tum_capture(tmp)), tmp))
case("sequence out = the COLMAP workspace", ValueError, "out")(
    lambda tmp: _run(read_colmap(colmap_workspace(tmp), depth_scale=0.001), tmp / "workspace"))
case("sequence out = a saved scene's folder", ValueError, "out")(
    lambda tmp: (desk_scene().save(tmp / "s" / "scene.npz"), _run(read_scene(tmp / "s"), tmp / "s"))[1])
case("sequence out = a path given as source", ValueError, "out")(
    lambda tmp: (lambda: run_sequence(desk_scene(), tmp / "data" / "out", tiny(iterations=1),
                                      source={"path": str(tmp / "data")}, log=lambda *a: None)))
case("sequence out is a file", ValueError, "out")(
    lambda tmp: ((tmp / "out").write_text("x"), _run(desk_scene(), tmp / "out"))[1])


# --------------------------------------------------------------------------- files

def _manifest(text):
    def setup(tmp):
        (tmp / "out").mkdir()
        (tmp / "out" / MANIFEST).write_text(text)
        return _run(desk_scene(), tmp / "out")
    return setup


case("manifest.json a JSON list", ValueError, "manifest")(_manifest("[1, 2]"))
case("manifest.json views a list", ValueError, "manifest")(_manifest('{"views": [1]}'))
case("manifest.json a view entry a string", ValueError, "manifest")(_manifest('{"views": {"desk0": "done"}}'))
case("manifest.json not JSON", ValueError, "manifest")(_manifest("{views"))
case("finished view .npy corrupt", ValueError, "bad.npy")(
    lambda tmp: ((tmp / "bad.npy").write_bytes(b"\x93NUMPY garbage"), lambda: sequence_files._load_depth(tmp / "bad.npy"))[1])
case("finished view .npy of the wrong kind", ValueError, "wrong.npy")(
    lambda tmp: (np.save(tmp / "wrong.npy", np.zeros(3)), lambda: sequence_files._load_depth(tmp / "wrong.npy"))[1])


test_bad_input_is_refused_clearly_and_changes_nothing = refusal_test(CASES)


def test_corrupt_finished_view_is_redone_not_fused(tmp_path):
    """A finished view whose .npy was damaged is fitted again on the next run (and named nowhere as done)."""
    scene = desk_scene()
    out = tmp_path / "out"
    config = tiny(iterations=1)
    first = run_sequence(scene, out, config, fuse=False, log=lambda *a: None)
    assert len(first["computed"]) == 3
    npy = out / read_manifest(out)["views"][scene[0].name]["files"]["npy"]
    npy.write_bytes(b"\x93NUMPY broken")
    again = run_sequence(scene, out, config, log=lambda *a: None)
    assert again["computed"] == [scene[0].name] and len(again["skipped"]) == 2
    assert sequence_files._load_depth(npy).shape == (H, W)
