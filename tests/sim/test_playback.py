"""The 3D playback: a standalone page whose animation puts the arm where the run had it, drawn with
example-robot-data's meshes where the model has them; in headless Chromium it loads without console errors
or network requests, draws into a WebGL canvas, and the arm is visible in the screenshot."""

from __future__ import annotations

import base64
import json
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, ShapeError, UnknownNameError
from armctl.references import Quintic
from armctl.sim import simulate
from armctl.sim.playback import frame_samples, playback
from armctl.sim.visuals import parts
from tests.helpers.browser import grey, keep_screenshot, needs_chromium, open_page

pytest.importorskip("meshcat")


def _commands(page: Path) -> list[dict[str, Any]]:
    import umsgpack

    found = re.search(r"const COMMANDS=(\[.*?\]);", page.read_text())
    assert found is not None
    return [umsgpack.unpackb(base64.b64decode(c)) for c in json.loads(found.group(1))]


@pytest.fixture(scope="module")
def planar_run() -> armctl.sim.SimResult:
    model = armctl.models.planar_2r()
    ctrl = armctl.controllers.ComputedTorque(armctl.Dynamics(model), 100.0, 20.0)
    return simulate(model, ctrl, Quintic([0.0, 0.0], [1.0, -0.8], 1.0), 1.0)


def test_frames_are_the_nearest_samples() -> None:
    t = np.arange(1001) * 1e-3
    idx, rate = frame_samples(t, 30.0)
    assert rate == 30.0 and len(idx) == 31
    np.testing.assert_array_equal(idx, np.round(np.arange(31) / 30.0 * 1000).astype(int))
    idx, rate = frame_samples(np.arange(600_001) * 1e-3, 30.0)  # 600 s: capped at 3000 frames
    assert len(idx) == 3000 and rate == pytest.approx(2999 / 600.0)


def test_the_animation_puts_each_joint_where_the_run_had_it(planar_run: armctl.sim.SimResult, tmp_path: Path) -> None:
    """The animated position of every joint's cylinder at every frame equals that joint's origin computed by
    the Lagrange backend (CasADi kinematics, not the Pinocchio model the page is built from) at the frame's
    sample."""
    page = playback(planar_run, tmp_path / "planar")
    assert page.suffix == ".html" and page.exists()
    commands = _commands(page)
    animation = commands[-1]
    assert animation["type"] == "set_animation"
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    idx, rate = frame_samples(planar_run.t, 30.0)
    model = planar_run.plant
    lagrange = armctl.Dynamics(model, backend="lagrange")
    for name in model.joint_names:
        clip = clips[f"/meshcat/{model.name}/{name}_joint"]
        assert clip["fps"] == rate
        keys = next(tr["keys"] for tr in clip["tracks"] if tr["name"] == ".position")
        assert [k["time"] for k in keys] == list(range(len(idx)))
        want = [lagrange.frame_pose(planar_run.q[k], name)[:3, 3] for k in idx]
        np.testing.assert_allclose([k["value"] for k in keys], want, rtol=0, atol=1e-12)
    # the page holds the viewer itself and fetches nothing
    text = page.read_text()
    assert "MeshCat.Viewer" in text and not re.search(r"(src|href)\s*=\s*['\"]?https?:", text)


def test_example_robot_data_meshes_for_its_arms_and_shapes_otherwise() -> None:
    panda = armctl.models.panda()
    drawn, source = parts(panda)
    assert source.startswith("example-robot-data panda_description") and len(drawn) == 11  # 8 links, hand, fingers
    assert parts(panda.with_payload(1.0, [0, 0, 0.05], np.eye(3) * 1e-3))[1].startswith("example-robot-data")
    assert parts(panda, "collision")[1].endswith("(collision meshes)")
    assert parts(panda, "shapes")[1] == "simple shapes"
    # the same name on other kinematics: the meshes would not fit, so shapes
    moved = armctl.RobotModel(panda.joints[:6], name="panda", gravity=panda.gravity, frames=(), tool_frame=None)
    assert parts(moved)[1] == "simple shapes"
    drawn, source = parts(armctl.models.puma560())
    assert source == "simple shapes" and {p.joint for p in drawn} == set(range(7))


