"""What the benchmark scripts share: the size/profile/threads arguments and the profile they select."""
from __future__ import annotations

import argparse
import dataclasses

import torch

from ddp_lite.method.profiles import get_profile


def add_profile_args(parser: argparse.ArgumentParser) -> None:
    """``--size H W``, ``--profile`` and ``--threads``."""
    parser.add_argument("--size", type=int, nargs=2, metavar=("H", "W"), help="image size (default: the profile's)")
    parser.add_argument("--profile", default="class")
    parser.add_argument("--threads", type=int, default=1)


def profile_from_args(args):
    """Set torch's thread count and return the chosen profile, resized by ``--size``."""
    torch.set_num_threads(args.threads)
    profile = get_profile(args.profile)
    return dataclasses.replace(profile, size=tuple(args.size)) if args.size else profile
