"""How far each notebook check that reads a fit is from failing, over fit seeds: what a change to a profile's
size or budget must keep (a check that holds on seed 0 alone is luck, not a margin).

    python benchmarks/notebook_margins.py                              # `ci`, fit seeds 0-2, every notebook
    python benchmarks/notebook_margins.py --channels 8 16 32 64        # the same with another UNet at `ci`
    python benchmarks/notebook_margins.py --only 04_ 12_ --seeds 0 1   # some notebooks, some seeds

Each notebook runs whole in a fresh kernel (nbclient, one torch thread, no fit cache), with a first cell
added that moves every fit's seed by ``1_000_000 × seed`` (the scenes and holes stay those the notebook
draws: only the nets' weights, input noise and held-out pixels change) and, with ``--channels``, the profile's
UNet widths. A last cell added prints each check's margin (how far from failing; > 0 passes); a check whose
cell errored prints None. Two notebooks run side by side (``--jobs``), each on one thread.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _common import parse_args, positive_int  # noqa: E402

NOTEBOOKS = HERE.parent / "notebooks"
SEED_STEP = 1_000_000  # a fit seed below it is moved; one at or above it was moved already (dataclasses.replace)

# notebook prefix → {check: expression of its margin, > 0 where the check passes}, in the notebook's names
MARGINS = {
    "01_": {"best PSNR - noisy (dB)": "best_psnr - noisy_psnr",
            "inpainting - (masked + 3 dB)": "psnr_vs_clean(inpaint.image) - psnr_vs_clean(masked) - 3"},
    "02_": {"2 - DDP / nearest (holes)": "2 - table['DDP depth-only']['holes'] / table['nearest']['holes']"},
    "03_": {"depth-only - rgbd (edge band)": "table['d']['edge band'] - table['rgbd']['edge band']"},
    "04_": {"1.25 - warp ratio": "1.25 - ratio"},
    "05_": {"D - RGBD+warp (mean)": "mean['UNet + D'] - mean['UNet + RGBD + warp']"},
    "07_": {"min recall gain": "min(recall_gain.values())"},
    "08_": {"holes bad - SGM+DDP (D1-all, min)":
            "min(table[(p, 'SGM (holes bad)')]['D1-all'] - table[(p, 'SGM + DDP')]['D1-all'] "
            "for p in {k[0] for k in table})"},
    "09_": {"3 - DDP / linear (last)": "SANE_FACTOR - ratio"},
    "11_": {"recall SGM+DDP - SGM": "rows['SGM+DDP']['R'] - rows['SGM']['R']"},
    "12_": {"recall MVS+DDP - MVS": "table4['MVS+DDP']['R'] - table4['MVS']['R']"},
}

FIRST_CELL = """\
import dataclasses as _dc
import ddp_lite.method.paper.config as _pc
import ddp_lite.method.profiles as _profiles
_init = _pc.PaperConfig.__init__
def _moved(self, *args, **kwargs):
    _init(self, *args, **kwargs)
    if self.seed < {step}:
        object.__setattr__(self, "seed", self.seed + {offset})
_pc.PaperConfig.__init__ = _moved
if {channels!r} is not None:
    _profiles.PROFILES["ci"] = _dc.replace(_profiles.PROFILES["ci"], channels={channels!r})
"""

LAST_CELL = """\
import json as _json
_margins = {{}}
for _name, _expression in {margins!r}.items():
    try:
        _margins[_name] = float(eval(_expression))
    except Exception:
        _margins[_name] = None
print("MARGINS " + _json.dumps(_margins))
"""


def run_one(path: Path, seed: int, channels, profile: str) -> dict:
    """Run one notebook with its fits' seeds moved by ``seed``; its margins, failed cells and seconds."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    margins = next((m for prefix, m in MARGINS.items() if path.name.startswith(prefix)), {})
    nb.cells.insert(0, nbformat.v4.new_code_cell(FIRST_CELL.format(step=SEED_STEP, offset=SEED_STEP * seed,
                                                                  channels=channels)))
    nb.cells.append(nbformat.v4.new_code_cell(LAST_CELL.format(margins=margins)))
    env = {**os.environ, "DDP_PROFILE": profile, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    env.pop("DDP_CACHE", None)
    start = time.perf_counter()
    client = NotebookClient(nb, timeout=1800, allow_errors=True, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    with client.setup_kernel(env=env):
        for index, cell in enumerate(nb.cells):
            if cell.cell_type == "code":
                client.execute_cell(cell, index)
    failed = [i for i, c in enumerate(nb.cells[1:-1]) if c.cell_type == "code"
              and any(o.get("output_type") == "error" for o in c.outputs)]
    printed = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.get("output_type") == "stream")
    found = json.loads(printed.split("MARGINS ", 1)[1]) if "MARGINS " in printed else {}
    return {"notebook": path.stem, "seed": seed, "channels": channels, "profile": profile, "margins": found,
            "failed_cells": failed, "seconds": round(time.perf_counter() - start, 1)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", default="ci", choices=("ci", "class"))
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--channels", type=positive_int, nargs="+",
                        help="the `ci` UNet's widths (default: the profile's)")
    parser.add_argument("--only", nargs="+", default=[], help="notebook name prefixes, e.g. 04_ 12_")
    parser.add_argument("--jobs", type=positive_int, default=2, help="notebooks side by side (one thread each)")
    parser.add_argument("--out", type=Path, help="append one JSON row per notebook run")

    def check(args):
        if any(s < 0 for s in args.seeds):
            raise ValueError(f"--seeds must be >= 0, got {args.seeds}")
        if args.channels is not None and len(args.channels) < 2:
            raise ValueError(f"--channels needs at least two widths, got {args.channels}")
        if not all(any(p.name.startswith(o) for p in NOTEBOOKS.glob("*.ipynb")) for o in args.only):
            raise ValueError(f"--only: no notebook starts with one of {args.only}")

    args = parse_args(parser, argv, check)
    notebooks = [p for p in sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))
                 if any(p.name.startswith(prefix) for prefix in MARGINS)
                 and (not args.only or any(p.name.startswith(o) for o in args.only))]
    channels = tuple(args.channels) if args.channels else None
    jobs = [(p, seed) for seed in args.seeds for p in notebooks]
    rows = []
    with ThreadPoolExecutor(args.jobs) as pool:
        for row in pool.map(lambda job: run_one(job[0], job[1], channels, args.profile), jobs):
            rows.append(row)
            print(json.dumps(row), flush=True)
            if args.out:
                with open(args.out, "a", encoding="utf-8") as handle:
                    handle.write(json.dumps(row) + "\n")
    print(f"\nmargins (> 0 passes), profile {args.profile}, UNet {channels or 'the profile’s'}, "
          f"fit seeds {args.seeds}:")
    for p in notebooks:
        for name in next(m for prefix, m in MARGINS.items() if p.name.startswith(prefix)):
            values = [r["margins"].get(name) for r in rows if r["notebook"] == p.stem]
            shown = ", ".join("error" if v is None else f"{v:+.3f}" for v in values)
            print(f"  {p.stem[:3]} {name:38s} {shown}")
    for r in rows:
        if r["failed_cells"]:
            print(f"  {r['notebook']} seed {r['seed']}: cells {r['failed_cells']} raised")


if __name__ == "__main__":
    main()
