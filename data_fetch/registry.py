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

from .pinned_pixels import PINNED

__all__ = ["RemoteFile", "Dataset", "DATASETS", "get_dataset", "MIDDLEBURY2014_SCENES", "MIDDLEBURY2005_SCENES",
           "MIDDLEBURY2006_SCENES", "MIDDLEBURY_SIZES", "MIDDLEBURY_VIEW_FILES", "MIDDEVAL3_Q_SCENES", "MEMBER_CANDIDATES",
           "TNT_TRAINING_SCENES"]


@dataclass(frozen=True)
class RemoteFile:
    """One file: ``url`` (None for a manual download), local ``name`` (relative path under the
    dataset folder), ``sha256`` (hex, or None = unverified), ``size`` (bytes, or None = unknown),
    ``unpack`` (True for a .zip/.tar* to extract safely into the dataset folder), ``pixel_sha256``
    (``data_fetch.pixels.pixel_sha256`` of its decoded content, or None = not pinned) and, for an
    archive, ``members``: ``(unpacked name, pixel_sha256)`` pairs checked after unpacking."""

    name: str
    url: str | None = None
    sha256: str | None = None
    size: int | None = None
    unpack: bool = False
    pixel_sha256: str | None = None
    members: tuple[tuple[str, str], ...] = ()

    def __post_init__(self):  # hashes normalised once, here: a pin in upper case is the same pin
        from .download import normal_sha256
        object.__setattr__(self, "sha256", normal_sha256(self.sha256, f"{self.name}: sha256"))
        object.__setattr__(self, "pixel_sha256", normal_sha256(self.pixel_sha256, f"{self.name}: pixel_sha256"))
        object.__setattr__(self, "members", tuple((member, normal_sha256(pin, f"{self.name}: member {member!r}"))
                                                  for member, pin in self.members))


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

# Middlebury 2005 and 2006: seven rectified views on one rail, GT disparity of views 1 and 5.
# Per-file layout on the server: scenes<year>/<Size>/<Scene>/<file> (see the datasets' notes).
MIDDLEBURY2005_SCENES = ("Art", "Books", "Dolls", "Laundry", "Moebius", "Reindeer")
MIDDLEBURY2006_SCENES = ("Aloe", "Baby1", "Baby2", "Baby3", "Bowling1", "Bowling2", "Cloth1", "Cloth2", "Cloth3",
                         "Cloth4", "Flowerpots", "Lampshade1", "Lampshade2", "Midd1", "Midd2", "Monopoly", "Plastic",
                         "Rocks1", "Rocks2", "Wood1", "Wood2")
MIDDLEBURY_SIZES = ("FullSize", "HalfSize", "ThirdSize")
MIDDLEBURY_VIEW_FILES = tuple(f"view{k}.png" for k in range(7)) + ("disp1.png", "disp5.png", "dmin.txt")
_MB_DATA = "https://vision.middlebury.edu/stereo/data/"

# MiddEval3 (Middlebury 2014 benchmark) quarter-size training scenes: two zips, both unpacking into
# MiddEval3/trainingQ/<Scene>/ (the data zip also holds MiddEval3/testQ/).
MIDDEVAL3_Q_SCENES = ("Adirondack", "ArtL", "Jadeplant", "Motorcycle", "MotorcycleE", "Piano", "PianoL", "Pipes",
                      "Playroom", "Playtable", "PlaytableP", "Recycle", "Shelves", "Teddy", "Vintage")
_MB_SUBMIT3 = "https://vision.middlebury.edu/stereo/submit3/zip/"
MIDDEVAL3_Q_DATA_FILES = ("im0.png", "im1.png", "calib.txt")
MIDDEVAL3_Q_GT_FILES = ("disp0GT.pfm", "mask0nocc.png")

# DepthComp's example input (Atapour-Abarghouei & Breckon 2017): Plastic with the holes of the
# paper's Table 6, from the authors' repository at a fixed commit.
_DEPTHCOMP = ("https://raw.githubusercontent.com/atapour/depthComp/adab1821813dee7c54b80db1d4564243c7c38800/"
              "Examples/plastic-disp-hole.png")

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

