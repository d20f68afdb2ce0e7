"""The data root and the Middlebury scenes in it: the one place every reader asks what is installed.

**One data root**: ``dest`` if given, else ``$DDP_DATA``, else the per-user data folder
(``platformdirs.user_data_dir("ddp-lite")``). ``python -m data_fetch`` installs there, downloaded or
``--from`` a local copy, each dataset in its own folder; the notebooks, ``ddp-lite complete --scene`` and
the benchmarks read from there without a path typed:

* ``middlebury2005/<Size>/<Scene>/``, ``middlebury2006/<Size>/<Scene>/`` (``Size`` = ``FullSize``,
  ``HalfSize``, ``ThirdSize``): ``view0.png`` … ``view6.png``, ``disp1.png``, ``disp5.png``, ``dmin.txt``;
* ``middlebury2014/<Scene>-perfect/`` (and ``-imperfect``): ``im0.png``, ``im1.png``, ``calib.txt``, ``disp0.pfm``;
* ``middlebury2014q/MiddEval3/trainingQ/<Scene>/``: the same at quarter size, the truth in ``disp0GT.pfm``;
* ``depthcomp/plastic-disp-hole.png``: DepthComp's own holes on Plastic (the paper's Table 6 input).

A scene is named by its folder: ``HalfSize/Plastic`` → ``Plastic``, ``Adirondack-perfect`` → ``Adirondack``,
and in the offline copies' layout ``2006-Plastic`` → ``Plastic``, ``2014-Piano-Q`` → ``Piano``. Where one
scene is there more than once, the copy the kit's recorded results were measured on comes first
(``PREFERENCE``: HalfSize, quarter-size 2014), then the larger ones (FullSize, a full-size 2014 pair with
perfect rectification), then ThirdSize and imperfect rectification. Standard library only (``data_fetch``,
which runs without torch, imports it).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import platformdirs

__all__ = ["ENV_VAR", "DEPTHCOMP_FILE", "PREFERENCE", "RAIL_FILES", "PAIR_FILES", "data_root", "is_rail_folder",
           "is_2014_folder", "SceneCopy", "scene_copies", "scene_folders", "installed_scenes", "find_scene",
           "shipped_scene", "resolve_scene", "fetch_command", "data_line", "depthcomp_hole_file"]

ENV_VAR = "DDP_DATA"
DEPTHCOMP_FILE = "plastic-disp-hole.png"
# the files a reader of the kit needs: view1 with its truth and its stereo partner view5, and view0 and view2
# as the warp term's two nearest calibrated neighbours; a 2014 pair with its calibration and its truth
RAIL_FILES = ("view0.png", "view1.png", "view2.png", "view5.png", "disp1.png", "dmin.txt")
PAIR_FILES = ("im0.png", "im1.png", "calib.txt")
PREFERENCE = ("HalfSize", "trainingQ", "FullSize", "perfect", "ThirdSize", "imperfect")  # best first


def data_root(dest=None) -> Path:
    """The data root: ``dest`` if given, else ``$DDP_DATA``, else ``platformdirs.user_data_dir('ddp-lite')``.
    ValueError for an empty ``dest`` or a ``$DDP_DATA`` that is set but blank (a typo'd export)."""
    if dest is not None:
        if not str(dest).strip():
            raise ValueError("dest must name a folder, got an empty string")
        return Path(dest).expanduser()
    if ENV_VAR in os.environ:
        if not os.environ[ENV_VAR].strip():
            raise ValueError(f"{ENV_VAR} is set but blank; name a folder (export {ENV_VAR}=/path/to/data) or unset "
                             f"it to use {platformdirs.user_data_dir('ddp-lite')}")
        return Path(os.environ[ENV_VAR]).expanduser()
    return Path(platformdirs.user_data_dir("ddp-lite"))


def is_rail_folder(folder) -> bool:
    """Whether ``folder`` holds a 2005/2006 scene (``view1.png``, ``disp1.png``, ``dmin.txt``)."""
    folder = Path(folder)
    return all((folder / name).is_file() for name in ("view1.png", "disp1.png", "dmin.txt"))


def is_2014_folder(folder) -> bool:
    """Whether ``folder`` holds a 2014 scene (``im0.png``, ``calib.txt`` and ``disp0GT.pfm`` or ``disp0.pfm``)."""
    folder = Path(folder)
    return ((folder / "im0.png").is_file() and (folder / "calib.txt").is_file()
            and any((folder / name).is_file() for name in ("disp0GT.pfm", "disp0.pfm")))


@dataclass(frozen=True)
class SceneCopy:
    """One copy of a Middlebury scene on disk: ``name`` (``Plastic``), ``folder``, ``dataset`` (the data_fetch
    name it was installed as, ``"shipped"`` for the kit's samples, None for a folder of another layout),
    ``size`` (``HalfSize``, ``trainingQ``, ``perfect``, …, ``quarter`` for the samples, ``""`` unknown),
    ``layout`` (``"2005/2006"`` or ``"2014"``) and ``missing`` (files a reader needs that are not there)."""

    name: str
    folder: Path
    dataset: str | None
    size: str
    layout: str
    missing: tuple[str, ...] = ()

    @property
    def complete(self) -> bool:
        """Whether every file the kit's readers need is there."""
        return not self.missing

    def describe(self) -> str:
        """``'Plastic (middlebury2006, HalfSize) in /data/middlebury2006/HalfSize/Plastic'``."""
        where = ", ".join(part for part in (self.dataset, self.size) if part)
        return f"{self.name} ({where or self.layout}) in {self.folder}"


def _name_and_size(folder: Path) -> tuple[str, str]:
    """A scene folder's scene name and size label, from its path (see the module docstring)."""
    name, size = folder.name, ""
    if folder.parent.name in ("FullSize", "HalfSize", "ThirdSize", "trainingQ"):
        size = folder.parent.name
    if name[:4].isdigit() and "-" in name:  # the offline copies: 2006-Plastic, 2014-Piano-Q
        year, name = name.split("-", 1)
        size = size or ("HalfSize" if year in ("2005", "2006") else "")
    if name.endswith("-Q"):
        name, size = name[:-2], "trainingQ"
    for calibration in ("perfect", "imperfect"):
        if name.endswith(f"-{calibration}"):
            name, size = name[: -len(calibration) - 1], calibration
    return name, size


def _dataset_of(folder: Path, root: Path) -> str | None:
    """The data_fetch dataset a scene folder under the data root belongs to (its first path part there)."""
    try:
        first = folder.relative_to(root).parts[0]
    except (ValueError, IndexError):
        return None
    return first if first.startswith("middlebury") else None


def _copy(folder: Path, root: Path, dataset: str | None = None) -> SceneCopy:
    name, size = _name_and_size(folder)
    if is_rail_folder(folder):
        layout, needed = "2005/2006", RAIL_FILES
    else:
        layout, needed = "2014", PAIR_FILES
    missing = tuple(f for f in needed if not (folder / f).is_file())
    return SceneCopy(name, folder, dataset or _dataset_of(folder, root), size, layout, missing)


def _rank(copy: SceneCopy) -> tuple:
    return (not copy.complete, PREFERENCE.index(copy.size) if copy.size in PREFERENCE else len(PREFERENCE))


def scene_copies(root) -> dict[str, list[SceneCopy]]:
    """{scene name: every copy of it under ``root`` (any depth), best first (complete ones, then by
    ``PREFERENCE``)}: a data root as ``data_fetch`` fills it, the offline copies' layout, or any folder of
    scene folders. ``root`` itself may be a scene folder. {} when there is none or ``root`` is no folder."""
    root = Path(root)
    if not root.is_dir():
        return {}
    found: dict[str, list[SceneCopy]] = {}
    for folder in [root] + sorted(p for p in root.rglob("*") if p.is_dir()):
        if is_rail_folder(folder) or is_2014_folder(folder):
            copy = _copy(folder, root)
            found.setdefault(copy.name, []).append(copy)
    return {name: sorted(copies, key=_rank) for name, copies in sorted(found.items())}


def scene_folders(root) -> dict[str, Path]:
    """{scene name: folder} of every complete Middlebury scene with ground truth under ``root``, the best
    copy of each (``scene_copies``). ValueError when ``root`` is no folder, when it holds no complete scene,
    or when two copies of one scene rank alike (which to take is then the caller's to say)."""
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"root must be a folder of Middlebury scenes (as data_fetch installs them), got {root}")
    chosen = {}
    for name, copies in scene_copies(root).items():
        complete = [c for c in copies if c.complete]
        if not complete:
            continue
        if len(complete) > 1 and _rank(complete[0]) == _rank(complete[1]):
            raise ValueError(f"root: two folders hold scene {name!r} alike: {complete[0].folder} and "
                             f"{complete[1].folder}")
        chosen[name] = complete[0].folder
    if not chosen:
        raise ValueError(f"root: no complete Middlebury scene with ground truth under {root} (a 2005/2006 scene "
                         f"folder holds {', '.join(RAIL_FILES)}; a 2014 one {', '.join(PAIR_FILES)} and "
                         f"disp0GT.pfm or disp0.pfm)")
    return chosen


