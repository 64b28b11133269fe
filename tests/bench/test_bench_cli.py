"""``armctl bench``'s parts and help: ``--scene`` and ``--section`` run a part of the bench (a wrong name is a usage
error listing the valid ones), the parts left out are named in the console and the report with the command that
adds them, the warnings a section's runs raise are counted into the report instead of printed, and ``--help``
describes the command and every option."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path
from typing import Any

import pytest

from armctl.bench import sections, suite
from armctl.cli import main


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (
            ["--scene", "nosuch"],
            r"unknown scene 'nosuch'; valid scenes: pendulum, planar_2r, panda_topp, panda_contact",
        ),
        (["--section", "nosuch"], r"unknown section 'nosuch'; valid sections: scenes, stability_maps, "),
        (["--scene", "pendulum", "--section", "osc_speed"], r"--scene runs the scene matrix: add --section scenes"),
    ],
)
def test_a_wrong_part_is_a_usage_error_naming_the_valid_ones(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], match: str
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["bench", "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "Traceback" not in err
    assert re.search(r"armctl bench: error: " + match, err), err
    assert not (tmp_path / "out").exists()  # refused before anything ran or was created


def test_run_suite_refuses_unknown_names() -> None:
    from armctl.errors import InvalidParameterError, UnknownNameError

    with pytest.raises(UnknownNameError, match=r"unknown scene 'pendulm'; valid scenes: 'pendulum'"):
        suite.run_suite(scenes="pendulm")
    with pytest.raises(UnknownNameError, match=r"unknown section 'speed'"):
        suite.run_suite(sections=["speed"])
    with pytest.raises(InvalidParameterError, match=r"leave out the scene matrix"):
        suite.run_suite(scenes="pendulum", sections="topp_convergence")


@pytest.mark.parametrize("command", ["bench", "demo"])
def test_help_describes_the_command_and_every_option(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = capsys.readouterr().out
    _, rest = text.split("\n\n", 1)
    description = rest.split("options:")[0]
    assert len(description.split()) > 20  # what the command does, in words
    options = re.findall(r"^  (--?\w[\w-]*)(.*?)(?=^  -|\Z|^\S)", rest.split("options:")[1], re.S | re.M)
    assert len(options) >= 3
    for name, help_text in options:
        assert len(help_text.split()) >= 3, f"{command} {name} has no description"
    if command == "bench":
        assert f"A whole run takes {sections.DURATION['full']} on 2 cores" in " ".join(text.split())
        for key in sections.SECTION_TITLES:
            assert f"  {key} " in text
        assert ", ".join(sections.SCENE_NAMES) in text


@pytest.fixture
def noisy_topp(monkeypatch: pytest.MonkeyPatch) -> None:
    """The TOPP section, made to raise three SimulationWarnings of one text and one of another."""
    from armctl.errors import SimulationWarning

    def topp(quick: bool) -> dict[str, Any]:
        for _ in range(3):
            warnings.warn("joint1 over its velocity limit on 12.5% of samples", SimulationWarning, stacklevel=2)
        warnings.warn("the contact was lost at t = 0.4 s", SimulationWarning, stacklevel=2)
        return {"grids": [10], "durations": [1.1], "errors": [0.1], "compute_s": [1e-3], "analytic_duration": 1.0}

    monkeypatch.setattr(suite, "topp_convergence", topp)


def test_a_section_runs_alone_and_its_warnings_go_into_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], noisy_topp: None
) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning that escaped the section would fail here
        assert main(["bench", "--quick", "--section", "topp_convergence", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "SimulationWarning" not in captured.err  # not printed raw
    figures = json.loads((tmp_path / "figures.json").read_text())
    assert [k for k in sections.SECTION_TITLES if k in figures] == ["topp_convergence"]
    assert figures["section_warnings"]["topp_convergence"] == [
        {"category": "SimulationWarning", "message": "joint1 over its velocity limit on 12.5% of samples", "count": 3},
        {"category": "SimulationWarning", "message": "the contact was lost at t = 0.4 s", "count": 1},
    ]
    assert "4 warnings raised by this section's runs:" in captured.out
    page = (tmp_path / "report.html").read_text()
    assert "4 warnings raised by this section's runs" in page
    assert "3 × <code>SimulationWarning</code>: joint1 over its velocity limit on 12.5% of samples" in page
    # the sections left out: said in the console and in the report, with the command that runs them all
    whole = f"armctl bench --quick --out {tmp_path}"
    assert "not in this report: the sections scenes, stability_maps" in captured.out
    assert f"add with: {whole}" in captured.out
    assert "Not in this report" in page and f"<code>{whole}</code>" in page
    assert re.search(r"Section run time: (\d\.\d+ s|\d+ s)\.", page)
    assert "Section run time 0 s" not in page


def test_the_playback_left_out_without_meshcat_is_said_with_its_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    real = sections.find_spec
    monkeypatch.setattr(sections, "find_spec", lambda name: None if name == "meshcat" else real(name))
    assert main(["bench", "--quick", "--scene", "pendulum", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    line = "not in this report: 3D playback of the scenes (the meshcat package is not installed); add with: pip"
    assert out.count(line) == 2  # at the start and at the end of the run
    assert 'pip install -e ".[view]"' in out
    page = (tmp_path / "report.html").read_text()
    assert "No playback in this report: the meshcat package is not installed" in page
    assert "<code>pip install -e &quot;.[view]&quot;" in page
    assert not list(tmp_path.glob("playback_*.html"))