_MB0506_LICENCE = ("Free to use and publish with citation: D. Scharstein and C. Pal, \"Learning conditional random "
                   "fields for stereo\", CVPR 2007; H. Hirschmueller and D. Scharstein, \"Evaluation of cost "
                   "functions for stereo matching\", CVPR 2007.")
_MB0506_NOTES = (
    "URL layout scenes<year>/<Size>/<Scene>/<file> not checked against the server (unreachable here). Public "
    "download scripts fetch disp1.png and dmin.txt from scenes2005/FullSize/<Scene>/ and scenes2006/FullSize/"
    "<Scene>/, mirror scenes2006/HalfSize/ recursively for png/txt, and take views from <Scene>/Illum<i>/Exp<e>/"
    "view<k>.png; whether view0, view2, view3, view4 and view6 also sit directly in <Scene>/ was not confirmed. "
    "The site also serves each size as <Size>/zip-2views/<Scene>-2views.zip and <Size>/zip-7views/"
    "<Scene>-7views.zip: if a file here 404s, download those by hand and install them with --from.",
)


def _pin_note(pins) -> str:
    scenes = sorted({name.split("/")[1] for name in pins})
    return (f"Pixel hashes pinned for the HalfSize files of {', '.join(scenes) or 'no scene'}, from offline copies "
            f"(decoded pixels, so any PNG encoding of the same pixels passes; dmin.txt as text); every other file "
            f"is unverified.")


def _views(year: int, scenes, pins) -> tuple[RemoteFile, ...]:
    return tuple(RemoteFile(f"{size}/{scene}/{name}", f"{_MB_DATA}scenes{year}/{size}/{scene}/{name}",
                            pixel_sha256=pins.get(f"{size}/{scene}/{name}"))
                 for size in MIDDLEBURY_SIZES for scene in scenes for name in MIDDLEBURY_VIEW_FILES)


_add(Dataset(
    name="middlebury2005",
    title="Middlebury 2005 stereo, the 6 scenes with ground truth, 7 views, 3 sizes",
    files=_views(2005, MIDDLEBURY2005_SCENES, PINNED.get("middlebury2005", {})),
    licence=_MB0506_LICENCE,
    use="Real multi-view scenes with GT disparity: view1 with neighbours view0/view2 (the paper's N = 2), "
        "view5 its stereo partner; SGM holes and DDP on real photographs (ddp_lite.data.middlebury_rail.load_rail_scene).",
    size_note="Not measured (server unreachable here): 180 files; a HalfSize scene is about 2 MB "
              "(the offline copies), FullSize about 4 times that.",
    homepage="https://vision.middlebury.edu/stereo/data/scenes2005/",
    checked=False,
    notes=("Computer, Drumsticks and Dwarves, the other three 2005 scenes, have no public ground truth "
           "(withheld for evaluation), so they are not registered.",) + _MB0506_NOTES
          + (_pin_note(PINNED.get("middlebury2005", {})),),
))

_add(Dataset(
    name="middlebury2006",
    title="Middlebury 2006 stereo, all 21 scenes (Plastic, Baby1, Bowling1 of Table 6 among them), 7 views, 3 sizes",
    files=_views(2006, MIDDLEBURY2006_SCENES, PINNED.get("middlebury2006", {})),
    licence=_MB0506_LICENCE,
    use="Table 6 (comparison with DepthComp's baselines, RMSE in disparity) and real multi-view scenes with "
        "GT disparity (ddp_lite.data.middlebury_rail.load_rail_scene).",
    size_note="Not measured (server unreachable here): 630 files; a HalfSize scene is about 2 MB "
              "(the offline copies), FullSize about 4 times that; use --only 'HalfSize/Plastic/*'.",
    homepage="https://vision.middlebury.edu/stereo/data/scenes2006/",
    checked=False,
    notes=_MB0506_NOTES + (_pin_note(PINNED.get("middlebury2006", {})),),
))

