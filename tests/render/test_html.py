"""The HTML preview: one self-contained page, and a real browser that plays it and shows the dancer.

The browser test drives Debian's headless Chromium over the DevTools protocol on a pipe (no extra
Python package): it loads the page from a file:// URL, plays to 2 s, takes a screenshot, and checks
the console stayed free of errors and that nothing was fetched from the network. Skipped when no
Chromium is installed (``apt-get install chromium``).
"""

from __future__ import annotations

import base64
import fcntl
import io
import json
import os
import re
import shutil
import subprocess
import time
import wave
from html.parser import HTMLParser

import numpy as np
import pytest
from PIL import Image

from choreo.motion import Motion
from choreo.render.html import write_html_preview
from choreo.skeleton import SMPL24
from tests.formats.hostile import hostile_dance

FPS, SECONDS = 30.0, 4.0
BEATS = [0.25, 0.75, 1.25, 1.75, 2.25, 2.75, 3.25, 3.75]


@pytest.fixture(scope="module")
def motion():
    """Four seconds of a dancer swaying and lifting their arms as they walk in a small circle."""
    frames = int(FPS * SECONDS)
    t = np.arange(frames) / FPS
    axis_angle = np.zeros((frames, 24, 3))
    axis_angle[:, 0, 1] = 0.6 * t  # turning slowly
    axis_angle[:, 16, 2] = 1.0 + 0.4 * np.sin(2 * np.pi * t)  # left shoulder
    axis_angle[:, 17, 2] = -1.0 - 0.4 * np.sin(2 * np.pi * t)  # right shoulder
    axis_angle[:, 1, 0] = -0.3 * np.sin(2 * np.pi * t)  # hips
    axis_angle[:, 2, 0] = 0.3 * np.sin(2 * np.pi * t)
    root = np.stack([0.3 * np.sin(t), 0.95 + 0.02 * np.sin(4 * np.pi * t), 0.3 * np.cos(t) - 0.3], axis=1)
    return Motion.from_axis_angle(root, axis_angle, fps=FPS)


