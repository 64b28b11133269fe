"""The HTML of a playback page (:func:`armctl.sim.playback.playback`): meshcat's viewer script, inlined from
the meshcat package, the scene's commands, and a bar with the title, play/pause, a time slider and a legend."""

from __future__ import annotations

import html
import json
from pathlib import Path


def _viewer_script() -> str:
    import meshcat

    source = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    return source.read_text(encoding="utf-8").replace("</script", "<\\/script")


_STYLE = """
body{margin:0;font-family:sans-serif;overflow:hidden}
#meshcat-pane{width:100vw;height:100vh;overflow:hidden}
#armctl-bar{position:absolute;left:0;right:0;bottom:0;background:rgba(255,255,255,.92);padding:8px 14px;
 font-size:14px;border-top:1px solid #ccc}
#armctl-bar h1{font-size:15px;margin:0 0 4px 0}
#armctl-bar .row{display:flex;align-items:center;gap:10px}
#armctl-slider{flex:1}
#armctl-legend{font-size:12px;color:#333;margin-top:4px}
"""

_SCRIPT = """
(function(){
function bytes(s){const b=atob(s);const a=new Uint8Array(b.length);for(let i=0;i<b.length;i++)a[i]=b.charCodeAt(i);
 return a;}
var viewer=new MeshCat.Viewer(document.getElementById("meshcat-pane"));
window.armctlViewer=viewer;
for(const c of COMMANDS){viewer.handle_command_bytearray(bytes(c));}
const anim=viewer.animator, slider=document.getElementById("armctl-slider"),
 label=document.getElementById("armctl-time"), button=document.getElementById("armctl-play");
slider.max=DURATION; slider.step=1/FPS;
function show(t){label.textContent="t = "+(T0+t).toFixed(3)+" s";}
slider.addEventListener("input",function(){anim.pause();const t=parseFloat(slider.value);anim.seek(t);
 anim.display_progress(t);show(t);button.textContent="play";});
button.addEventListener("click",function(){if(anim.playing){anim.pause();button.textContent="play";}
 else{if(parseFloat(slider.value)>=DURATION-1e-9){anim.reset();}anim.play();button.textContent="pause";}});
function tick(){if(anim.playing){slider.value=anim.time;show(anim.time);button.textContent="pause";}
 else if(button.textContent==="pause"){button.textContent="play";}requestAnimationFrame(tick);}
show(0);tick();
})();
"""


def page(commands: list[str], title: str, legend: list[str], t0: float, duration: float, fps: float) -> str:
    """The page: meshcat's viewer, the ``commands`` (base64 msgpack) it runs in order, a bar with ``title``,
    play/pause, a slider over [0, ``duration``] s of animation (run time ``t0`` + t) and the ``legend``."""
    items = "".join(f"<span>{html.escape(x)}</span> · " for x in legend).removesuffix(" · ")
    script = (
        f"const COMMANDS={json.dumps(commands)};\nconst DURATION={duration:.9g}, FPS={fps:.9g}, T0={t0:.9g};\n"
        + _SCRIPT
    )
    return (
        "<!doctype html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>"
        "<div id='meshcat-pane'></div>"
        f"<div id='armctl-bar'><h1>{html.escape(title)}</h1><div class='row'>"
        "<button id='armctl-play'>pause</button><input id='armctl-slider' type='range' min='0' value='0'>"
        "<span id='armctl-time'></span></div>"
        f"<div id='armctl-legend'>{items}</div></div>"
        f"<script>{_viewer_script()}</script><script>{script}</script></body></html>"
    )
