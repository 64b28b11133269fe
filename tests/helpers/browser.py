"""A page opened in headless Chromium through the DevTools protocol: its console errors and uncaught
exceptions, the value of a JavaScript expression, and a screenshot. For the tests of the pages armctl writes
(the benchmark report, the 3D playback); they skip where no Chromium is installed (``.ci/run`` installs
Debian's ``chromium``)."""

from __future__ import annotations

import asyncio
import base64
import json
import os
import re
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--use-gl=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--window-size=1280,900",
)


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


needs_chromium = pytest.mark.skipif(chromium() is None, reason="no chromium (apt-get install chromium)")


@dataclass
class PageReport:
    """What the browser saw: ``errors`` (console errors and uncaught exceptions, as text), ``value`` (of the
    expression evaluated after the page settled) and the ``screenshot`` (PNG bytes)."""

    errors: list[str] = field(default_factory=list)
    value: Any = None
    screenshot: bytes = b""
    requests: list[str] = field(default_factory=list)
    #: the screenshots taken after evaluating each expression of ``then``, in turn
    screenshots_after: list[bytes] = field(default_factory=list)
    #: the value of each expression of ``then``
    values_after: list[Any] = field(default_factory=list)
    #: console warnings (``console.warn``, and the browser's own warnings such as deprecations), as text
    warnings: list[str] = field(default_factory=list)


async def _visit(ws_url: str, page: Path, expression: str, settle: float, then: Sequence[str]) -> PageReport:
    import websockets

    report = PageReport()
    async with websockets.connect(ws_url, max_size=None) as ws:
        counter = 0
        pending: dict[int, asyncio.Future[Any]] = {}

        async def reader() -> None:
            async for raw in ws:
                msg = json.loads(raw)
                if "id" in msg and msg["id"] in pending:
                    pending.pop(msg["id"]).set_result(msg)
                    continue
                method, params = msg.get("method"), msg.get("params", {})
                if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                    report.errors.append(" ".join(str(a.get("value", a.get("description"))) for a in params["args"]))
                elif method == "Runtime.consoleAPICalled" and params.get("type") == "warning":
                    report.warnings.append(" ".join(str(a.get("value", a.get("description"))) for a in params["args"]))
                elif method == "Runtime.exceptionThrown":
                    d = params["exceptionDetails"]
                    report.errors.append(d.get("exception", {}).get("description") or d.get("text", "exception"))
                elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
                    report.errors.append(params["entry"].get("text", ""))
                elif method == "Log.entryAdded" and params["entry"].get("level") == "warning":
                    report.warnings.append(params["entry"].get("text", ""))
                elif method == "Network.requestWillBeSent":
                    report.requests.append(params["request"]["url"])

        async def call(method: str, tab: str | None = None, **params: Any) -> Any:
            nonlocal counter
            counter += 1
            fut: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
            pending[counter] = fut
            msg: dict[str, Any] = {"id": counter, "method": method, "params": params}
            if tab:
                msg["sessionId"] = tab
            await ws.send(json.dumps(msg))
            out = await asyncio.wait_for(fut, 120)
            if "error" in out:
                raise RuntimeError(f"{method}: {out['error']}")
            return out.get("result", {})

        task = asyncio.create_task(reader())
        target = await call("Target.createTarget", url="about:blank")
        tab = (await call("Target.attachToTarget", targetId=target["targetId"], flatten=True))["sessionId"]
        for domain in ("Runtime", "Log", "Page", "Network"):
            await call(f"{domain}.enable", tab)
        size = {"width": 1280, "height": 900, "deviceScaleFactor": 1, "mobile": False}
        await call("Emulation.setDeviceMetricsOverride", tab, **size)
        await call("Page.navigate", tab, url=page.resolve().as_uri())
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            state = await call("Runtime.evaluate", tab, expression="document.readyState", returnByValue=True)
            if state["result"].get("value") == "complete":
                break
            await asyncio.sleep(0.2)
        await asyncio.sleep(settle)
        value = await call("Runtime.evaluate", tab, expression=expression, returnByValue=True, awaitPromise=True)
        report.value = value["result"].get("value")
        shot = await call("Page.captureScreenshot", tab, format="png")
        report.screenshot = base64.b64decode(shot["data"])
        for step in then:
            done = await call("Runtime.evaluate", tab, expression=step, returnByValue=True)
            report.values_after.append(done["result"].get("value"))
            await asyncio.sleep(0.5)
            shot = await call("Page.captureScreenshot", tab, format="png")
            report.screenshots_after.append(base64.b64decode(shot["data"]))
        task.cancel()
    return report


def open_page(page: Path, expression: str = "true", settle: float = 2.0, then: Sequence[str] = ()) -> PageReport:
    """Load ``page`` (a local file) in a fresh headless Chromium, wait for it to load and ``settle`` seconds
    more, evaluate ``expression`` and take a screenshot; then evaluate each expression of ``then`` in turn,
    taking a screenshot after each."""
    exe = chromium()
    assert exe is not None
    # (Chromium's child processes may still write into the profile as the browser exits: what they leave stays)
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        proc = subprocess.Popen(
            [exe, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-port=0", "about:blank"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            ws_url = None
            deadline = time.monotonic() + 60
            assert proc.stderr is not None
            while time.monotonic() < deadline:
                line = proc.stderr.readline()
                found = re.search(r"DevTools listening on (ws://\S+)", line)
                if found:
                    ws_url = found.group(1)
                    break
                if not line and proc.poll() is not None:
                    break
            assert ws_url, "chromium did not start its DevTools endpoint"
            return asyncio.run(_visit(ws_url, page, expression, settle, then))
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()


def grey(png: bytes) -> Any:
    """The screenshot's grey levels (H, W), 0–255."""
    import io

    import numpy as np
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=float)


def keep_screenshot(png: bytes, name: str) -> Path:
    """Write a screenshot where a person can look at it: ``$ARMCTL_SCREENSHOTS`` or the temporary folder."""
    folder = Path(os.environ.get("ARMCTL_SCREENSHOTS", tempfile.gettempdir()))
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / name
    out.write_bytes(png)
    return out
