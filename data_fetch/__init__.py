"""data_fetch: get the paper's real datasets onto disk, verified (``python -m data_fetch ...``).

    python -m data_fetch list                                   # what exists, size, licence, use
    python -m data_fetch list middlebury2006                    # its scenes, sizes, files, pins; what is installed
    python -m data_fetch fetch middlebury2014 --only 'Adirondack-*' --trust-first-download
    python -m data_fetch fetch kitti2015                        # prints what to download by hand
    python -m data_fetch fetch middlebury2006 --only HalfSize/Plastic                # one scene, one size
    python -m data_fetch fetch middlebury2006 --from DIR --only Plastic   # from a local copy, every size it has

Where data goes: ``--dest DIR``, else ``$DDP_DATA``, else platformdirs' ``user_data_dir("ddp-lite")``;
each dataset in its own folder (``ddp_lite.data.installed.data_root``). ``ddp_lite.data.installed`` finds what
landed there for every reader (notebooks, ``ddp-lite complete --scene``, the benchmarks); the loaders in
``ddp_lite.data`` read it. ``--only`` takes a scene name, a folder or a glob (``data_fetch.select``).

How files are trusted (the honest part). The kit was written on machines that cannot reach the
dataset servers, so no byte hash of a downloaded file could be measured and none is invented:
every ``sha256`` in ``registry.py`` is ``None`` (*unverified*). Two things verify files anyway:

* **Decoded-pixel hashes** (``pixels.py``): for the Middlebury files of which offline copies could be
  read (the HalfSize files of 6 scenes of 2005 and 6 of 2006, the quarter-size files of 7 MiddEval3
  training scenes, DepthComp's Plastic holes), ``pixel_sha256`` of the decoded content (PNG pixels,
  PFM values, calib/dmin text tokens) is pinned (``pinned_pixels.py``, written by ``pin_pixels.py``).
  It is stable under PNG re-encoding. ``fetch`` checks it after a download (a mismatch is deleted and
  refused), and for archives checks the pinned files they unpack to; ``fetch NAME --from DIR``
  (``local.py``) checks it before anything is installed from a local folder. These pins say "same
  content as the offline copies", whose provenance the project recorded; they were not compared
  with the official servers.
* **Trust on first use**, for everything else (all archives, the FullSize/ThirdSize files, KITTI, ...):
  ``fetch`` refuses an unverified file by default. With ``--trust-first-download`` it accepts what
  arrives: only bytes that fetch itself downloads, a manual download you placed, or a file copied
  by ``--from`` (a file already under the final name of a downloadable file is refused, not trusted).
  It records the SHA-256 in ``<dataset>/registry.json`` next to the data, with whose bytes they were
  (``bytes_from``), and from then on verifies every fetch against that record. Once somebody has
  checked a file against its source, its hash belongs in ``registry.py``.

What ``fetch`` guarantees:

* pooch drives every download (``pooch.retrieve`` with the hash); our ``ResumableDownloader``
  streams into ``<file>.part`` and resumes with HTTP Range after a dropped connection (retries,
  exponential back-off, tqdm progress bar). A file gets its final name only after its hash
  matched; on a mismatch it is deleted (no final file, no ``.part``) and ``ChecksumError`` says so.
* Offline or server down: a ``FetchError`` that says so and keeps the ``.part`` for resuming.
* One install of a dataset folder at a time (``install_lock.py``): a second ``fetch`` or ``--from`` into it
  waits, saying so, so no record in ``registry.json`` is lost; the temporary files of an install that was
  killed are removed (and named) by the next one. Text files are compared as text (a byte-order mark and
  CRLF line ends make no difference); a file taken on trust is said to be unverified.
* Nothing is fetched twice: a file present with the right hash is not requested again, and an
  archive already unpacked (marker ``.<file>.unpacked``) is not unpacked again; its unpacked files
  are checked against it on every fetch (a missing one is unpacked again, one of another size is
  kept and named).
* Archives are unpacked safely (``unpack.py``): absolute names, ``..``, links and special files,
  and two members landing on one file (``./a.txt`` and ``a.txt``, another case), refuse the whole
  archive before anything is written.
* Datasets behind a form (KITTI, Tanks and Temples): ``fetch`` prints exactly what to download and
  where to put it (``ManualDownloadRequired``, exit code 2), then, once the files are there,
  verifies (or records, with the flag) and unpacks them. A user's file that fails its hash is
  renamed ``<file>.rejected`` (``.rejected-2``, ... after the first: never over an earlier one), not deleted.
"""
from .download import ChecksumError, FetchError, ResumableDownloader
from .fetch import ENV_VAR, REGISTRY_FILE, ManualDownloadRequired, UnpinnedFileError, data_dir, fetch
from .registry import DATASETS, Dataset, RemoteFile, get_dataset
from .unpack import UnsafeArchiveError, safe_extract

__all__ = ["fetch", "data_dir", "DATASETS", "Dataset", "RemoteFile", "get_dataset", "ResumableDownloader",
           "safe_extract", "FetchError", "ChecksumError", "UnsafeArchiveError", "ManualDownloadRequired",
           "UnpinnedFileError", "ENV_VAR", "REGISTRY_FILE", "describe"]


def describe() -> str:
    """The text ``python -m data_fetch list`` prints: a README-style preamble, then one block per dataset."""
    lines = ["ddp-lite datasets (python -m data_fetch fetch NAME [--dest DIR] [--only SCENE|FOLDER|GLOB] "
             "[--trust-first-download])",
             "python -m data_fetch list NAME: a dataset's scenes, sizes and files, which are pixel-pinned, and what "
             "of it is installed",
             "",
             f"Data root: --dest, else ${ENV_VAR}, else {data_dir()}",
             "Hashes: no byte SHA-256 could be measured (the servers were unreachable when the registry was",
             "written). 'pixel hash' files are verified by their decoded content (pinned from offline copies;",
             "stable under PNG re-encoding), after a download or before --from DIR installs them. Everything",
             "else, archives included, is 'unverified': fetch refuses it unless you pass --trust-first-download,",
             "then records the SHA-256 of what arrives in <dataset>/registry.json and checks every later fetch",
             "against it. No size was measured here; where one is given, it is what the dataset's page states.",
             ""]
    for d in DATASETS.values():
        n_bytes = sum(1 for f in d.files if f.sha256)
        n_pixels = sum(1 for f in d.files if f.pixel_sha256 and not f.sha256)
        n_archives = sum(1 for f in d.files if f.unpack)
        n_members = sum(len(f.members) for f in d.files)
        how = "automatic" if d.automatic else "MANUAL download (fetch prints the steps)"
        lines += [f"{d.name}  —  {d.title}",
                  f"    files    {len(d.files)} ({how}); pixel hash (from offline copies, decoded pixels, stable "
                  f"under re-encoding) for {n_pixels}, byte SHA-256 for {n_bytes}, unverified for "
                  f"{len(d.files) - n_pixels - n_bytes}"]
        if n_archives:
            lines.append(f"    archives {n_archives}, trust-on-first-download (no byte hash measured)"
                         + (f"; {n_members} unpacked file(s) checked by pixel hash" if n_members else ""))
        lines += [
                  f"    size     {d.size_note}",
                  f"    licence  {d.licence}",
                  f"    use      {d.use}",
                  f"    page     {d.homepage}"]
        lines += [f"    note     {note}" for note in d.notes]
        lines.append("")
    return "\n".join(lines)
