"""A preview anyone can open: one self-contained HTML page with the dancer, the music and its beats.

The page carries everything inline, so it works offline, from a mail attachment or a file:// URL:
three.js (vendored from npm, ``vendor/README.md``; MIT, its licence is copied into the page), the
joint positions of every frame (float32, base64), the song (base64, its own format) and the beat
times. It draws the dancer as capsules on a floor, with play/pause, a scrub slider with the beats
marked under it, and a camera that orbits the dancer (drag to turn, wheel to zoom, or let it turn).
``window.choreoPreview`` exposes play/pause/seek/time for scripted checks.
"""

from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import InputError, MotionFormatError
from ..motion import Motion

VENDOR = Path(__file__).parent / "vendor"
THREE_VERSION = "0.167.1"
AUDIO_TYPES = {".mp3": "audio/mpeg", ".wav": "audio/wav", ".ogg": "audio/ogg", ".oga": "audio/ogg",
               ".opus": "audio/ogg", ".flac": "audio/flac", ".m4a": "audio/mp4", ".aac": "audio/aac",
               ".webm": "audio/webm"}  # fmt: skip
MAX_AUDIO_BYTES = 200 * 2**20  # a browser would choke on more, inlined as base64


def write_html_preview(motion: Motion, audio_path: str | Path | None, beat_times: Sequence[float] | None,
                       handle) -> None:
    """Write the preview page for ``motion`` (with the song at ``audio_path`` and its beats, both optional)
    to a binary handle."""
    if motion.num_frames == 0:
        raise MotionFormatError("cannot preview a motion without frames")
    fields = {
        "TITLE": html.escape(str(motion.metadata.get("source", "choreo dance"))),
        "THREE_LICENSE": (VENDOR / "LICENSE").read_text().replace("-->", "- ->"),
        "THREE_VERSION": THREE_VERSION,
        "THREE_B64": _base64((VENDOR / "three.module.min.js").read_bytes()),
        "AUDIO": _audio_element(audio_path),
        "DANCE_JSON": _script_safe(_dance_json(motion, beat_times)),
    }
    # one pass: a placeholder inside a value (a title holding __AUDIO__) is text, not expanded
    page = PLACEHOLDER.sub(lambda match: fields[match.group(1)], PAGE)
    handle.write(page.encode("utf-8"))


PLACEHOLDER = re.compile(r"__(TITLE|THREE_LICENSE|THREE_VERSION|THREE_B64|AUDIO|DANCE_JSON)__")


def _script_safe(text: str) -> str:
    """JSON made inert inside a <script> element: with no <, > or & left (JSON's own \\u escapes
    stand in, which JSON.parse reads back), no joint name can close the element or open an HTML
    comment (``<!--<script>`` makes the parser swallow the rest of the page)."""
    return text.replace("&", "\\u0026").replace("<", "\\u003c").replace(">", "\\u003e")


def _base64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def _audio_element(audio_path: str | Path | None) -> str:
    """An <audio> element with the song inlined as a data URL (nothing when there is no song)."""
    if audio_path is None:
        return ""
    path = Path(audio_path)
    if not path.is_file():
        raise InputError(f"{path}: no such audio file")
    if path.stat().st_size > MAX_AUDIO_BYTES:
        raise InputError(f"{path}: too large to inline in a preview page ({path.stat().st_size >> 20} MB)")
    mime = AUDIO_TYPES.get(path.suffix.lower(), "application/octet-stream")
    return f'<audio id="song" preload="auto" src="data:{mime};base64,{_base64(path.read_bytes())}"></audio>'


def _dance_json(motion: Motion, beat_times: Sequence[float] | None) -> str:
    """Joint positions (T, J, 3) as little-endian float32 base64, with the tree, rate and beats."""
    positions = motion.joint_positions().astype("<f4")
    beats = [] if beat_times is None else [round(float(t), 4) for t in np.asarray(beat_times, dtype=float).ravel()
                                           if np.isfinite(t) and 0.0 <= t <= motion.duration]
    return json.dumps({
        "fps": float(motion.fps), "frames": motion.num_frames, "joints": motion.num_joints,
        "parents": list(motion.skeleton.parents), "names": list(motion.skeleton.names),
        "positions": _base64(positions.tobytes()), "beats": beats,
    })