def installed_scenes(dest=None, datasets=None) -> dict[str, SceneCopy]:
    """{scene name: its best complete copy} in the data root (``data_root(dest)``), only from the data_fetch
    datasets named in ``datasets`` (e.g. ``("middlebury2014", "middlebury2014q")``) when given. {} when
    nothing is installed."""
    root = data_root(dest)
    out = {}
    for name, copies in scene_copies(root).items():
        chosen = [c for c in copies if c.complete and c.dataset and (datasets is None or c.dataset in datasets)]
        if chosen:
            out[name] = chosen[0]
    return out


def find_scene(name: str, dest=None, datasets=None) -> SceneCopy | None:
    """The best complete installed copy of scene ``name`` (``installed_scenes``), or None."""
    return installed_scenes(dest, datasets).get(name)


def shipped_scene(name: str) -> SceneCopy:
    """A scene the kit ships (``data.samples.SAMPLES``: Plastic, Baby1, Bowling1, Art, quarter size)."""
    from .samples import SAMPLES, sample_scene

    if name not in SAMPLES:
        raise ValueError(f"name must be one of the shipped scenes {SAMPLES}, got {name!r}")
    folder = sample_scene(name)
    return SceneCopy(name, folder, "shipped", "quarter", "2005/2006")


def resolve_scene(text, dest=None, what: str = "scene") -> SceneCopy:
    """``text`` → a scene copy: a Middlebury scene folder (the 2005/2006 or 2014 layout), else the best
    installed copy of that scene name in the data root, else the shipped sample of that name. ValueError
    naming ``what`` and what was expected (the scenes installed and shipped) otherwise."""
    from .samples import SAMPLES

    if text is None or not str(text).strip():
        raise ValueError(f"{what} must name a Middlebury scene folder or a scene, got {text!r}")
    path = Path(str(text)).expanduser()
    if path.is_dir():
        if is_rail_folder(path) or is_2014_folder(path):
            copy = _copy(path, data_root(dest))
            if copy.missing:
                raise ValueError(f"{what}: {path} lacks {', '.join(copy.missing)} (a {copy.layout} scene needs "
                                 f"{', '.join(RAIL_FILES if copy.layout == '2005/2006' else PAIR_FILES)})")
            return copy
        raise ValueError(f"{what}: {path} is not a Middlebury scene folder with ground truth: expected "
                         f"{', '.join(RAIL_FILES)} (2005/2006) or {', '.join(PAIR_FILES)} and disp0GT.pfm or "
                         f"disp0.pfm (2014)")
    if path.exists():
        raise ValueError(f"{what}: {text!r} is not a folder (give a Middlebury scene folder, or a scene name)")
    if os.sep in str(text) or (os.altsep and os.altsep in str(text)):
        raise ValueError(f"{what}: no such folder {text!r} (give a Middlebury scene folder, or a scene name)")
    installed = installed_scenes(dest)
    if str(text) in installed:
        return installed[str(text)]
    if str(text) in SAMPLES:
        return shipped_scene(str(text))
    raise ValueError(f"{what}: no scene {text!r}: installed in {data_root(dest)}: "
                     f"{', '.join(sorted(installed)) or 'none'}; shipped: {', '.join(SAMPLES)} (python -m data_fetch "
                     f"list middlebury2006 lists a dataset's scenes)")


