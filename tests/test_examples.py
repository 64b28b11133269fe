"""Every example runs as a user would run it (a subprocess from a clean working directory): it writes what it
makes under ``--out`` (its figures, and results, playbacks or presets where it makes them), prints each path,
and writes nothing else into the working directory."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: what each example writes under --out (besides these, nothing)
WRITES = {
    "closed_loop_simulation.py": [
        f"{stem}.{ext}" for stem in ("computed_torque", "passivity_based") for ext in ("npz", "png", "html")
    ],
    "collision_detection.py": ["collision_detection.png", "force_control_border.png"],
    "contact_qp.py": ["contact_qp.png"],
    "contact_recipe.py": ["contact_recipe_normal_force.png", "contact_recipe_run.png"],
    "custom_controller.py": ["custom_controller.png"],
    "identification.py": ["identification.png"],
    "interaction_control.py": ["interaction_press.png", "interaction_wipe.png"],
    "model_views.py": ["model_views.png"],
    "mujoco_comparison.py": ["panda_table.xml"],
    "osc_priorities.py": ["osc_priorities.png"],
    "sweep_study.py": ["sweep_study.parquet", "sweep_study.png", "sweep_study_store"],
    "topp_tracking.py": ["topp_tracking.png"],
}


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")))
def test_example_runs(script: str, tmp_path: Path) -> None:
    out = tmp_path / "out"
    work = tmp_path / "work"
    work.mkdir()
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / script), "--out", str(out)],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.strip(), "an example says what it did"
    assert not list(work.iterdir()), "an example writes only under --out"
    if script in WRITES:
        assert sorted(p.name for p in out.iterdir()) == sorted(WRITES[script])
        for name in WRITES[script]:
            assert (out / name).stat().st_size > 1000 and str(out / name) in proc.stdout, name
    if script == "tune_gains.py":
        written = sorted(p.name for p in out.glob("*.toml"))
        assert len(written) == 17 and "planar_2r.computed_torque.toml" in written
        assert "panda_contact.osc_qp.toml" in written and "panda_contact.osc_closed_form.toml" in written


def test_every_example_takes_out_and_show_and_names_them_in_its_help() -> None:
    for script in sorted(EXAMPLES.glob("*.py")):
        proc = subprocess.run(
            [sys.executable, str(script), "--help"], capture_output=True, text=True, timeout=120, check=False
        )
        assert proc.returncode == 0, (script.name, proc.stderr[-2000:])
        assert "--out" in proc.stdout, script.name
        if script.name in WRITES and any(n.endswith(".png") for n in WRITES[script.name]):
            assert "--show" in proc.stdout, script.name


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