PAGE = r"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="choreo">
<title>__TITLE__</title>
<!-- three.js __THREE_VERSION__ (https://threejs.org), inlined below under its licence:
__THREE_LICENSE__
-->
<style>
  html, body { margin: 0; height: 100%; background: #20232a; color: #e8e8e8; font: 14px system-ui, sans-serif; overflow: hidden; }
  #view { position: absolute; inset: 0 0 64px 0; }
  #view canvas { display: block; width: 100%; height: 100%; cursor: grab; }
  #bar { position: absolute; left: 0; right: 0; bottom: 0; height: 64px; display: flex; align-items: center; gap: 12px; padding: 0 14px; background: #15171c; box-sizing: border-box; }
  #bar button { width: 72px; height: 34px; border: 0; border-radius: 6px; background: #e0874f; color: #15171c; font-weight: 600; cursor: pointer; }
  #bar button.quiet { width: auto; padding: 0 10px; background: #3a3f4b; color: #e8e8e8; }
  #timeline { position: relative; flex: 1; height: 40px; }
  #beats { position: absolute; left: 0; right: 0; top: 26px; height: 12px; pointer-events: none; }
  #beats span { position: absolute; top: 0; width: 2px; height: 12px; margin-left: -1px; background: #e0874f; opacity: 0.8; }
  #scrub { position: absolute; left: 0; right: 0; top: 4px; width: 100%; margin: 0; }
  #clock { min-width: 92px; text-align: right; font-variant-numeric: tabular-nums; }
  #beat { width: 14px; height: 14px; border-radius: 7px; background: #3a3f4b; }
</style>
</head>
<body>
<div id="view"></div>
<div id="bar">
  <button id="play" type="button">Play</button>
  <div id="timeline"><input id="scrub" type="range" min="0" max="1" step="0.001" value="0" aria-label="time"><div id="beats"></div></div>
  <div id="beat" title="beat"></div>
  <span id="clock">0.00 s</span>
  <button id="orbit" class="quiet" type="button" title="turn the camera around the dancer">Orbit: on</button>
</div>
__AUDIO__
<script id="dance" type="application/json">__DANCE_JSON__</script>
<script id="three" type="text/plain">__THREE_B64__</script>
<script id="player" type="module">
const THREE = await import(URL.createObjectURL(new Blob(
  [Uint8Array.from(atob(document.getElementById('three').textContent.trim()), (c) => c.charCodeAt(0))],
  {type: 'text/javascript'})));
const dance = JSON.parse(document.getElementById('dance').textContent);
const bytes = Uint8Array.from(atob(dance.positions), (c) => c.charCodeAt(0));
const positions = new Float32Array(bytes.buffer);
const J = dance.joints, duration = dance.frames / dance.fps;
const song = document.getElementById('song');

// -- scene: floor, lights, a capsule per bone and a ball per joint ------------------------------
const view = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({antialias: true});
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20232a);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(2, 4, 3);
scene.add(sun);
const grid = new THREE.GridHelper(12, 24, 0x6a7080, 0x3a3f4b);
scene.add(grid);
const camera = new THREE.PerspectiveCamera(40, 1, 0.05, 100);

const skin = new THREE.MeshStandardMaterial({color: 0xe0874f, roughness: 0.6});
const left = new THREE.MeshStandardMaterial({color: 0x4f9be0, roughness: 0.6});
const bones = [], balls = [];
const boneGeometry = new THREE.CapsuleGeometry(0.035, 1, 4, 10);
const ballGeometry = new THREE.SphereGeometry(0.045, 16, 12);
for (let j = 0; j < J; j++) {
  const material = dance.names[j].startsWith('l_') ? left : skin;
  const ball = new THREE.Mesh(ballGeometry, material);
  if (dance.names[j] === 'head') ball.scale.setScalar(2.2);
  scene.add(ball);
  balls.push(ball);
  if (dance.parents[j] >= 0) {
    const bone = new THREE.Mesh(boneGeometry, material);
    scene.add(bone);
    bones.push([j, bone]);
  }
}
const up = new THREE.Vector3(0, 1, 0), a = new THREE.Vector3(), b = new THREE.Vector3();
function joint(frame, j, out) {
  const k = (frame * J + j) * 3;
  return out.set(positions[k], positions[k + 1], positions[k + 2]);
}
function pose(frame) {
  for (let j = 0; j < J; j++) joint(frame, j, balls[j].position);
  for (const [j, bone] of bones) {
    joint(frame, dance.parents[j], a);
    joint(frame, j, b);
    const length = a.distanceTo(b);
    bone.position.addVectors(a, b).multiplyScalar(0.5);
    bone.scale.set(1, Math.max(length - 0.07, 0.001), 1);
    if (length > 1e-6) bone.quaternion.setFromUnitVectors(up, b.sub(a).divideScalar(length));
  }
}

// -- camera: orbits the dancer; drag to turn, wheel to zoom -------------------------------------
const orbit = {azimuth: 0.6, elevation: 0.25, distance: 4.2, spin: true, dragging: null};
const target = new THREE.Vector3();
function place(frame) {
  joint(frame, 0, target);
  target.y = 0.9;
  const c = Math.cos(orbit.elevation);
  camera.position.set(target.x + orbit.distance * c * Math.sin(orbit.azimuth), target.y + orbit.distance * Math.sin(orbit.elevation),
                      target.z + orbit.distance * c * Math.cos(orbit.azimuth));
  camera.lookAt(target);
  grid.position.set(Math.round(target.x * 2) / 2, 0, Math.round(target.z * 2) / 2);
}
const canvas = renderer.domElement;
canvas.addEventListener('pointerdown', (e) => { orbit.dragging = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointerup', () => { orbit.dragging = null; });
canvas.addEventListener('pointermove', (e) => {
  if (!orbit.dragging) return;
  orbit.azimuth -= (e.clientX - orbit.dragging[0]) * 0.008;
  orbit.elevation = Math.min(1.4, Math.max(-0.1, orbit.elevation + (e.clientY - orbit.dragging[1]) * 0.008));
  orbit.dragging = [e.clientX, e.clientY];
});
canvas.addEventListener('wheel', (e) => { e.preventDefault(); orbit.distance = Math.min(20, Math.max(1.2, orbit.distance * Math.exp(e.deltaY * 0.001))); }, {passive: false});
const orbitButton = document.getElementById('orbit');
orbitButton.addEventListener('click', () => { orbit.spin = !orbit.spin; orbitButton.textContent = 'Orbit: ' + (orbit.spin ? 'on' : 'off'); });

// -- clock: the song's when there is one, else the wall clock -----------------------------------
const clock = {playing: false, offset: 0, started: 0};
function now() {
  if (song && !song.paused) return song.currentTime;
  return clock.playing ? clock.offset + (performance.now() - clock.started) / 1000 : clock.offset;
}
function play() {
  if (now() >= duration) seek(0);
  clock.started = performance.now();
  clock.playing = true;
  if (song) {
    song.currentTime = clock.offset;
    song.play().catch((error) => console.warn('music cannot play here, dancing without it:', error.message));
  }
  playButton.textContent = 'Pause';
}
function pause() {
  clock.offset = Math.min(now(), duration);
  clock.playing = false;
  if (song) song.pause();
  playButton.textContent = 'Play';
}
function seek(seconds) {
  clock.offset = Math.min(Math.max(seconds, 0), duration);
  clock.started = performance.now();
  if (song) song.currentTime = clock.offset;
}
const playButton = document.getElementById('play');
playButton.addEventListener('click', () => (clock.playing ? pause() : play()));
const scrub = document.getElementById('scrub');
scrub.max = duration.toFixed(3);
scrub.addEventListener('input', () => seek(parseFloat(scrub.value)));
document.addEventListener('keydown', (e) => { if (e.code === 'Space') { e.preventDefault(); clock.playing ? pause() : play(); } });

// -- beats under the timeline, and a light that flashes on each --------------------------------
const beatStrip = document.getElementById('beats');
for (const t of dance.beats) {
  const tick = document.createElement('span');
  tick.style.left = (100 * t / duration) + '%';
  tick.title = t.toFixed(2) + ' s';
  beatStrip.appendChild(tick);
}
const beatLight = document.getElementById('beat');
function nearBeat(t) {
  for (const beat of dance.beats) if (t >= beat && t - beat < 0.1) return true;
  return false;
}

// -- the loop ------------------------------------------------------------------------------------
function resize() {
  const width = view.clientWidth, height = view.clientHeight;
  renderer.setSize(width, height, false);
  camera.aspect = width / Math.max(height, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();
let last = performance.now();
function frameAt(t) { return Math.min(dance.frames - 1, Math.max(0, Math.floor(t * dance.fps))); }
function tick() {
  const wall = performance.now();
  if (orbit.spin && clock.playing && !orbit.dragging) orbit.azimuth += (wall - last) / 1000 * 0.35;
  last = wall;
  let t = now();
  if (clock.playing && t >= duration) { pause(); seek(duration); t = duration; }
  const frame = frameAt(t);
  pose(frame);
  place(frame);
  if (document.activeElement !== scrub) scrub.value = t.toFixed(3);
  document.getElementById('clock').textContent = t.toFixed(2) + ' / ' + duration.toFixed(2) + ' s';
  beatLight.style.background = nearBeat(t) ? '#e0874f' : '#3a3f4b';
  renderer.render(scene, camera);
  requestAnimationFrame(tick);
}
tick();
window.choreoPreview = {play, pause, seek, time: now, duration, frames: dance.frames, beats: dance.beats.length, ready: true};
</script>
</body>
</html>
"""
