"""The bench's modules import one another without a loop (the report reads the sections' titles and texts from
:mod:`armctl.bench.sections`, never from the suite that writes it), at module level or inside a function."""

from __future__ import annotations

from tests.helpers.imports import package_imports


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A cycle of the graph as a list of modules (its first repeated last), or None."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(n: str) -> list[str] | None:
        state[n] = 1
        path.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return [*path[path.index(m) :], m]
            if m not in state and (found := visit(m)) is not None:
                return found
        path.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state and (found := visit(n)) is not None:
            return found
    return None


def test_the_bench_has_no_import_loop() -> None:
    graph = package_imports("bench")
    assert {"report", "sections", "suite", "charts"} <= set(graph)
    assert _cycle(graph) is None, _cycle(graph)
    assert "suite" not in graph["report"] and "suite" not in graph["sections"]


def test_the_cycle_finder_finds_a_loop() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None