def test_bad_arguments_are_named(planar_run: armctl.sim.SimResult, tmp_path: Path) -> None:
    with pytest.raises(ShapeError, match="model has 7 joints, the result 2"):
        playback(planar_run, tmp_path / "x", armctl.models.panda())
    with pytest.raises(UnknownNameError, match="meshes"):
        playback(planar_run, tmp_path / "x", meshes="fancy")
    loaded = type(planar_run).load(planar_run.save(tmp_path / "run"))
    with pytest.raises(InvalidParameterError, match="pass model="):
        loaded.playback(tmp_path / "x")
    assert loaded.playback(tmp_path / "x", armctl.models.planar_2r()).exists()


@pytest.fixture(scope="module")
def contact_page(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from armctl.scenes import scene

    sc = scene("panda_contact")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sc.run("osc_qp", duration=1.0)
    assert np.abs(res.contact_force_on_environment).max() > 1.0  # it touches the table
    return res.playback(tmp_path_factory.mktemp("pb") / "contact", environment=sc.sim_options["environment"])


def test_contact_forces_are_arrows(contact_page: Path) -> None:
    commands = _commands(contact_page)
    clips = {a["path"]: a["clip"] for a in commands[-1]["animations"]}
    arrow = clips["/meshcat/panda/contact_force_0"]
    visible = next(tr["keys"] for tr in arrow["tracks"] if tr["name"] == ".visible")
    assert any(k["value"] for k in visible)
    assert "contact force on the arm" in contact_page.read_text()


@needs_chromium
def test_playback_page_in_headless_chromium(contact_page: Path) -> None:
    """No console error, no request beyond the page itself, a WebGL canvas, the animation as long as the run;
    the slider moves the arm (the view at its start and at its end differ, and the time shown follows), and the
    arm is on the screenshot (hiding it changes a visible share of the pixels)."""
    probe = """(() => {
        const c = document.querySelector('canvas');
        const gl = c && (c.getContext('webgl2') || c.getContext('webgl'));
        return {canvas: !!c, webgl: !!gl, duration: window.armctlViewer.animator.duration,
                slider: document.getElementById('armctl-slider').max};
    })()"""

    def slide(t: float) -> str:
        return f"""(() => {{ const s = document.getElementById('armctl-slider'); s.value = {t};
            s.dispatchEvent(new Event('input')); return document.getElementById('armctl-time').textContent; }})()"""

    hide = """(() => { const v = window.armctlViewer;
        v.scene_tree.find(['meshcat', 'panda']).object.visible = false; v.set_dirty(); })()"""
    report = open_page(contact_page, probe, settle=3.0, then=[slide(0.0), slide(1.0), hide])
    keep_screenshot(report.screenshot, "armctl-playback.png")
    assert report.errors == []
    assert all(u.startswith(("file:", "data:")) for u in report.requests), report.requests
    assert report.value["canvas"] and report.value["webgl"]
    assert report.value["duration"] == pytest.approx(1.0) and float(report.value["slider"]) == pytest.approx(1.0)
    assert report.values_after[:2] == ["t = 0.000 s", "t = 1.000 s"]
    start, end, hidden = (grey(png) for png in report.screenshots_after)
    assert start.std() > 5.0  # not one colour
    assert (np.abs(start - end) > 10.0).mean() > 0.001  # the slider moved the arm
    assert (np.abs(end - hidden) > 10.0).mean() > 0.005  # the arm covers a visible share of the view


#: the GPU driver's note on reading pixels back, caused by the test's own screenshots, not by the page
SCREENSHOT_NOTE = "GPU stall due to ReadPixels"


def test_collision_meshes_by_default_and_mesh_files_under_their_current_type(tmp_path: Path) -> None:
    """The default page draws the smaller collision meshes, and lowers its mesh files as "_meshfile_geometry"
    (the deprecated "_meshfile" made the viewer warn in the console once per mesh)."""
    model = armctl.models.ur5()
    dyn = armctl.Dynamics(model)
    q0 = np.array([0.0, -1.2, 1.2, -1.5, -1.5, 0.0])
    run = simulate(dyn, lambda t, q, qd, ref: dyn.gravity_torque(q), armctl.Reference.hold(q0), 0.05, q0=q0)
    small = playback(run, tmp_path / "small")
    large = playback(run, tmp_path / "large", meshes="visual")
    assert "(collision meshes)" in small.read_text() and "(visual meshes)" in large.read_text()
    assert small.stat().st_size < 0.3 * large.stat().st_size
    types = {g["type"] for c in _commands(small) for g in c.get("object", {}).get("geometries", [])}
    assert "_meshfile_geometry" in types and "_meshfile" not in types


def test_the_ground_grid_is_under_everything_the_arm_sweeps(planar_run: armctl.sim.SimResult, tmp_path: Path) -> None:
    """The pendulum hangs below its base: the grid is put under its lowest point, not through it."""
    from armctl.scenes import scene

    sc = scene("pendulum")
    res = sc.run("pd_gravity", duration=0.2)
    page = playback(res, tmp_path / "pendulum")
    grid = next(c for c in _commands(page) if c["type"] == "set_transform" and c["path"] == "/Grid")
    height = np.array(grid["matrix"]).reshape(4, 4).T[2, 3]
    import pinocchio as pin

    pm = sc.plant.to_pinocchio()
    pd = pm.createData()
    lowest = 0.0
    for q in res.q:
        pin.forwardKinematics(pm, pd, q)
        pin.updateFramePlacements(pm, pd)
        lowest = min(lowest, *(float(f.translation[2]) for f in pd.oMf))
    assert height < lowest


@needs_chromium
def test_playback_speed_and_loop_in_headless_chromium(planar_run: armctl.sim.SimResult, tmp_path: Path) -> None:
    """The speed menu sets the animation's time scale; with the loop on (the default) the animation starts over
    at its end and keeps playing, with it off it stops at the end; the page's title is left out in a frame; the
    page logs no console warning."""
    page = playback(planar_run, tmp_path / "planar", title="planar 2R")
    state = "({t: window.armctlViewer.animator.time, playing: window.armctlViewer.animator.playing})"
    set_speed = """(() => { const s = document.getElementById('armctl-speed'); s.value = '0.25';
        s.dispatchEvent(new Event('change')); return window.armctlViewer.animator.mixer.timeScale; })()"""
    near_end = """(() => { const a = window.armctlViewer.animator; const s = document.getElementById('armctl-speed');
        s.value = '1'; s.dispatchEvent(new Event('change')); a.seek(0.95 * a.duration);
        a.display_progress(0.95 * a.duration); return a.time; })()"""
    loop_off = """(() => { document.getElementById('armctl-loop').checked = false;
        const a = window.armctlViewer.animator; a.seek(0.9 * a.duration); return true; })()"""
    report = open_page(page, state, settle=2.5, then=[set_speed, near_end, state, loop_off, state, state])
    keep_screenshot(report.screenshot, "armctl-playback-loop.png")
    assert report.errors == []
    assert [w for w in report.warnings if SCREENSHOT_NOTE not in w] == []
    # 1 s of animation, 2.5 s after loading: looping, so still playing, somewhere inside the run
    assert report.value["playing"] and 0.0 <= report.value["t"] <= 1.0
    assert report.values_after[0] == pytest.approx(0.25)
    assert report.values_after[1] == pytest.approx(0.95, abs=0.05)
    after_end = report.values_after[2]  # half a second later: past the end, started over
    assert after_end["playing"] and after_end["t"] < 0.9
    stopped = report.values_after[5]  # loop off: a second after 0.9 s the run has ended and stays ended
    assert not stopped["playing"]
    text = page.read_text()
    assert "<h1>planar 2R</h1>" in text and "body.embedded #armctl-bar h1{display:none}" in text