def fetch_command(dataset: str, *scenes: str) -> str:
    """The one command that installs ``scenes`` of ``dataset`` (a data_fetch name) into the data root: the
    HalfSize files of 2005/2006 scenes (of the pixel-pinned ones no trust flag needed; no scene named: every
    HalfSize scene), full-size 2014 pairs, the quarter-size 2014 archives (every scene at once), DepthComp's holes.

    Example:
        >>> fetch_command("middlebury2006", "Plastic", "Baby1")
        'python -m data_fetch fetch middlebury2006 --only HalfSize/Plastic --only HalfSize/Baby1'
    """
    if dataset in ("middlebury2005", "middlebury2006"):
        if not scenes:  # every HalfSize scene: only some are pixel-pinned, the others taken on first use
            return f"python -m data_fetch fetch {dataset} --only HalfSize --trust-first-download"
        return f"python -m data_fetch fetch {dataset}" + "".join(f" --only HalfSize/{s}" for s in scenes)
    if dataset == "middlebury2014":
        return ("python -m data_fetch fetch middlebury2014" + "".join(f" --only {s}-perfect.zip" for s in scenes)
                + " --trust-first-download")
    if dataset == "middlebury2014q":
        return "python -m data_fetch fetch middlebury2014q --trust-first-download"
    return f"python -m data_fetch fetch {dataset}"


def data_line(copies, fallback: str = "", dataset: str = "", scenes=(), why: str = "not installed") -> str:
    """The first line a reader prints: ``data: `` the installed copies it reads (``SceneCopy``s or folders),
    and, where it falls back to what the kit ships (``fallback``, in words), why and the one command that
    installs the real data (``fetch_command(dataset, *scenes)``).

    Example:
        >>> data_line([], "the shipped Plastic", "middlebury2006", ["Plastic"])
        'data: the shipped Plastic (not installed; the real one: python -m data_fetch fetch middlebury2006 --only HalfSize/Plastic)'
    """
    parts = [copy.describe() if isinstance(copy, SceneCopy) else str(copy) for copy in copies]
    if fallback:
        parts.append(f"{fallback} ({why}; the real one: {fetch_command(dataset, *scenes)})")
    return "data: " + "; ".join(parts)


def depthcomp_hole_file(copy: SceneCopy, dest=None) -> Path | None:
    """DepthComp's hole file for a scene copy (Plastic only): one in its own folder, else the one installed in
    the data root (``depthcomp/plastic-disp-hole.png``), else the shipped quarter-size one; None for another scene."""
    if copy.name != "Plastic":
        return None
    from .samples import sample_scene

    for candidate in (copy.folder / DEPTHCOMP_FILE, data_root(dest) / "depthcomp" / DEPTHCOMP_FILE,
                      sample_scene("Plastic") / DEPTHCOMP_FILE):
        if candidate.is_file():
            return candidate
    return None