_Q = PINNED.get("middlebury2014q", {})
# the unpacked files that may carry a pixel pin (pin_pixels takes its names from here)
MEMBER_CANDIDATES = {"middlebury2014q": tuple(f"MiddEval3/trainingQ/{scene}/{f}" for scene in MIDDEVAL3_Q_SCENES
                                              for f in MIDDEVAL3_Q_DATA_FILES + MIDDEVAL3_Q_GT_FILES)}


def _q_members(files) -> tuple[tuple[str, str], ...]:
    names = (n for n in MEMBER_CANDIDATES["middlebury2014q"] if n.rsplit("/", 1)[1] in files)
    return tuple((name, _Q[name]) for name in names if name in _Q)


_add(Dataset(
    name="middlebury2014q",
    title="Middlebury 2014 / MiddEval3 training scenes at quarter size (trainingQ: images, calib, GT, masks)",
    files=(RemoteFile("MiddEval3-data-Q.zip", f"{_MB_SUBMIT3}MiddEval3-data-Q.zip", unpack=True,
                      members=_q_members(MIDDEVAL3_Q_DATA_FILES)),
           RemoteFile("MiddEval3-GT0-Q.zip", f"{_MB_SUBMIT3}MiddEval3-GT0-Q.zip", unpack=True,
                      members=_q_members(MIDDEVAL3_Q_GT_FILES))),
    licence="Free to use and publish with citation: D. Scharstein et al., \"High-resolution stereo datasets with "
            "subpixel-accurate ground truth\", GCPR 2014.",
    use="Small real stereo pairs with float GT disparity (PFM) and occlusion masks: quick real-data checks.",
    size_note="Not measured (server unreachable here); public scripts describe the two zips as tens of MB "
              "together (data zip larger: it also holds the 15 test scenes).",
    homepage="https://vision.middlebury.edu/stereo/submit3/",
    checked=False,
    notes=("URLs as used by many public download scripts (submit3/zip/MiddEval3-data-Q.zip, "
           "MiddEval3-GT0-Q.zip); both unpack under MiddEval3/trainingQ/<Scene>/. Not fetched from here.",
           "The archives stay trust-on-first-download (no byte hash measured). After unpacking, the members "
           "of 7 scenes (Adirondack, ArtL, Jadeplant, Piano, Pipes, Playroom, Playtable) are checked against "
           "pixel hashes from offline copies; calib.txt is compared as text tokens (the offline copy's spacing "
           "differs from the official files' and its values were not checked against them).",
           "Ground truth exists for the left view only in GT0 (disp0GT.pfm, +inf = unknown; mask0nocc.png "
           "255 visible, 128 occluded in the right view)."),
))

_add(Dataset(
    name="depthcomp",
    title="DepthComp's Plastic with holes (the paper's Table 6 input), full size",
    files=(RemoteFile("plastic-disp-hole.png", _DEPTHCOMP,
                      pixel_sha256=PINNED.get("depthcomp", {}).get("plastic-disp-hole.png")),),
    licence="Derived from Middlebury 2006 Plastic (cite Scharstein & Pal, CVPR 2007; Hirschmueller & Scharstein, "
            "CVPR 2007); shipped in DepthComp's repository (GPL), A. Atapour-Abarghouei and T. Breckon, "
            "\"DepthComp: real-time depth image completion based on prior semantic scene segmentation\", BMVC 2017.",
    use="Table 6: the holes DepthComp fills on Plastic (0 = hole or unknown); score where 0 here and known in GT.",
    size_note="Not measured (server unreachable here); one 8-bit PNG of about 50 kB (the offline copy).",
    homepage="https://github.com/atapour/depthComp",
    checked=False,
    notes=("URL pinned to the commit of atapour/depthComp that holds Examples/plastic-disp-hole.png; not fetched "
           "from here. Pixel hash from an offline copy.",),
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
    use="Kinect-style holes (rawDepths) vs the toolbox's cross-bilateral fill (depths); Fig. 8 (ddp_lite.data.datasets.load_nyu).",
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
