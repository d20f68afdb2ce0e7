"""The notebooks' prose says what is true now, and never quotes a figure that a run prints.

A notebook's Markdown is read by a student who has just run it, at whatever profile: a figure
typed into the prose drifts from what the run printed the moment a recipe, a seed or a library
changes. So the figures of a run are printed by code cells, and the prose keeps the story. Two
rules, checked on every Markdown cell of every notebook (instructor's copy, expected answers
included), without executing anything:

1. **No history.** How the kit got here (earlier recipes, old runs, what changed) lives in
   ``docs/studies/``, not in a notebook: no cell uses a phrase of ``HISTORY_PHRASES``, and none sends the
   reader to a history page (``HISTORY_PAGES``) for what a notebook found.

2. **No run figure in prose.** A *sentence* that names a profile (``ci``/``class``/``paper`` in
   backticks, or "at ci", "at class") may not hold a *result number*: a decimal (``1.287``,
   ``+2.5``, ``0.44 dB``) or a percentage (``38.9 %``, ``67 %``). What does not count as a result:
   a number in a code span or in ``$...$`` maths (the notebook's own variables and formulas), and a
   setting or threshold written after ``=``, ``≤``, ``≥``, ``<``, ``>`` or ``×`` (γ = 0.98,
   λ = 0.5, p ≥ 0.1, ×0.01). Sizes (48×64) and fractions (1/30) are not decimals. The paper's own
   figures are welcome wherever no profile is named in the same sentence; a sentence that needs
   both says "the paper: ..." in a sentence of its own. Sentences end at ``. `` / ``; `` / ``: ``
   / ``? `` followed by a space, at a blank line, and at each list item.

And each notebook whose "What we saw" speaks of this run's figures has a code cell that prints them
(``RUN_FIGURES_PRINTED``): the prose points at it instead of repeating it.
"""
import re
from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
SOURCES = sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))

HISTORY_PHRASES = ("earlier recipe", "earlier run", "before it took", "notes from earlier", "before them",
                   "in an earlier", "an older", "used to be", "no longer", "was last at", "once passed",
                   "what we found (", "before the colour image joined", "before `ci`", "before `class`")
HISTORY_PAGES = ("benchmark_history.md", "notebook_notes.md", "tuning_history.md")

PROFILE = re.compile(r"`(?:ci|class|paper)`|\bat (?:ci|class)\b", flags=re.I)
RESULT = re.compile(r"(?<![\w.=≤≥<>×/])(?:[+−-]\s?)?(\d+(?:\.\d+)?\s?%|\d+\.\d+)")
# "p ≥ ", "×", "γ = (0.98, ": what follows is a setting or a threshold, not a result
SETTING_BEFORE = re.compile(r"(?:[=≤≥<>×]\s*[(\[]?\s*|=\s*\([^()]*)$")
SENTENCE_END = re.compile(r"(?<=[.;:?])\s+(?=\S)|\n\s*\n|\n\s*(?=[-*]\s|\d+\.\s)")

# notebook stem → a phrase of the code cell that prints the run's figures its conclusion speaks of
RUN_FIGURES_PRINTED = {
    "01_deep_image_prior": "this run:",
    "02_depth_only_prior": "this run:",
    "03_rgbd_prior": "this run:",
    "04_warp_loss": "this run:",
    "05_ablation": "this run:",
    "06_classical_baselines": "this run:",
    "07_fusion_and_views": "this run:",
    "08_stereo_d1": "this run:",
    "09_real_data": "this run:",
    "10_beyond_the_paper": "this run:",
    "12_mvs_and_kinect": "this run:",
}


def _markdown(path):
    return [(i, cell.source) for i, cell in enumerate(nbformat.read(path, as_version=4).cells)
            if cell.cell_type == "markdown"]


def _prose(text: str) -> str:
    """``text`` without code spans, code blocks, maths and HTML comments (what a result is not)."""
    for pattern in (r"```.*?```", r"\$\$.*?\$\$", r"\$[^$\n]+\$", r"`[^`\n]*`", r"<!--.*?-->"):
        text = re.sub(pattern, lambda m: m.group(0) if m.group(0) in ("`ci`", "`class`", "`paper`") else " ",
                      text, flags=re.S)
    return text


def run_figures(text: str) -> list[tuple[str, str]]:
    """[(figure, sentence)] for every result number in a sentence of ``text`` that names a profile."""
    found = []
    for sentence in SENTENCE_END.split(_prose(text)):
        if not PROFILE.search(sentence):
            continue
        for match in RESULT.finditer(sentence):
            if not SETTING_BEFORE.search(sentence[:match.start()]):
                found.append((match.group(1), " ".join(sentence.split())))
    return found


@pytest.mark.parametrize("text, figures", [
    ("At `ci` DDP ranks 3rd (1.259 px).", ["1.259"]),
    ("At class the sparse set's D1 is 38.9 % against 16 %.", ["38.9 %", "16 %"]),
    ("The paper's DDP is 0.34× linear. At `ci` see the printed table.", []),
    ("At `ci` γ = (0.98, 0.01) and λ = 0.5; `reg_noise_std = 1/30`, 48×64 images, p ≥ 0.1.", []),
    ("At `ci` the cell prints `round(x, 3)`; $\\lambda_z = 0.8$.", []),
    ("- first item at `class`\n- 2.5 dB in another item", []),
])
def test_the_rule_finds_run_figures_and_spares_settings_and_the_papers_figures(text, figures):
    assert [figure for figure, _ in run_figures(text)] == figures


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.stem[:2])
def test_no_markdown_cell_tells_the_kits_history(path):
    for index, text in _markdown(path):
        lowered = " ".join(text.lower().split())
        said = [p for p in HISTORY_PHRASES + HISTORY_PAGES if p in lowered]
        assert not said, f"{path.name}, cell {index}: {said} is history: it belongs in the record of studies, docs/studies/ ({text[:120]!r})"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.stem[:2])
def test_no_markdown_cell_quotes_a_figure_of_a_run(path):
    for index, text in _markdown(path):
        quoted = run_figures(text)
        assert not quoted, (f"{path.name}, cell {index}: a run's figure typed into the prose drifts from what the "
                            f"run prints; print it from a code cell: {quoted}")


@pytest.mark.parametrize("stem", sorted(RUN_FIGURES_PRINTED))
def test_the_conclusion_has_a_code_cell_printing_the_runs_figures(stem):
    cells = nbformat.read(NOTEBOOKS / f"{stem}.ipynb", as_version=4).cells
    conclusion = next(i for i, c in enumerate(cells) if c.cell_type == "markdown" and "## What we saw" in c.source)
    printing = [c for c in cells[:conclusion + 1] if c.cell_type == "code" and RUN_FIGURES_PRINTED[stem] in c.source]
    assert printing, f"{stem}: no code cell before 'What we saw' prints {RUN_FIGURES_PRINTED[stem]!r}"
