"""data_fetch: get the paper's real datasets onto disk, verified (``python -m data_fetch ...``).

    python -m data_fetch list                                   # what exists, size, licence, use
    python -m data_fetch fetch middlebury2014 --only 'Adirondack-*' --trust-first-download
    python -m data_fetch fetch kitti2015                        # prints what to download by hand

Where data goes: ``--dest DIR``, else ``$DDP_DATA``, else platformdirs' ``user_data_dir("ddp-lite")``;
each dataset in its own folder. Loaders in ``ddp_lite.data.datasets`` read what lands there.

How files are trusted (the honest part). Every file in ``registry.py`` carries a SHA-256, or
``None`` = *unverified*. The kit was written on machines that cannot reach the dataset servers,
so no hash could be computed, and none is invented: today **every** entry is unverified. ``fetch``
therefore refuses an unverified file by default. With ``--trust-first-download`` it accepts what
arrives (trust on first use): only bytes that fetch itself downloads, or a manual download you
placed (a file already under the final name of a downloadable file is refused, not trusted). It
records the SHA-256 in ``<dataset>/registry.json`` next to the data, with whose bytes they were
(``bytes_from``), and from then on verifies every fetch against that record, so a later change is caught even
though the first copy was taken on trust. Once somebody has checked a file against its source,
its hash belongs in ``registry.py`` and the flag is no longer needed for it.

What ``fetch`` guarantees:

* pooch drives every download (``pooch.retrieve`` with the hash); our ``ResumableDownloader``
  streams into ``<file>.part`` and resumes with HTTP Range after a dropped connection (retries,
  exponential back-off, tqdm progress bar). A file gets its final name only after its hash
  matched; on a mismatch it is deleted (no final file, no ``.part``) and ``ChecksumError`` says so.
* Offline or server down: a ``FetchError`` that says so and keeps the ``.part`` for resuming.
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
    lines = ["ddp-lite datasets (python -m data_fetch fetch NAME [--dest DIR] [--only GLOB] [--trust-first-download])",
             "",
             f"Data root: --dest, else ${ENV_VAR}, else {data_dir()}",
             "Hashes: no SHA-256 below could be computed (the servers were unreachable when the registry was",
             "written), so each file is 'unverified'. fetch refuses unverified files unless you pass",
             "--trust-first-download: it then records the hash of what arrives in <dataset>/registry.json and",
             "checks every later fetch against it. No size was measured here; where one is given, it is what",
             "the dataset's own page states.",
             ""]
    for d in DATASETS.values():
        n_pinned = sum(1 for f in d.files if f.sha256)
        how = "automatic" if d.automatic else "MANUAL download (fetch prints the steps)"
        lines += [f"{d.name}  —  {d.title}",
                  f"    files    {len(d.files)} ({how}); SHA-256 pinned for {n_pinned}, unverified for "
                  f"{len(d.files) - n_pinned}",
                  f"    size     {d.size_note}",
                  f"    licence  {d.licence}",
                  f"    use      {d.use}",
                  f"    page     {d.homepage}"]
        lines += [f"    note     {note}" for note in d.notes]
        lines.append("")
    return "\n".join(lines)
