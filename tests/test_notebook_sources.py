"""The committed notebooks are built from tools/notebooks/*.py: their cells must match the sources
(a notebook edited without its source, or a source edited without rebuilding, fails here)."""

import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from build_notebooks import parse  # noqa: E402

SOURCES = sorted((ROOT / "tools" / "notebooks").glob("[0-9][0-9]_*.py"))


def test_every_source_has_a_notebook_and_back():
    notebooks = {p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")}
    assert notebooks == {p.stem for p in SOURCES}


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.stem)
def test_committed_notebook_matches_its_source_and_was_executed(source):
    built = parse(source.read_text())
    committed = nbformat.read(ROOT / "notebooks" / f"{source.stem}.ipynb", as_version=4)
    assert [c.source for c in committed.cells] == [c.source for c in built.cells], \
        f"rebuild it: python tools/build_notebooks.py {source.stem[:2]}"
    code = [c for c in committed.cells if c.cell_type == "code"]
    assert all(c.get("execution_count") for c in code), "commit notebooks executed, outputs visible"


def test_readme_results_section_is_the_one_the_records_give():
    """The README's numbers are written by tools/readme_results.py from data/: none typed by hand."""
    from readme_results import BEGIN, END, README, section

    text = README.read_text()
    assert text.count(BEGIN) == 1 and text.count(END) == 1
    committed = BEGIN + text.split(BEGIN)[1].split(END)[0] + END
    assert committed == section(), "run `python tools/readme_results.py --write`"


# Numbers that may stand in a markdown cell: definitions and arithmetic of the book's set-up, not
# measurements (a measured number is rendered from computed values with ``vgai_lite.book.prose``).
# Besides these: integers up to 12 (counts, section and equation numbers), years, every number of
# the paper's tables (``vgai_lite.lab.paper``) and every value of the config objects.
DEFINED_NUMBERS = {
    "49": "the drones a panorama draws in a larger team (RenderConfig(nearest=49)): every other drone at N = 50",
    "360°": "the panorama's field of view",
    "90°": "one camera's horizontal field of view",
    "45°": "half a camera's field of view (the pinhole model)",
    "90%": "the top of a 10-90 % band", "95%": "a bootstrap 95 % interval",
    "100": "N' = 100 of Table 3 (ours); 100 steps per second at Ts = 0.01 s",
    "128": "panorama columns: 4 cameras x 32",
    "2048": "16 channels x 128 columns into the CNN's first fully connected layer",
    "400": "8 swarm states x 50 agents' images per stage-1 step",
    "800": "4 windows x 4 steps x 50 agents' images per stage-3 step",
    "125": "1 / 0.2^3, the 1/r^4 feature of a neighbour at 0.2 m",
    "7.07": "sqrt(50), the paper's disc radius taken literally",
    "2.66": "50^(1/4), the reference code's disc radius",
    "8.5": "6 sqrt(2), the largest closing speed of two drones at v_init = 3 m/s",
    "2.8°": "360° / 128 columns",
    "1e-9": "a test's tolerance",
    "20": "the potential's push at rho = 0.5 m, 2 rho (1/rho^4 + 1/rho^2) m/s^2",
    "20°": "the bearing of notebook 04's worked example",
    "180°": "a half turn of the world",
    "190": "a step late in a 200-step episode",
    "1.96": "the normal quantile of a two-sided 95 % interval",
    "10,000": "the random starts of the NaN property test (tests/test_numerical_safety.py)",
    "255": "10/255, the authors' test noise on 8-bit pixel values",
    "144": "the paper's camera rows (144 x 256 pixels)",
    "256": "the paper's camera columns (144 x 256 pixels)",
    "3.5": "the top of U(1.0, 3.5) m, the radius range of the authors' released training code",
    "0.005": "the top of a stage 1's sensor-noise range, a set-up of notebook 08's noise probe "
             "(stage1_capacity.py --noise-max 0,0.005)",
}


def _config_values() -> set:
    import dataclasses

    from vgai_lite.config import FlockConfig
    from vgai_lite.dagnn_training import DAGNNTrainConfig
    from vgai_lite.render import RenderConfig
    from vgai_lite.vgai_config import VGAITrainConfig
    from vgai_lite.vision import VisionConfig

    out = set()

    def walk(x):
        if dataclasses.is_dataclass(x):
            for f in dataclasses.fields(x):
                walk(getattr(x, f.name))
        elif isinstance(x, (tuple, list)):
            for y in x:
                walk(y)
        elif isinstance(x, (int, float)) and not isinstance(x, bool):
            out.add(float(x))

    from vgai_lite.lab.robustness import TARGETS, RobustnessConfig

    for c in (FlockConfig(), DAGNNTrainConfig(), VGAITrainConfig(), VisionConfig(), RenderConfig(), RobustnessConfig()):
        walk(c)
    walk(list(TARGETS.values()))
    return out