@pytest.fixture(scope="module")
def song(tmp_path_factory):
    """A 4 s WAV: a quiet tone with a click on every beat."""
    rate = 8000
    t = np.arange(int(rate * SECONDS)) / rate
    signal = 0.1 * np.sin(2 * np.pi * 220 * t)
    for beat in BEATS:
        click = (t >= beat) & (t < beat + 0.03)
        signal[click] += 0.6 * np.sin(2 * np.pi * 1000 * t[click])
    path = tmp_path_factory.mktemp("song") / "song.wav"
    with wave.open(str(path), "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes((signal * 32767).astype("<i2").tobytes())
    return path


@pytest.fixture(scope="module")
def page(motion, song, tmp_path_factory):
    path = tmp_path_factory.mktemp("page") / "preview.html"
    with open(path, "wb") as handle:
        write_html_preview(motion, song, BEATS, handle)
    return path


# -- structure -------------------------------------------------------------------------------
class Resources(HTMLParser):
    """Every URL the page's markup would load, and its script blocks by id."""

    def __init__(self):
        super().__init__()
        self.urls, self.scripts, self._open = [], {}, None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for key in ("src", "href", "data", "poster"):
            if attrs.get(key):
                self.urls.append(attrs[key])
        if tag == "script":
            self._open = attrs.get("id") or f"script{len(self.scripts)}"
            self.scripts[self._open] = ""

    def handle_data(self, data):
        if self._open:
            self.scripts[self._open] += data

    def handle_endtag(self, tag):
        if tag == "script":
            self._open = None


def parse(page):
    parser = Resources()
    parser.feed(page.read_text())
    return parser


def test_page_is_self_contained(page):
    parsed = parse(page)
    assert all(url.startswith("data:") for url in parsed.urls), parsed.urls
    module = parsed.scripts["player"]  # the page's own code: imports three.js from the inlined copy only
    assert not re.search(r"""(import|fetch|XMLHttpRequest|src\s*=)[^;\n]*["']https?:""", module)
    three = base64.b64decode(parsed.scripts["three"].strip()).decode()
    assert "Three.js Authors" in three and 'const t="167"' in three  # the vendored build, whole
    assert "The MIT License" in page.read_text()  # its licence travels with it


def test_motion_audio_and_beats_are_inlined(page, motion, song):
    parsed = parse(page)
    dance = json.loads(parsed.scripts["dance"])
    positions = np.frombuffer(base64.b64decode(dance["positions"]), dtype="<f4").reshape(-1, 24, 3)
    assert dance["frames"] == motion.num_frames and dance["fps"] == FPS
    np.testing.assert_allclose(positions, motion.joint_positions(), atol=1e-5)
    assert dance["beats"] == BEATS
    audio = [url for url in parsed.urls if url.startswith("data:audio/wav;base64,")]
    assert len(audio) == 1 and base64.b64decode(audio[0].split(",", 1)[1]) == song.read_bytes()


def test_page_without_music_has_no_audio_element(motion):
    out = io.BytesIO()
    write_html_preview(motion, None, None, out)
    text = out.getvalue().decode()
    assert "<audio" not in text and '"beats": []' in text


# -- a real browser --------------------------------------------------------------------------
class DevTools:
    """The Chrome DevTools protocol over --remote-debugging-pipe: JSON messages ended by NUL on fds 3/4."""

    def __init__(self, executable, *flags):
        to_browser_r, self._to_browser = os.pipe()
        self._from_browser, from_browser_w = os.pipe()

        def child_fds():  # the browser reads commands on fd 3 and writes replies on fd 4
            high_r = fcntl.fcntl(to_browser_r, fcntl.F_DUPFD, 10)  # out of the way of 3 and 4 first
            high_w = fcntl.fcntl(from_browser_w, fcntl.F_DUPFD, 10)
            os.dup2(high_r, 3)
            os.dup2(high_w, 4)

        self.process = subprocess.Popen([executable, "--remote-debugging-pipe", *flags], preexec_fn=child_fds,
                                        pass_fds=(3, 4), stdout=subprocess.DEVNULL,
                                        stderr=subprocess.PIPE)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._buffer, self._next_id, self.events, self.session = b"", 0, [], None

    def send(self, method, timeout=30, **params):
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params}
        if self.session:
            message["sessionId"] = self.session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            reply = self._receive()
            if reply.get("id") == self._next_id:
                assert "error" not in reply, reply["error"]
                return reply["result"]
            self.events.append(reply)
        raise TimeoutError(method)

    def _receive(self):
        while b"\0" not in self._buffer:
            chunk = os.read(self._from_browser, 1 << 20)
            if not chunk:
                raise RuntimeError("the browser closed the pipe: " + self.process.stderr.read().decode()[-1000:])
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def evaluate(self, expression):
        result = self.send("Runtime.evaluate", expression=expression, awaitPromise=True, returnByValue=True)
        assert "exceptionDetails" not in result, result["exceptionDetails"]
        return result["result"].get("value")

    def close(self):
        try:
            self.session = None
            self.send("Browser.close", timeout=10)
        except Exception:
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
        os.close(self._to_browser)
        os.close(self._from_browser)


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    pytest.skip("no Chromium installed (apt-get install chromium)")


def console_errors(events):
    """Console errors, uncaught exceptions and error log entries among the browser's events."""
    errors = []
    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            errors.append(" ".join(str(arg.get("value", arg.get("description"))) for arg in params.get("args", [])))
        elif method == "Runtime.exceptionThrown":
            errors.append(json.dumps(params["exceptionDetails"])[:500])
        elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
            errors.append(params["entry"]["text"])
    return errors


