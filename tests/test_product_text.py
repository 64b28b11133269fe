"""The product speaks of the product: its text (src, tests, examples, docs, README, CHANGELOG) describes the library
to its users and carries no development history or internal targets.

Refused, case-insensitive unless said otherwise:

* rounds of work: "session(s)" — pytest's ``scope="session"`` excepted;
* issue numbers: "issue 3", "issues #14" — an upstream toppra issue cited in a comment or docstring excepted, never
  in a message a user reads (a string literal of the code);
* reviewers and audits: "reviewer(s)", "audit(s)", "audited", "auditor(s)";
* the design notes kept outside the repository: "DESIGN.md";
* machine states: "slow state", "fast state", "quiet state", "loaded state";
* missed targets: "MISSED" (upper case), "target(s) … missed".
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: what is scanned: these folders (recursively) and files of the repository
SCANNED = ("src", "tests", "examples", "docs", "README.md", "CHANGELOG.md")
#: text files by suffix
SUFFIXES = {".py", ".md", ".rst", ".txt", ".toml", ".cfg", ".ini", ".html", ".css", ".js", ".svg", ".yml", ".yaml"}
#: generated folders (a local docs build, caches): not the product's sources
GENERATED = {
    "_build",
    "example-out",
    "bench-out",
    "auto_examples",
    "generated",
    "gen_modules",
    "__pycache__",
    ".pytest_cache",
    ".ruff_cache",
}
#: this file holds the words it refuses
SELF = Path(__file__).resolve()

#: (name, pattern) of each refused kind of text
PATTERNS: tuple[tuple[str, re.Pattern[str]], ...] = (
    ("a round of work", re.compile(r"\bsessions?\b", re.IGNORECASE)),
    ("an issue number", re.compile(r"\bissues?\s*#?\s*\d+", re.IGNORECASE)),
    ("a reviewer", re.compile(r"\breviewers?\b", re.IGNORECASE)),
    ("an audit", re.compile(r"\baudit(s|ed|ing|ors?)?\b", re.IGNORECASE)),
    ("the design notes", re.compile(r"\bDESIGN\.md\b", re.IGNORECASE)),
    ("a machine state", re.compile(r"\b(slow|fast|quiet|loaded) state\b", re.IGNORECASE)),
    ("a missed target", re.compile(r"\bMISSED\b")),
    ("a missed target", re.compile(r"\btargets?\b[^\n]{0,40}?\bmissed\b", re.IGNORECASE)),
)
#: pytest's fixture scope, the one "session" a test may say
PYTEST_SCOPE = re.compile(r"""scope\s*=\s*["']session["']""")
#: an upstream toppra issue cited by number: "toppra issue #26", "toppra issues #14, #17"
TOPPRA_CITATION = re.compile(r"toppra(?:'s)?\s+issues?\s*#?\s*\d+", re.IGNORECASE)


def product_files() -> Iterator[Path]:
    """Every text file of the product, this test excepted."""
    for name in SCANNED:
        top = ROOT / name
        if top.is_file():
            yield top
        elif top.is_dir():
            for path in sorted(top.rglob("*")):
                rel = path.relative_to(ROOT).parts
                if path.is_file() and path.suffix in SUFFIXES and not GENERATED & set(rel) and path != SELF:
                    yield path


def message_strings(source: str) -> list[str]:
    """The string literals of Python ``source`` that are not docstrings: what code hands a user (messages,
    output), where a citation of an upstream issue does not belong."""
    tree = ast.parse(source)
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                docstrings.add(id(first.value))
    return [
        n.value
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docstrings
    ]


def findings(text: str, python: bool = False) -> list[tuple[int, str, str]]:
    """(line number, kind, line) of every refused phrase in ``text`` (``python``: the text is Python source, whose
    non-docstring string literals may not cite upstream issues either)."""
    out = []
    for number, line in enumerate(text.splitlines(), start=1):
        allowed = PYTEST_SCOPE.sub("", TOPPRA_CITATION.sub("", line))
        out += [(number, kind, line.strip()) for kind, pattern in PATTERNS if pattern.search(allowed)]
    if python:
        for literal in message_strings(text):
            if TOPPRA_CITATION.search(literal):
                out.append((0, "an issue number in a message", literal[:100]))
    return out


def test_the_product_text_carries_no_development_history() -> None:
    files = list(product_files())
    assert len(files) > 100 and ROOT / "README.md" in files and ROOT / "CHANGELOG.md" in files
    bad = []
    for path in files:
        text = path.read_text(encoding="utf-8", errors="replace")
        for number, kind, line in findings(text, python=path.suffix == ".py"):
            bad.append(f"{path.relative_to(ROOT)}:{number}: {kind}: {line}")
    assert not bad, "development history in the product's text:\n" + "\n".join(bad)


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ("measured over the third session", "a round of work"),
        ("Sessions 4 and 5 changed it", "a round of work"),
        ("a regression test for issue 3", "an issue number"),
        ("(see Issue #12)", "an issue number"),
        ("as issues 7 and 8 ask", "an issue number"),
        ("the reviewer's case", "a reviewer"),
        ("an audit found 6.3 rad/s", "an audit"),
        ("audited by hand", "an audit"),
        ("the names DESIGN.md lists", "the design notes"),
        ("in the slow state the ratio is higher", "a machine state"),
        ("Fast state: 1.9 µs", "a machine state"),
        ("PD+gravity  3.2×  MISSED", "a missed target"),
        ("regressor 1.9× (target 1.5: missed)", "a missed target"),
    ],
)
def test_each_kind_of_history_is_found(text: str, kind: str) -> None:
    assert kind in [k for _, k, _ in findings(text)], text


@pytest.mark.parametrize(
    "text",
    [
        '@pytest.fixture(scope="session")',
        "# toppra issues #14/#17: NaN sets on a feasible problem",
        "toppra then returns None with a log line (toppra issue #26).",
        "Kelly 1997, 'PD control with desired gravity compensation: a review'",
        "a triangle inequality missed by less than tol is met",
        "start_new_session=True",
        "the pose target is reached",
    ],
)
def test_what_is_not_history_passes(text: str) -> None:
    assert findings(text) == []


def test_an_upstream_issue_in_a_message_is_found_but_not_in_a_docstring_or_comment() -> None:
    message = 'def f():\n    """Cites toppra issue #26."""\n    # toppra issue #104\n    raise E("toppra issue #226")\n'
    assert [kind for _, kind, _ in findings(message, python=True)] == ["an issue number in a message"]
    quiet = 'def f():\n    """Cites toppra issue #26."""\n    # toppra issue #104\n    raise E("no number")\n'
    assert findings(quiet, python=True) == []