def _numbers_in(x) -> set:
    """Every number in a nested structure of dicts and lists (keys included): the paper's tables."""
    if isinstance(x, dict):
        return set().union(*(_numbers_in(k) | _numbers_in(v) for k, v in x.items())) if x else set()
    if isinstance(x, (list, tuple)):
        return set().union(*(_numbers_in(y) for y in x)) if x else set()
    return {float(x)} if isinstance(x, (int, float)) and not isinstance(x, bool) else set()


def undefined_numbers(markdown: str, allowed: set) -> list:
    """The numbers of a markdown text that are neither defined (DEFINED_NUMBERS, small integers,
    years) nor in ``allowed``: candidates for a measured number typed by hand."""
    import re

    text = re.sub(r"`[^`]*`", " ", markdown)                 # code: literals of the code it shows
    text = re.sub(r"\]\([^)]*\)", "]", text)                  # link targets
    text = re.sub(r"(?m)^#+\s*\d+\.", " ", text)              # a heading's section number
    text = re.sub(r"(?i)arXiv:\S+", " ", text)                  # references
    text = re.sub(r"(?i)(?:\beqs?\.|\bequations?|\bsections?|§|\btables?|\bfig(?:ure)?s?\.?|\bexercises?|"
                  r"\bnotebooks?)\s*[\d.,\-–ab ]+(?:and [\d.]+)?", " ", text)  # references
    bad = []
    for m in re.finditer(r"(?<![\w.])(\d[\d,]*(?:\.\d+)?(?:e-?\d+)?)(°|\s?%|×)?", text):  # "2.4×" a ratio, "12 × 128" a shape
        token = m.group(1).rstrip(",")
        suffix = (m.group(2) or "").strip()
        value = float(token.replace(",", ""))
        if value.is_integer() and (value <= 12 or 1990 <= value <= 2030):
            continue
        if token + suffix in DEFINED_NUMBERS or (not suffix and token in DEFINED_NUMBERS):
            continue
        if value in allowed and suffix != "×":  # a ratio "2.4×" is a measurement, whatever its value
            continue
        bad.append(token + suffix)
    return bad


def test_the_guard_against_hand_typed_numbers_finds_them():
    allowed = {3.0, 1.5}
    assert undefined_numbers("Local costs about 4.4× the expert's, trained in 45 s.", allowed) == ["4.4×", "45"]
    assert undefined_numbers("see eq. 10, section 3.2 and `keep_late = 0.25`; R = 1.5 m, v = 3 m/s, "
                             "a 360° view, 2020", allowed) == []


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.stem)
def test_prose_holds_no_hand_typed_measurement(source):
    """Numbers in a notebook's prose that come from a measurement are rendered from computed values
    (``book.prose``), so they cannot go stale; a markdown cell may hold only numbers that define the
    set-up: the paper's, the config objects', and those of DEFINED_NUMBERS (each with its reason)."""
    from vgai_lite.lab.paper import PAPER, TABLES

    allowed = _config_values() | _numbers_in(PAPER) | _numbers_in(TABLES)
    bad = [(i, n) for i, c in enumerate(parse(source.read_text()).cells) if c.cell_type == "markdown"
           for n in undefined_numbers(c.source, allowed)]
    assert not bad, (f"{source.name}: numbers typed into markdown cells {bad} (cell index, number): render "
                     "measured numbers with vgai_lite.book.prose, or add a defining number to DEFINED_NUMBERS "
                     "with its reason")


def test_the_model_answers_claims_match_the_outputs_they_discuss():
    """07.1's model answer says the DAGNN levels off: the committed run's computed reading must say so too.
    05.2's model answer makes no claim on the direction; its run's reading says which way it went."""
    def outputs(name):
        nb = nbformat.read(ROOT / "notebooks" / name, as_version=4)
        texts = []
        for cell in nb.cells:
            for out in cell.get("outputs", []):
                data = out.get("data", {})
                texts.append(out.get("text", "") + data.get("text/markdown", "") + data.get("text/plain", ""))
        return "\n".join(texts), "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")

    out07, md07 = outputs("07_experiments.ipynb")
    reading = [line for line in out07.splitlines() if line.startswith("Read off this run")]
    assert reading, "07.1's experiment printed no reading"
    if "even the DAGNN" in md07 and "levels off" in md07:
        assert "DAGNN levels off" in reading[0], reading[0]
    out06, md06 = outputs("06_vgai_joint_training.ipynb")
    reading = [line for line in out06.splitlines() if line.startswith("Read off this run")]
    assert reading and ("shrink" not in md06 or "size fell" in reading[0]), reading
    out05, md05 = outputs("05_visual_state_cnn.ipynb")
    assert any(line.startswith("Read off this run") for line in out05.splitlines())
    assert "should fall" not in md05 and "should rise" not in md05


