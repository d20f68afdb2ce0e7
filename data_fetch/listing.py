"""``python -m data_fetch list NAME``: one dataset's scenes, sizes and files, which are pixel-pinned, and what of
it is installed in the data root."""
from __future__ import annotations

from ddp_lite.data.installed import data_root, fetch_command, scene_copies

from .registry import MEMBER_CANDIDATES, Dataset, get_dataset

__all__ = ["describe_dataset", "scene_files"]


def _split(name: str) -> tuple[str, str, str] | None:
    """A file name → (scene, size, file) where the name says so, else None: ``HalfSize/Plastic/view1.png``,
    ``MiddEval3/trainingQ/Piano/im0.png``, ``Adirondack-perfect.zip``."""
    parts = name.split("/")
    if len(parts) == 3:
        return parts[1], parts[0], parts[2]
    if len(parts) == 4 and parts[1] == "trainingQ":
        return parts[2], parts[1], parts[3]
    if len(parts) == 1 and name.endswith(("-perfect.zip", "-imperfect.zip")):
        scene, variant = name[:-4].rsplit("-", 1)
        return scene, variant, name
    return None


def scene_files(dataset: Dataset) -> dict[str, dict[str, dict[str, str]]]:
    """{scene: {size: {file: how it is verified}}} of a dataset's files and pinned archive members that belong
    to a scene; 'pixel-pinned', 'sha256' or 'unverified' (a member of an archive: 'in <archive>, pixel-pinned'
    or 'in <archive>')."""
    out: dict[str, dict[str, dict[str, str]]] = {}
    for entry in dataset.files:
        split = _split(entry.name)
        if split:
            how = "pixel-pinned" if entry.pixel_sha256 else "sha256" if entry.sha256 else "unverified"
            out.setdefault(split[0], {}).setdefault(split[1], {})[split[2]] = how
        pins = dict(entry.members)
        for member in MEMBER_CANDIDATES.get(dataset.name, ()):
            split = _split(member)
            in_this = any(member.endswith("/" + f) for f in _archive_files(entry.name))
            if split and in_this:
                how = f"in {entry.name}" + (", pixel-pinned" if member in pins else "")
                out.setdefault(split[0], {}).setdefault(split[1], {})[split[2]] = how
    return out


def _archive_files(archive: str) -> tuple[str, ...]:
    from .registry import MIDDEVAL3_Q_DATA_FILES, MIDDEVAL3_Q_GT_FILES  # the two archives of middlebury2014q

    return {"MiddEval3-data-Q.zip": MIDDEVAL3_Q_DATA_FILES, "MiddEval3-GT0-Q.zip": MIDDEVAL3_Q_GT_FILES}.get(archive, ())


def _count(files: dict[str, str]) -> str:
    pinned = sum(1 for how in files.values() if "pixel-pinned" in how)
    count = f"{len(files)} file{'s' if len(files) != 1 else ''}"
    return f"{count}, {pinned} pinned" if pinned else count


def describe_dataset(name: str, dest=None) -> str:
    """The text ``python -m data_fetch list NAME`` prints (ValueError listing the names for an unknown one)."""
    dataset = get_dataset(name)
    lines = [f"{dataset.name}  —  {dataset.title}", f"    page     {dataset.homepage}",
             f"    size     {dataset.size_note}", ""]
    scenes = scene_files(dataset)
    if scenes:
        sizes = sorted({size for per_size in scenes.values() for size in per_size},
                       key=lambda s: ("FullSize", "HalfSize", "ThirdSize", "perfect", "imperfect").index(s)
                       if s in ("FullSize", "HalfSize", "ThirdSize", "perfect", "imperfect") else 9)
        every = sorted({f.replace(scene, "<Scene>") for scene, per_size in scenes.items()
                        for files in per_size.values() for f in files})
        lines.append(f"{len(scenes)} scenes × sizes {', '.join(sizes)}; a scene's files: {', '.join(every)}")
        lines.append(f"{'scene':<14}" + "".join(f"{size:<22}" for size in sizes))
        for scene, per_size in scenes.items():
            lines.append(f"{scene:<14}" + "".join(f"{_count(per_size[s]) if s in per_size else '-':<22}" for s in sizes))
        pinned = sorted({f"{scene} {size}" for scene, per_size in scenes.items() for size, files in per_size.items()
                         if any("pixel-pinned" in how for how in files.values())})
        lines.append(f"pixel-pinned (verified by decoded content, no trust flag needed): {', '.join(pinned) or 'none'}")
        archives = [f.name for f in dataset.files if f.unpack and not _split(f.name)]
        if archives:
            lines.append(f"archives {', '.join(archives)} hold every scene (unverified archives: fetch them with "
                         f"--trust-first-download; their members above are checked after unpacking)")
    else:
        for entry in dataset.files:
            how = "pixel-pinned" if entry.pixel_sha256 else "sha256" if entry.sha256 else "unverified"
            lines.append(f"    {entry.name:<40} {how}{' (archive)' if entry.unpack else ''}")
    root = data_root(dest) / dataset.name
    installed = scene_copies(root)
    lines.append("")
    if installed:
        lines.append(f"installed in {root}:")
        for scene, copies in installed.items():
            lines.append(f"    {scene:<12} " + "; ".join(
                f"{c.size or c.folder.name}" + ("" if c.complete else f" (lacks {', '.join(c.missing)})")
                for c in copies))
    else:
        present = root.is_dir() and any(p.is_file() for p in root.rglob("*"))
        lines.append(f"installed in {root}: {'files, but no complete scene' if present else 'nothing yet'}")
    example = next(iter(scenes), None)
    if example and not any(f.unpack and not _split(f.name) for f in dataset.files):
        lines.append(f"fetch a scene: {fetch_command(dataset.name, example)}   (--only takes a scene, e.g. "
                     f"--only {example} for every size of it, a folder or a glob; --from DIR installs a local copy)")
    else:
        lines.append(f"fetch it: {fetch_command(dataset.name)}")
    return "\n".join(lines)