def test_chromium_plays_the_page_and_shows_the_dancer(page, tmp_path):
    browser = DevTools(chromium(), "--headless=new", "--no-sandbox", "--disable-gpu-sandbox", "--use-angle=swiftshader",
                       "--enable-unsafe-swiftshader", "--autoplay-policy=no-user-gesture-required", "--mute-audio",
                       "--no-first-run", "--window-size=900,640", f"--user-data-dir={tmp_path / 'profile'}",
                       "about:blank")
    try:
        target = next(t for t in browser.send("Target.getTargets")["targetInfos"] if t["type"] == "page")
        browser.session = browser.send("Target.attachToTarget", targetId=target["targetId"], flatten=True)["sessionId"]
        for domain in ("Runtime", "Log", "Page", "Network"):
            browser.send(f"{domain}.enable")
        browser.send("Emulation.setDeviceMetricsOverride", width=900, height=640, deviceScaleFactor=1, mobile=False)
        browser.send("Page.navigate", url=page.as_uri())
        deadline = time.monotonic() + 60
        while not browser.evaluate("Boolean(window.choreoPreview && window.choreoPreview.ready)"):
            assert time.monotonic() < deadline, console_errors(browser.events) or "the page never became ready"
            time.sleep(0.2)
        assert browser.evaluate("choreoPreview.frames") == int(FPS * SECONDS)
        assert browser.evaluate("document.querySelectorAll('#beats span').length") == len(BEATS)
        song_seconds = browser.evaluate("new Promise((done) => { const song = document.getElementById('song'); "
                                        "if (song.readyState >= 1) done(song.duration); "
                                        "else song.addEventListener('loadedmetadata', () => done(song.duration)); })")
        assert song_seconds == pytest.approx(SECONDS, abs=0.05)  # the inlined song decodes in the browser
        browser.evaluate("choreoPreview.play()")
        deadline = time.monotonic() + 30
        while browser.evaluate("choreoPreview.time()") < 2.0:
            assert time.monotonic() < deadline, "playback never reached 2 s"
            time.sleep(0.05)
        assert browser.evaluate("!document.getElementById('song').paused")  # the clock is the music's
        browser.evaluate("choreoPreview.pause()")
        stopped_at = browser.evaluate("choreoPreview.time()")
        assert 2.0 <= stopped_at < 3.0
        browser.evaluate("new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))")
        shot = base64.b64decode(browser.send("Page.captureScreenshot", format="png")["data"])
        (tmp_path / "preview.png").write_bytes(shot)
        if os.environ.get("CHOREO_KEEP_SCREENSHOT"):
            shutil.copy(tmp_path / "preview.png", os.environ["CHOREO_KEEP_SCREENSHOT"])
        errors = console_errors(browser.events)
        fetched = [e["params"]["request"]["url"][:80] for e in browser.events if e.get("method") == "Network.requestWillBeSent"]
    finally:
        browser.close()
    assert not errors, errors
    assert all(not url.startswith(("http:", "https:")) for url in fetched), fetched
    image = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int)
    height, width, _ = image.shape
    background = np.array([0x20, 0x23, 0x2A])
    middle = image[height // 6: height * 3 // 4, width // 3: width * 2 // 3]
    # the dancer: warm orange (right side and spine) and blue (left side) pixels in the middle of the view
    orange = (middle[..., 0] > 150) & (middle[..., 0] - middle[..., 2] > 60)
    blue = (middle[..., 2] > 150) & (middle[..., 2] - middle[..., 0] > 60)
    assert orange.sum() > 300 and blue.sum() > 100, (orange.sum(), blue.sum())
    assert (np.abs(middle - background).sum(axis=-1) > 60).mean() > 0.01


@pytest.mark.hardening
def test_preview_placeholders_in_the_source_stay_text_and_names_stay_inside_their_script():
    motion = hostile_dance(source="__AUDIO__ __DANCE_JSON__ __THREE_B64__ <b>")
    names = list(SMPL24.names)
    names[5] = "<!--<script>"
    motion = Motion(motion.root_positions, motion.rotations, fps=30, metadata=motion.metadata,
                    skeleton=type(SMPL24)(tuple(names), SMPL24.parents, SMPL24.offsets))
    handle = io.BytesIO()
    write_html_preview(motion, None, None, handle)
    page = handle.getvalue().decode()
    title = page[page.index("<title>"):page.index("</title>")]
    assert title == "<title>__AUDIO__ __DANCE_JSON__ __THREE_B64__ &lt;b&gt;"
    script = page[page.index('<script id="dance"'):]
    script = script[script.index(">") + 1:script.index("</script>")]
    assert "<" not in script and json.loads(script)["names"][5] == "<!--<script>"
