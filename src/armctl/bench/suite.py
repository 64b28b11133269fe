"""``armctl bench``: runs every benchmark section, writes ``figures.json`` and prints a summary.

Sections so far: the dynamics backends' speed. (Scenes × controllers, stability maps, TOPP, integrators and
the HTML report join as the layers land.)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def run_suite(quick: bool = False, out: Path = Path("bench-out")) -> dict[str, Any]:
    from armctl.bench import dynamics_speed

    out.mkdir(parents=True, exist_ok=True)
    figures: dict[str, Any] = {"quick": quick}
    number, rounds = (300, 5) if quick else (1000, 15)
    figures["dynamics_speed"] = dynamics_speed.run(number=number, rounds=rounds)
    print(dynamics_speed.report(figures["dynamics_speed"]))
    (out / "figures.json").write_text(json.dumps(figures, indent=2, default=float))
    return figures
