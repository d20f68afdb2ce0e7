"""One data root: what ``data_fetch`` installs (here ``--from`` a local folder) every reader finds without a path,
and says so in its first line; ``data_fetch list NAME``; ``--only`` takes a scene or a folder. No network."""
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from data_fetch import Dataset, RemoteFile, get_dataset
from data_fetch.__main__ import main as data_fetch_main
from data_fetch.fetch import _select
from data_fetch.local import install_from
from data_fetch.pinned_pixels import PINNED
from data_fetch.pixels import pixel_sha256
from data_fetch.registry import MIDDLEBURY2006_SCENES
from ddp_lite.data.installed import (data_root, find_scene, installed_scenes, resolve_scene, scene_copies)
from ddp_lite.data.middlebury import load_middlebury, make_middlebury_fixture
from ddp_lite.data.samples import sample_scene
from ddp_lite.studies.real_suite import find_scenes
from ddp_lite.studies.table6 import table6_data_line, table6_sources

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import bench_real  # noqa: E402

RAIL = ("view0.png", "view1.png", "view2.png", "view5.png", "disp1.png", "disp5.png", "dmin.txt")
PAIR = ("im0.png", "im1.png", "calib.txt", "disp0GT.pfm")


def quiet(dataset, source, dest, only):
    return install_from(dataset, source, dest=dest, only=only, say=lambda *a: None)


def rail_dataset(source: Path, sizes=("HalfSize", "ThirdSize")) -> Dataset:
    """A middlebury2006 like the registry's (``<Size>/<Scene>/<file>``), pinned to the files under ``source``."""
    files = tuple(RemoteFile(f"{size}/Plastic/{f}", "http://127.0.0.1:9/x", pixel_sha256=pixel_sha256(source / size / "Plastic" / f))
                  for size in sizes for f in RAIL)
    return Dataset("middlebury2006", "toy 2006", files, "cite", "tests", "tiny", "http://127.0.0.1/")


def quarter_dataset(source: Path) -> Dataset:
    """A middlebury2014q like the registry's: one archive whose pinned members are Piano's quarter-size files."""
    members = tuple((f"MiddEval3/trainingQ/Piano/{f}", pixel_sha256(source / "2014-Piano-Q" / f)) for f in PAIR)
    return Dataset("middlebury2014q", "toy Q", (RemoteFile("MiddEval3-data-Q.zip", "http://127.0.0.1:9/q", unpack=True,
                                                          members=members),), "cite", "tests", "tiny", "http://127.0.0.1/")


@pytest.fixture
def sources(tmp_path):
    """A local folder holding Plastic at two sizes (dataset layout) and a 2014 quarter-size pair (offline layout)."""
    source = tmp_path / "source"
    for size in ("HalfSize", "ThirdSize"):  # the same pixels under both names: only the layout matters here
        shutil.copytree(sample_scene("Plastic"), source / size / "Plastic")
    pair = make_middlebury_fixture(source / "2014-Piano-Q", size=(48, 64))
    (pair / "disp0.pfm").rename(pair / "disp0GT.pfm")  # MiddEval3's name for the truth
    return source


def test_every_reader_finds_what_data_fetch_installed_and_says_so(sources, tmp_path, monkeypatch):
    root = tmp_path / "root"
    monkeypatch.setenv("DDP_DATA", str(root))
    assert data_root() == root and installed_scenes() == {}
    assert table6_sources("class")["Plastic"].dataset == "shipped"  # nothing installed: the shipped copies
    line = table6_data_line("class")
    assert line.startswith("data: the shipped") and "python -m data_fetch fetch middlebury2006 --only HalfSize/Plastic" in line

    quiet(rail_dataset(sources), sources, None, ["Plastic"])  # every size of the scene, by its name
    quiet(quarter_dataset(sources), sources, None, ["Piano"])
    full = make_middlebury_fixture(root / "middlebury2014" / "Piano-perfect", size=(96, 128))  # as its zip unpacks
    half = root / "middlebury2006" / "HalfSize" / "Plastic"
    quarter = root / "middlebury2014q" / "MiddEval3" / "trainingQ" / "Piano"
    assert sorted(p.name for p in half.iterdir()) == sorted(RAIL) and (root / "middlebury2006" / "ThirdSize" / "Plastic").is_dir()

    # the one rule: the copy the recorded results used first (HalfSize over ThirdSize, quarter-size 2014 over full)
    assert find_scene("Plastic").folder == half and find_scene("Plastic").size == "HalfSize"
    assert [c.size for c in scene_copies(root)["Piano"]] == ["trainingQ", "perfect"]
    assert find_scene("Piano", datasets=("middlebury2014", "middlebury2014q")).folder == quarter
    assert find_scene("Piano", datasets=("middlebury2014",)).folder == full
    assert find_scene("Plastic", datasets=("middlebury2014",)) is None
    # notebook 06 (Table 6), complete --scene, the real suite and notebook 09 read those folders
    assert table6_sources("class")["Plastic"].folder == half and table6_sources("ci")["Plastic"].dataset == "shipped"
    assert str(half) in table6_data_line("class") and "fetch" not in table6_data_line("class").split(";")[0]
    assert resolve_scene("Plastic").folder == half and resolve_scene(str(full)).folder == full
    assert find_scenes(root) == {"Piano": quarter, "Plastic": half}  # two copies of a scene: one taken, no error
    folder, line, samples = bench_real.suite_data()
    assert folder == root and not samples and line.startswith("data: 2 scenes installed in") and "Piano" in line
    scene = load_middlebury(find_scene("Piano", datasets=("middlebury2014q",)).folder)
    assert scene[0].depth.shape == (48, 64) and 0.8 < np.isfinite(scene[0].depth).mean() < 0.95  # 10 % unknown


