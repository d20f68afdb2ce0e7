"""What ``data_fetch`` knows how to get: one ``Dataset`` per name, each a list of ``RemoteFile``.

Honesty rules for this file (see ``data_fetch/__init__.py``):

* ``sha256`` is ``None`` ("unverified") for every file whose bytes we never saw. The machines this
  kit was written on cannot reach the dataset servers, so *no* hash below was computed by us and
  none is invented. ``fetch`` refuses an unpinned file unless ``--trust-first-download`` is given;
  then it records the hash of what arrived in ``registry.json`` next to the data and checks every
  later fetch against it. Pin a hash here (``sha256="…"``) once someone has verified a file.
* ``size`` is in bytes and ``None`` when not measured; ``Dataset.size_note`` says, in words, what
  the dataset's own page states (and that we could not check it).
* URLs follow each site's published layout; none could be reached from here (``checked=False``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["RemoteFile", "Dataset", "DATASETS", "get_dataset", "MIDDLEBURY2014_SCENES", "MIDDLEBURY2006_SCENES",
           "TNT_TRAINING_SCENES"]


@dataclass(frozen=True)
class RemoteFile:
    """One file: ``url`` (None for a manual download), local ``name`` (relative path under the
    dataset folder), ``sha256`` (hex, or None = unverified), ``size`` (bytes, or None = unknown),
    ``unpack`` (True for a .zip/.tar* to extract safely into the dataset folder)."""

    name: str
    url: str | None = None
    sha256: str | None = None
    size: int | None = None
    unpack: bool = False


@dataclass(frozen=True)
class Dataset:
    """A dataset: ``name`` (what ``fetch NAME`` takes), ``title``, ``files``, ``licence``, ``use``
    (what the kit uses it for), ``size_note`` (what is known about its size, and from where) and
    ``manual`` (instructions when the files sit behind a form; None = fetched automatically)."""

    name: str
    title: str
    files: tuple[RemoteFile, ...]
    licence: str
    use: str
    size_note: str
    homepage: str
    manual: str | None = None
    checked: bool = False  # True once the URLs and hashes were confirmed against the real server
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def automatic(self) -> bool:
        """True when every file has a URL (no manual step)."""
        return self.manual is None and all(f.url for f in self.files)

    @property
    def pinned(self) -> bool:
        """True when every file has a pinned SHA-256."""
        return all(f.sha256 for f in self.files)


# ------------------------------------------------------------------------------------------------
# Middlebury 2014: 23 scenes with ground truth, each with perfect and imperfect rectification.
# A zip holds <Scene>-<calib>/{im0.png, im1.png, im1E.png, im1L.png, disp0.pfm, disp1.pfm, calib.txt, ...}
# ------------------------------------------------------------------------------------------------
MIDDLEBURY2014_SCENES = ("Adirondack", "Backpack", "Bicycle1", "Cable", "Classroom1", "Couch", "Flowers",
                         "Jadeplant", "Mask", "Motorcycle", "Piano", "Pipes", "Playroom", "Playtable", "Recycle",
                         "Shelves", "Shopvac", "Sticks", "Storage", "Sword1", "Sword2", "Umbrella", "Vintage")
_MB14 = "https://vision.middlebury.edu/stereo/data/scenes2014/zip/"

# Middlebury 2006: the three scenes of the paper's Table 6 (Depthcomp's Middlebury comparison).
MIDDLEBURY2006_SCENES = ("Plastic", "Baby1", "Bowling1")
_MB06 = "https://vision.middlebury.edu/stereo/data/scenes2006/FullSize/"
_MB06_FILES = ("view1.png", "view5.png", "disp1.png", "disp5.png", "dmin.txt")

# Tanks and Temples training scenes evaluated in the paper (Sec. 4.1, Table 3).
TNT_TRAINING_SCENES = ("Barn", "Caterpillar", "Church", "Courthouse", "Ignatius", "Meetingroom", "Truck")

_TNT_MANUAL = """\
Tanks and Temples training data is served through links on its download page (Google Drive), not
from a stable URL, so fetch it by hand:

  1. Open https://www.tanksandtemples.org/download/ and accept the licence.
  2. Under "Training Data", for each scene you want (Barn, Caterpillar, Church, Courthouse,
     Ignatius, Meetingroom, Truck) download the image set <Scene>.zip. Optional, for the P/R/F
     evaluation: the ground truth <Scene>.ply, camera poses <Scene>_COLMAP_SfM.log, alignment
     <Scene>_trans.txt and crop <Scene>.json (kept as they are; fetch does not hash them).
  3. For cameras in MVSNet format (``cams/<id>_cam.txt``, read by ddp_lite.data.datasets.load_tnt),
     use the MVSNet authors' preprocessed "tankandtemples" folder (see github.com/YoYo000/MVSNet).
  4. Put the zips, unchanged, in {dest}
  5. Run this command again (with --only '<Scene>.zip' for a subset): it hashes the zips, records
     or checks the hashes, and unpacks them.
