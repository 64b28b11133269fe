"""Every example runs as a user would run it (a subprocess from a clean working directory)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARGS = {
    "tune_gains.py": ["--out", "{tmp}/presets"],
    "closed_loop_simulation.py": ["--out", "{tmp}/out"],
    "interaction_control.py": ["--out", "{tmp}/out"],
    "collision_detection.py": ["--out", "{tmp}/out"],
}


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")))
def test_example_runs(script: str, tmp_path: Path) -> None:
    args = [a.format(tmp=tmp_path) for a in ARGS.get(script, [])]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip(), "an example says what it did"
    if script == "tune_gains.py":
        written = sorted(p.name for p in (tmp_path / "presets").glob("*.toml"))
        assert len(written) == 17 and "planar_2r.computed_torque.toml" in written
        assert "panda_contact.osc_qp.toml" in written and "panda_contact.osc_closed_form.toml" in written


@pytest.mark.slow
def test_readme_code_runs_without_warnings(tmp_path: Path) -> None:
    """The README's Python blocks, run in order in one fresh process (the Lagrange line without compiling: the
    compiled library is exercised elsewhere), raise nothing and warn nothing: its simulation started the
    Panda outside joint 4's range and its planning call used waypoints it never defined."""
    import re

    text = (EXAMPLES.parent / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 2
    code = "\n".join(blocks).replace("compile=True", "compile=False")
    script = tmp_path / "readme.py"
    script.write_text("import warnings\nwarnings.simplefilter('error')\n" + code)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600, check=False
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
