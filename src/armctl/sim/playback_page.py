"""The HTML of a playback page (:func:`armctl.sim.playback.playback`): meshcat's viewer script, inlined from
the meshcat package, the scene's commands, and a bar below the view with the title, play/pause, a time slider,
the playback speed, a loop switch and a legend. The view and the bar share the window (nothing is drawn under
the bar); in a frame (the bench report, which titles it) the page leaves its title out."""

from __future__ import annotations

import html
import json
from pathlib import Path

#: the playback speeds offered, as multiples of real time
SPEEDS = (0.1, 0.25, 0.5, 1.0, 2.0)


def _viewer_script() -> str:
    import meshcat

    source = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    return source.read_text(encoding="utf-8").replace("</script", "<\\/script")


_STYLE = """
html,body{margin:0;height:100%;font-family:sans-serif;overflow:hidden}
body{display:flex;flex-direction:column}
#meshcat-pane{flex:1;min-height:0;position:relative;overflow:hidden}
#armctl-bar{flex:none;background:#fff;padding:6px 14px;font-size:14px;border-top:1px solid #ccc}
#armctl-bar h1{font-size:15px;margin:0 0 4px 0}
body.embedded #armctl-bar h1{display:none}
#armctl-bar .row{display:flex;align-items:center;gap:10px}
#armctl-slider{flex:1}
#armctl-legend{font-size:12px;color:#333;margin-top:4px}
"""

_SCRIPT = """
(function(){
if(window.self!==window.top){document.body.classList.add("embedded");}
function bytes(s){const b=atob(s);const a=new Uint8Array(b.length);for(let i=0;i<b.length;i++)a[i]=b.charCodeAt(i);
 return a;}
var viewer=new MeshCat.Viewer(document.getElementById("meshcat-pane"));
window.armctlViewer=viewer;
for(const c of COMMANDS){viewer.handle_command_bytearray(bytes(c));}
// mesh files whose normals are all zero (common in exported STL files) would be drawn black: shade them smoothly
viewer.scene.traverse(function(o){const n=o.isMesh&&o.geometry&&o.geometry.attributes.normal;
 if(n&&n.array.every(function(x){return x===0;})){o.geometry.computeVertexNormals();}});
viewer.set_dirty();
const anim=viewer.animator, slider=document.getElementById("armctl-slider"),
 label=document.getElementById("armctl-time"), button=document.getElementById("armctl-play"),
 speed=document.getElementById("armctl-speed"), loop=document.getElementById("armctl-loop");
slider.max=DURATION; slider.step=1/FPS;
let stopped=false, wasPlaying=anim.playing;
function show(t){label.textContent="t = "+(T0+t).toFixed(3)+" s";}
function setSpeed(){anim.mixer.timeScale=parseFloat(speed.value);}
speed.addEventListener("change",setSpeed); setSpeed();
slider.addEventListener("input",function(){stopped=true;anim.pause();const t=parseFloat(slider.value);anim.seek(t);
 anim.display_progress(t);show(t);button.textContent="play";});
button.addEventListener("click",function(){if(anim.playing){stopped=true;anim.pause();button.textContent="play";}
 else{stopped=false;if(parseFloat(slider.value)>=DURATION-1e-9){anim.reset();}anim.play();setSpeed();
 button.textContent="pause";}});
function tick(){
 if(anim.playing){slider.value=anim.time;show(anim.time);button.textContent="pause";}
 else if(wasPlaying&&!stopped&&loop.checked){anim.reset();anim.play();setSpeed();}
 else if(button.textContent==="pause"){button.textContent="play";slider.value=DURATION;show(DURATION);}
 wasPlaying=anim.playing;requestAnimationFrame(tick);}
show(0);tick();
})();
"""


def page(commands: list[str], title: str, legend: list[str], t0: float, duration: float, fps: float) -> str:
    """The page: meshcat's viewer, the ``commands`` (base64 msgpack) it runs in order, a bar with ``title``,
    play/pause, a slider over [0, ``duration``] s of animation (run time ``t0`` + t), the speed (:data:`SPEEDS`,
    real time by default), a loop switch (on) and the ``legend``."""
    items = "".join(f"<span>{html.escape(x)}</span> · " for x in legend).removesuffix(" · ")
    options = "".join(f"<option value='{s:g}'{' selected' if s == 1.0 else ''}>{s:g}×</option>" for s in SPEEDS)
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
        "<span id='armctl-time'></span>"
        f"<label>speed <select id='armctl-speed'>{options}</select></label>"
        "<label><input id='armctl-loop' type='checkbox' checked> loop</label></div>"
        f"<div id='armctl-legend'>{items}</div></div>"
        f"<script>{_viewer_script()}</script><script>{script}</script></body></html>"
    )
