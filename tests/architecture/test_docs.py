"""The pages a reader meets agree with what runs, and can be found.

- Every relative link in ``README.md``, ``docs/**/*.md`` and ``benchmarks/README.md`` reaches a file that
  exists, and a ``#fragment`` a heading of that page (GitHub's slugs); every ``docs/....md`` path named
  anywhere in the tree (code, tests, notebooks, pages) exists, so a moved page leaves no dangling name.
- The user pages (the README, ``docs/*.md``) send a reader into the record of studies (``docs/studies/``) only
  through its index, never to a study page for a figure.
- The README's profile table is the one :func:`~ddp_lite.method.profiles.profile_table` writes, and its
  figures are those of the configs the notebooks build.
- ``docs/results.md``'s per-scene table is what ``study_fill_blends.py per-case`` prints from the recorded
  rows, and the README's "Where DDP stands" rows are its means.
"""
import contextlib
import io
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
STUDIES = DOCS / "studies"
PAGES = [README, ROOT / "benchmarks" / "README.md"] + sorted(DOCS.rglob("*.md"))
USER_PAGES = [README] + sorted(DOCS.glob("*.md"))
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")


def _tracked(*suffixes) -> list[Path]:
    listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [ROOT / name for name in listed.splitlines() if name.endswith(suffixes) and (ROOT / name).is_file()]