"""

_KITTI_MANUAL = """\
KITTI 2015 stereo sits behind a registration form, so fetch it by hand:

  1. Open https://www.cvlibs.net/datasets/kitti/eval_scene_flow.php?benchmark=stereo and register.
  2. Download "stereo 2015 / flow 2015 / scene flow 2015 data set" -> data_scene_flow.zip
     and "calibration files" -> data_scene_flow_calib.zip.
  3. Put both zips, unchanged, in {dest}
  4. Run this command again: it hashes the zips, records or checks the hashes, and unpacks them
     (training/image_2, training/image_3, training/disp_occ_0, training/calib_cam_to_cam, ...).
"""

DATASETS: dict[str, Dataset] = {}


def _add(dataset: Dataset) -> None:
    DATASETS[dataset.name] = dataset


_add(Dataset(
    name="middlebury2014",
    title="Middlebury 2014 stereo (23 scenes, perfect and imperfect calibration)",
    files=tuple(RemoteFile(f"{s}-{c}.zip", f"{_MB14}{s}-{c}.zip", unpack=True)
                for s in MIDDLEBURY2014_SCENES for c in ("perfect", "imperfect")),
    licence="Free for research; cite Scharstein et al., GCPR 2014 (see the dataset page).",
    use="Stereo pairs with dense GT disparity (PFM) + calib.txt: SGM holes on real images, "
        "DDP vs classical completion (load_middlebury).",
    size_note="Not measured: the server was unreachable when this registry was written. Each zip holds "
              "full-resolution (about 6-megapixel) PNGs and PFMs, so expect large files; use --only to pick scenes.",
    homepage="https://vision.middlebury.edu/stereo/data/scenes2014/",
))

_add(Dataset(
    name="middlebury2006",
    title="Middlebury 2006 stereo, the paper's Table 6 scenes (Plastic, Baby1, Bowling1), full size",
    files=tuple(RemoteFile(f"{s}/{f}", f"{_MB06}{s}/{f}") for s in MIDDLEBURY2006_SCENES for f in _MB06_FILES),
    licence="Free for research; cite Scharstein & Pal, CVPR 2007 / Hirschmueller & Scharstein, CVPR 2007.",
    use="Table 6 (comparison with Depthcomp's baselines, RMSE in disparity) via load_middlebury2006.",
    size_note="Not measured (server unreachable here); 15 small files, a few MB per scene.",
    homepage="https://vision.middlebury.edu/stereo/data/scenes2006/",
    notes=("No 2005 scene appears in Table 6, so only 2006 scenes are registered.",),
))

_add(Dataset(
    name="tnt",
    title="Tanks and Temples, the 7 training scenes of the paper (images, poses, GT point clouds)",
    files=tuple(RemoteFile(f"{s}.zip", None, unpack=True) for s in TNT_TRAINING_SCENES),
    licence="See https://www.tanksandtemples.org/license/ (accept it before downloading).",
    use="Multi-view DDP (RGBD + warp loss over N=2 neighbours), fusion and P/R/F-score (Tables 1-3).",
    size_note="Not measured (manual download); each image set holds a few hundred full-HD frames.",
    homepage="https://www.tanksandtemples.org/download/",
    manual=_TNT_MANUAL,
    notes=("Only the image-set zips are verified; GT .ply/.log/.txt/.json files are optional and not hashed.",),
))

_add(Dataset(
    name="nyu",
    title="NYU Depth v2, labelled subset (1449 RGB-D frames, Kinect)",
    files=(RemoteFile("nyu_depth_v2_labeled.mat",
                      "http://horatio.cs.nyu.edu/mit/silberman/nyu_depth_v2/nyu_depth_v2_labeled.mat"),),
    licence="No licence stated on the download page; research use, cite Silberman et al., ECCV 2012.",
    use="Kinect-style holes (rawDepths) vs the toolbox's cross-bilateral fill (depths); Fig. 9 (load_nyu).",
    size_note="About 2.8 GB as stated on the NYU Depth v2 page (not verified here).",
    homepage="https://cs.nyu.edu/~silberman/datasets/nyu_depth_v2.html",
))

_add(Dataset(
    name="kitti2015",
    title="KITTI 2015 stereo (200 training pairs with sparse LiDAR-based GT disparity)",
    files=(RemoteFile("data_scene_flow.zip", None, unpack=True),
           RemoteFile("data_scene_flow_calib.zip", None, unpack=True)),
    licence="CC BY-NC-SA 3.0 (non-commercial); registration required.",
    use="Table 5: D1 error of SGM / ELAS-like input vs SGM+DDP (read_kitti_disparity, load_kitti).",
    size_note="About 2 GB for data_scene_flow.zip as stated on the KITTI page (not verified here); "
              "the calibration zip is small.",
    homepage="https://www.cvlibs.net/datasets/kitti/eval_scene_flow.php?benchmark=stereo",
    manual=_KITTI_MANUAL,
))


def get_dataset(name: str) -> Dataset:
    """The registered ``Dataset`` called ``name`` (ValueError listing the names otherwise)."""
    if name not in DATASETS:
        raise ValueError(f"name must be one of {sorted(DATASETS)}, got {name!r}")
    return DATASETS[name]