def test_the_readers_fall_back_to_the_shipped_scenes_with_the_command_that_installs_the_real_ones(tmp_path, monkeypatch):
    monkeypatch.setenv("DDP_DATA", str(tmp_path / "empty"))
    folder, line, samples = bench_real.suite_data()
    assert samples and folder == sample_scene("Plastic").parent
    assert "python -m data_fetch fetch middlebury2006 --only HalfSize --trust-first-download" in line
    assert resolve_scene("Art").dataset == "shipped" and resolve_scene("Art").folder == sample_scene("Art")
    with pytest.raises(ValueError, match="--scene: no scene 'Aloe'.*shipped: Plastic, Baby1, Bowling1, Art"):
        resolve_scene("Aloe", what="--scene")
    with pytest.raises(ValueError, match="no such folder"):
        resolve_scene(str(tmp_path / "nowhere" / "Plastic"))
    incomplete = shutil.copytree(sample_scene("Plastic"), tmp_path / "Plastic")
    (incomplete / "view0.png").unlink()
    with pytest.raises(ValueError, match="lacks view0.png"):
        resolve_scene(str(incomplete))


def test_only_takes_a_scene_name_a_folder_or_a_glob():
    mb2006 = get_dataset("middlebury2006")
    by_name = [f.name for f in _select(mb2006, ["Plastic"])]
    assert by_name == [f.name for f in mb2006.files if f.name.split("/")[1] == "Plastic"] and len(by_name) == 30
    assert [f.name for f in _select(mb2006, ["HalfSize/Plastic"])] == [f"HalfSize/Plastic/{f}" for f in
                                                                        [f"view{k}.png" for k in range(7)] + ["disp1.png", "disp5.png", "dmin.txt"]]
    assert _select(mb2006, ["HalfSize/Plastic/*"]) == _select(mb2006, ["HalfSize/Plastic"])  # the old glob still works
    with pytest.raises(ValueError, match="matches none.*list middlebury2006"):
        _select(mb2006, ["Plast"])
    assert [f.name for f in _select(get_dataset("middlebury2014"), ["Adirondack"])] == ["Adirondack-perfect.zip",
                                                                                         "Adirondack-imperfect.zip"]
    with pytest.raises(ValueError, match="inside the archive"):
        _select(get_dataset("middlebury2014q"), ["Piano"])


def test_data_fetch_list_names_a_datasets_scenes_sizes_files_and_pins(sources, tmp_path, capsys):
    root = tmp_path / "root"
    assert data_fetch_main(["list", "middlebury2006", "--dest", str(root)]) == 0
    text = capsys.readouterr().out
    rows = {line.split()[0]: line for line in text.splitlines() if line.split() and line.split()[0] in MIDDLEBURY2006_SCENES}
    assert sorted(rows) == sorted(MIDDLEBURY2006_SCENES)
    pins = PINNED["middlebury2006"]  # the registry's pins, counted here by scene
    for scene, line in rows.items():
        pinned = sum(1 for name in pins if name.startswith(f"HalfSize/{scene}/"))
        assert line.split()[1:4] == ["10", "files", "10"] and (f"{pinned} pinned" in line) == bool(pinned)
    assert "FullSize" in text and "ThirdSize" in text and "view6.png" in text and "nothing yet" in text
    quiet(rail_dataset(sources, ("HalfSize",)), sources, root, ["HalfSize/Plastic"])
    assert data_fetch_main(["list", "middlebury2006", "--dest", str(root)]) == 0
    installed = capsys.readouterr().out.split("installed in", 1)[1]
    assert "Plastic" in installed and "HalfSize" in installed
    assert data_fetch_main(["list", "middlebury2014q", "--dest", str(root)]) == 0
    assert "Piano" in capsys.readouterr().out
