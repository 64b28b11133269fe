"""The layering of a run's readers and of the sweep's modules, read from the source (imports at module level, inside
a function or under ``TYPE_CHECKING`` alike): the plots, the playback page and the tables read a run through
:class:`~armctl.sim.run_record.RunRecord` and never import :mod:`armctl.sim.result`, which offers them as methods;
the sweep's store and table sit below :mod:`armctl.sim.sweep_result`; and no import loop passes through any of
these modules."""

from __future__ import annotations

from tests.helpers.imports import package_imports

#: the modules whose layering this file checks
LAYERED = (
    "result",
    "run_record",
    "plot",
    "playback",
    "tables",
    "sweep_result",
    "sweep_store",
    "sweep_table",
    "case_failure",
    "case_settings",
)


def _reachable(graph: dict[str, set[str]], start: str) -> set[str]:
    """The modules ``start`` imports, directly or through others."""
    seen: set[str] = set()
    todo = list(graph.get(start, ()))
    while todo:
        n = todo.pop()
        if n not in seen:
            seen.add(n)
            todo.extend(graph.get(n, ()))
    return seen


def _in_a_loop(graph: dict[str, set[str]], module: str) -> bool:
    return module in _reachable(graph, module)


def test_no_import_loop_passes_through_the_run_readers_or_the_sweep_modules() -> None:
    graph = package_imports("sim")
    assert set(LAYERED) <= set(graph)
    looped = [m for m in LAYERED if _in_a_loop(graph, m)]
    assert not looped, looped


def test_the_readers_of_a_run_do_not_import_the_result() -> None:
    graph = package_imports("sim")
    for reader in ("plot", "playback", "tables", "run_record"):
        assert "result" not in _reachable(graph, reader), reader
    assert {"plot", "playback", "tables"} <= graph["result"]


def test_the_sweep_store_and_table_sit_below_the_sweep_result() -> None:
    graph = package_imports("sim")
    for low in ("sweep_store", "sweep_table", "case_failure", "case_settings"):
        assert "sweep_result" not in _reachable(graph, low), low
    assert not _reachable(graph, "case_failure") and not _reachable(graph, "case_settings")


def test_the_loop_finder_finds_a_loop() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _in_a_loop(graph, "a") and _in_a_loop(graph, "c")
    assert not _in_a_loop(graph, "d")
    assert not _in_a_loop({"a": {"b"}, "b": set()}, "a")