def undisplayed_prose(code: str) -> list:
    """Line numbers of ``prose(...)`` calls in a code cell whose Markdown is never shown: a bare call
    that is not the cell's last statement (Jupyter shows only the last expression's value), or one
    inside a block. Each such sentence must go through ``display``."""
    import ast

    try:
        tree = ast.parse(code)
    except SyntaxError:  # IPython magics: not Python; such a cell holds no prose
        return []
    last = tree.body[-1] if tree.body else None
    out = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name) and node.value.func.id == "prose" and node is not last):
            out.append(node.lineno)
    return out


def test_the_guard_against_undisplayed_prose_finds_it():
    assert undisplayed_prose('prose("a {x}", x=1)\nprose("b {x}", x=2)') == [1]
    assert undisplayed_prose('if True:\n    prose("a {x}", x=1)\nx = 2') == [2]
    assert undisplayed_prose('display(prose("a {x}", x=1))\nprose("b {x}", x=2)') == []


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.stem)
def test_every_rendered_sentence_is_displayed(source):
    cells = [c for c in parse(source.read_text()).cells if c.cell_type == "code"]
    hidden = [(i, line) for i, c in enumerate(cells) for line in undisplayed_prose(c.source)]
    assert not hidden, (f"{source.name}: prose(...) whose sentence is never shown, (code cell, line): {hidden}; "
                        "wrap it in display(...)")


PAPER_EQUATIONS = range(1, 11)
"""The paper's numbered equations (its local heuristic, displayed after eq. 3, carries no number)."""


def _markdown(source: Path) -> str:
    return "\n".join(c.source for c in parse(source.read_text()).cells if c.cell_type == "markdown")


def test_every_equation_of_the_paper_is_displayed_once_with_its_number():
    import re

    tags = [int(n) for src in SOURCES for n in re.findall(r"\\tag\{(\d+)\}", _markdown(src))]
    assert sorted(tags) == list(PAPER_EQUATIONS), \
        f"each of eqs. 1-10 displayed once with \\tag{{n}}; found tags {sorted(tags)}"
    heuristic = _markdown(ROOT / "tools" / "notebooks" / "01_flocking_dynamics_and_expert.py")
    assert re.search(r"\$\$\s*\\tilde\{\\mathbf u\}_i\(t\) =", heuristic), "01 displays the local heuristic"


def test_every_equation_is_named_in_the_docstring_of_the_code_that_implements_it():
    import ast
    import re

    named = set()
    for path in sorted((ROOT / "vgai_lite").rglob("*.py")):
        tree = ast.parse(path.read_text())
        nodes = [tree] + [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.ClassDef))]
        for node in nodes:
            doc = ast.get_docstring(node) or ""
            for a, b in re.findall(r"eqs?\. (\d+)(?:\s*-\s*(\d+))?", doc):
                named.update(range(int(a), int(b or a) + 1))
    assert set(PAPER_EQUATIONS) <= named, f"no docstring names eq(s). {sorted(set(PAPER_EQUATIONS) - named)}"


def test_every_colourbar_says_what_its_colours_mean():
    import ast

    for src in SOURCES:
        for cell in parse(src.read_text()).cells:
            if cell.cell_type != "code" or "colorbar" not in cell.source:
                continue
            tree = ast.parse("\n".join(l for l in cell.source.splitlines() if not l.startswith("%")))
            for node in ast.walk(tree):
                if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "colorbar":
                    assert any(k.arg == "label" for k in node.keywords), \
                        f"{src.stem}, line {node.lineno} of a cell: a colourbar without a label"


def test_every_controller_of_the_book_has_its_own_colour():
    from vgai_lite.viz import PALETTE, controller_color

    named = {k: v for k, v in PALETTE.items() if k != "centralized"}
    assert len(set(named.values())) == len(named), "two controllers share a colour"
    assert controller_color("VGAI, depth camera") == PALETTE["VGAI"]  # the book's VGAI sees through the camera
    assert controller_color("VGAI on clean frames") == PALETTE["clean frames"] != PALETTE["VGAI"]
    assert controller_color("the paper's VGAI (one gray frame)") == PALETTE["paper's VGAI"]


MARKDOWN_WORD_LIMITS = {"07_experiments": 2000}
"""Chapters with a word budget for their markdown (the reader's time): the results chapter reads in one sitting."""


@pytest.mark.parametrize("stem", sorted(MARKDOWN_WORD_LIMITS))
def test_a_chapter_with_a_word_budget_keeps_to_it(stem):
    import re

    words = len(re.findall(r"\S+", _markdown(ROOT / "tools" / "notebooks" / f"{stem}.py")))
    assert words <= MARKDOWN_WORD_LIMITS[stem], f"{stem}: {words} words of markdown, budget {MARKDOWN_WORD_LIMITS[stem]}"
