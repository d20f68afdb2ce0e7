"""``python -m data_fetch list [NAME]`` / ``python -m data_fetch fetch NAME [--dest ROOT] [--from DIR] ...``."""
from __future__ import annotations

import argparse
import sys

from . import DATASETS, FetchError, ManualDownloadRequired, describe, fetch
from .listing import describe_dataset
from .local import install_from


def main(argv=None) -> int:
    """Command-line entry point; returns the exit code (0 ok, 1 error, 2 manual step needed)."""
    parser = argparse.ArgumentParser(prog="python -m data_fetch", description="Fetch the paper's datasets, verified.")
    sub = parser.add_subparsers(dest="command", required=True)
    listing = sub.add_parser("list", help="every dataset with its size, licence and what the kit uses it for; "
                                          "with NAME, its scenes, sizes and files, which are pixel-pinned, and "
                                          "what of it is installed")
    listing.add_argument("name", nargs="?", choices=sorted(DATASETS), help="one dataset (default: all, in brief)")
    listing.add_argument("--dest", help="data root (default: $DDP_DATA, else the user data dir)")
    get = sub.add_parser("fetch", help="download (or take a manual download), verify and unpack a dataset")
    get.add_argument("name", choices=sorted(DATASETS))
    get.add_argument("--dest", help="data root (default: $DDP_DATA, else the user data dir)")
    get.add_argument("--only", action="append", metavar="WHICH", help="only these files: a scene (Plastic), a folder (HalfSize, HalfSize/Plastic) or a glob (HalfSize/P*); repeatable")
    get.add_argument("--trust-first-download", action="store_true",
                     help="accept unverified files once, record their SHA-256 next to the data, verify later fetches")
    get.add_argument("--from", dest="source", metavar="DIR",
                     help="install from this local folder instead of downloading (verified first; DIR is only read)")
    get.add_argument("--retries", type=int, default=3, help="retries after a dropped connection (default 3)")
    get.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.command == "list":
        try:
            print(describe() if args.name is None else describe_dataset(args.name, args.dest))
        except ValueError as error:  # a blank $DDP_DATA or --dest
            print(f"error: {error}", file=sys.stderr)
            return 1
        return 0
    if args.retries < 0:
        print(f"error: --retries must be 0 or more, got {args.retries}", file=sys.stderr)
        return 1
    if args.source is not None:
        try:
            result = install_from(args.name, args.source, dest=args.dest, only=args.only,
                                  trust_first_download=args.trust_first_download)
        except (FetchError, ValueError, OSError) as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
        if not (result.installed or result.present):
            print(f"error: {args.source} holds none of the selected {args.name} files", file=sys.stderr)
            return 1
        return 0
    try:
        paths = fetch(args.name, dest=args.dest, only=args.only, trust_first_download=args.trust_first_download,
                      retries=args.retries, progressbar=not args.no_progress)
    except ManualDownloadRequired as error:
        print(error)
        return 2
    except (FetchError, ValueError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(f"{args.name}: {len(paths)} file(s) verified in {paths[0].parent if paths else '-'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
