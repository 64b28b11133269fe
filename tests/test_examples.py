"""Every example runs as a user would run it (a subprocess from a clean working directory)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARGS = {"tune_gains.py": ["--out", "{tmp}/presets"], "closed_loop_simulation.py": ["--out", "{tmp}/out"]}


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")))
def test_example_runs(script: str, tmp_path: Path) -> None:
    args = [a.format(tmp=tmp_path) for a in ARGS.get(script, [])]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip(), "an example says what it did"
    if script == "tune_gains.py":
        written = sorted(p.name for p in (tmp_path / "presets").glob("*.toml"))
        assert len(written) == 17 and "planar_2r.computed_torque.toml" in written
        assert "panda_contact.osc_qp.toml" in written and "panda_contact.osc_closed_form.toml" in written