def _text_outside_code(path: Path) -> str:
    """The page without its fenced code blocks (a shell line with brackets is no link)."""
    return re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.S | re.M)


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, markup and punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`|\*\*|\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    return {slug(h) for h in re.findall(r"^#+ (.+)$", _text_outside_code(path), flags=re.M)}


def relative_links(path: Path) -> list[str]:
    return [target for target in LINK.findall(_text_outside_code(path))
            if not re.match(r"[a-z][a-z0-9+.-]*:", target)]  # http:, https:, mailto: are not files


def test_the_slug_rule_matches_githubs_on_known_headings():
    assert slug("## Without a browser: `demo`, `complete`, Python".lstrip("# ")) == "without-a-browser-demo-complete-python"
    assert slug("Your own data: `ddp-lite sequence`") == "your-own-data-ddp-lite-sequence"
    assert slug("Grading, in full (as run)") == "grading-in-full-as-run"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_reaches_a_file_and_a_heading(page):
    broken = []
    for target in relative_links(page):
        file_part, _, fragment = target.partition("#")
        linked = (page.parent / file_part).resolve() if file_part else page
        if not linked.exists():
            broken.append(f"{target}: no such file")
        elif fragment and linked.suffix == ".md" and fragment not in anchors(linked):
            broken.append(f"{target}: no heading #{fragment} in {linked.relative_to(ROOT)}")
    assert not broken, f"{page.relative_to(ROOT)}: {broken}"


def test_every_docs_path_named_in_the_tree_exists():
    named = []
    for path in _tracked(".py", ".ipynb", ".md", ".txt", ".toml", ".sh", "Makefile"):
        for name in re.findall(r"\bdocs/\w[\w./-]*\.md\b", path.read_text(encoding="utf-8", errors="replace")):
            if not (ROOT / name).exists():
                named.append(f"{path.relative_to(ROOT)}: {name}")
    assert not named, named


@pytest.mark.parametrize("page", USER_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_a_user_page_enters_the_record_of_studies_only_through_its_index(page):
    into_record = [target for target in relative_links(page)
                   if (page.parent / target.partition("#")[0]).resolve().is_relative_to(STUDIES)]
    assert all((page.parent / t.partition("#")[0]).resolve() == STUDIES / "README.md" for t in into_record), (
        f"{page.relative_to(ROOT)} links study pages {into_record}: a current figure belongs on a user page "
        "(docs/results.md, benchmarks/README.md), the record's index is docs/studies/README.md")
    named = re.findall(r"docs/studies/(?!README\.md)[\w.-]+\.md", page.read_text(encoding="utf-8"))
    assert not named, f"{page.relative_to(ROOT)} names study pages {named}"


def test_the_record_and_the_user_pages_are_both_indexed():
    record = {p.name for p in STUDIES.glob("*.md")} - {"README.md"}
    index = (STUDIES / "README.md").read_text(encoding="utf-8")
    assert record and all(f"]({name})" in index for name in record), record
    users = {p.name for p in DOCS.glob("*.md")} - {"README.md"}
    listed = (DOCS / "README.md").read_text(encoding="utf-8")
    assert all(f"]({name}" in listed for name in users), users
    assert "(docs/README.md)" in README.read_text(encoding="utf-8")


# --- the profile table -------------------------------------------------------------------------------------

def _profile_rows() -> dict:
    text = README.read_text(encoding="utf-8")
    rows = re.findall(r"^\| `(\w+)`(?: \(default\))? \| (.+) \|$", text, flags=re.M)
    return {name: [cell.strip() for cell in cells.split(" | ")] for name, cells in rows if name in ("ci", "class", "paper")}


def test_the_readme_profile_table_is_written_from_the_profiles():
    from ddp_lite.method.profiles import TABLE_END, TABLE_START, profile_table
    text = README.read_text(encoding="utf-8")
    assert f"{TABLE_START}\n{profile_table()}\n{TABLE_END}" in text, (
        "README.md's profile table differs from the profiles: python -m ddp_lite.method.profiles README.md")


@pytest.mark.parametrize("name", ["ci", "class", "paper"])
def test_the_profile_tables_iterations_are_what_the_fits_and_notebook_01_run(name, monkeypatch):
    """The iteration counts in the README, read as a reader reads them, against the configs the kit builds:
    a depth fit's (``FitConfig.for_profile``) and notebook 01's image fits (the config its first cell builds)."""
    monkeypatch.setenv("DDP_PROFILE", name)
    from ddp_lite.method.config import FitConfig
    from ddp_lite.method.profiles import get_profile
    size, net, depth_fit, schedule, image_fit, _ = _profile_rows()[name]
    config = FitConfig.for_profile(name, variant="rgbd")
    assert int(re.search(r"\d+", depth_fit).group()) == config.resolved_iterations("rgbd")
    assert ("stops by itself" in depth_fit) == config.stopping.auto_stop
    depth_only = re.search(r"depth-only (\d+)", depth_fit) or re.search(r"(\d+)", depth_fit)  # none named: the same
    assert int(depth_only.group(1)) == FitConfig.for_profile(name, variant="d").resolved_iterations("d")
    assert size == "×".join(map(str, get_profile(name).size))
    cell = next(c for c in __import__("nbformat").read(ROOT / "notebooks" / "01_deep_image_prior.ipynb", 4).cells
                if c.cell_type == "code")
    scope: dict = {}
    setup = "\n".join(line for line in cell.source.splitlines()
                      if line.startswith(("from ddp_lite", "profile =", "H, W =", "ITERATIONS =", "config =")))
    exec(setup, scope)  # the notebook's own lines that build its image-fit config
    assert scope["config"].resolved_iterations("rgbd") == int(image_fit.split(",")[0])
    assert not scope["config"].stopping.auto_stop and image_fit.endswith("fixed")


# --- the results page and the README's standing table -----------------------------------------------------

RESULTS = ROOT / "benchmarks" / "results"
PER_CASE_ROWS = ("fill_blends_eighth_core.jsonl", "fill_blends_eighth_rgbd_core.jsonl",
                 "fill_blends_eighth_noholes.jsonl", "fill_blends_eighth_noholes_rgbd.jsonl")


@pytest.fixture(scope="module")
def per_case_table() -> str:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import study_fill_blends
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        study_fill_blends.per_case(*(RESULTS / name for name in PER_CASE_ROWS[:2]),
                                   tuple(RESULTS / name for name in PER_CASE_ROWS[2:]))
    return printed.getvalue().strip()


def test_the_results_page_per_scene_table_is_what_the_rows_print(per_case_table):
    page = (DOCS / "results.md").read_text(encoding="utf-8")
    block = re.search(r"^```\n(61 cases.*?)\n```", page, flags=re.S | re.M).group(1)
    assert [line.rstrip() for line in block.splitlines()] == [line.rstrip() for line in per_case_table.splitlines()]
    assert all(name in page for name in PER_CASE_ROWS)  # the command that prints it again


def test_the_readmes_standing_rows_are_the_per_scene_tables_means(per_case_table):
    means = {kind: re.findall(r"([\d.]+) \(([\d.]+)\)", line)
             for kind, line in re.findall(r"^mean: (\w+) \(n=\d+\)(.*)$", per_case_table, flags=re.M)}
    columns = {("kit", "rgbd"): 0, ("kit", "rgbd+warp"): 1, ("photo", "rgbd"): 2, ("photo", "rgbd+warp"): 3}
    text = README.read_text(encoding="utf-8")
    checked = 0
    for recipe, variant, cells in re.findall(r"^\| `(kit|photo)`, (rgbd(?:\+warp)?)²? \| (.+) \|$", text, flags=re.M):
        for kind, cell in zip(("depthcomp", "blobs", "sgbm", "occlusion", "all"), cells.split(" | ")):
            over_best, over_table6 = re.match(r"\**([\d.]+) / ([\d.]+)\**", cell).groups()
            assert (over_best, over_table6) == means[kind][columns[recipe, variant]], (recipe, variant, kind)
            checked += 1
    assert checked == 4 * 5


# --- names the pages give ----------------------------------------------------------------------------------

NAMING_FILES = [README, ROOT / "environment.txt", ROOT / "data_fetch" / "registry.py"] + USER_PAGES[1:]


@pytest.mark.parametrize("path", NAMING_FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_dotted_kit_name_a_page_gives_can_be_imported(path):
    """``ddp_lite.a.b.name`` in a page, the environment file or the data registry is a module, or an attribute
    of one: a reader who types it finds it."""
    import importlib
    missing = []
    for dotted in sorted(set(re.findall(r"\bddp_lite(?:\.\w+)+", path.read_text(encoding="utf-8")))):
        parts = dotted.split(".")
        for cut in range(len(parts), 0, -1):
            try:
                found = importlib.import_module(".".join(parts[:cut]))
            except ModuleNotFoundError:
                continue
            try:
                for attribute in parts[cut:]:
                    found = getattr(found, attribute)
            except AttributeError:
                missing.append(dotted)
            break
        else:
            missing.append(dotted)
    assert not missing, f"{path.relative_to(ROOT)}: {missing}"


def test_nyu_is_one_figure_of_the_paper_everywhere():
    """The paper's NYU v2 figure is its Fig. 8 (the eighth figure of paper.tex, ``fig:nyu``): every line of the
    tree that names NYU or Kinect with a figure number gives that one."""
    numbers = {}
    for path in _tracked(".py", ".ipynb", ".md", ".txt"):
        for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
            if re.search(r"NYU|Kinect", line):
                for number in re.findall(r"\bFig(?:\.|ure) (\d+)", line):
                    numbers.setdefault(number, []).append(str(path.relative_to(ROOT)))
    assert set(numbers) == {"8"}, numbers


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_user_page_quotes_a_test_count_or_make_tests_time(page):
    """The number of tests and how long ``make test`` takes change with every commit and machine: no user page
    or the benchmarks' current figures quotes them (the record of studies may, as history)."""
    if page.is_relative_to(STUDIES):
        return
    text = page.read_text(encoding="utf-8")
    counts = re.findall(r"\b\d[\d,]* (?:unit )?tests\b", text)
    times = re.findall(r"`make test`[^.|\n]{0,80}?\d+ (?:min|s)\b", text)
    assert not counts and not times, f"{page.relative_to(ROOT)}: {counts + times}"
