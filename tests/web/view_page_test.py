#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The browser test of `uvr view` (docs/VIEWER.md): starts `uvr view MESH --port 0 --size
256x256 --device cpu`, drives its page in headless Chromium through Selenium, and checks:

- the HTTP side: a wrong or missing token gets no page (401/403), the page's scripts need the
  cookie the page sets (HttpOnly, SameSite=Strict), the socket refuses a wrong token and the
  cookie alone (no 101 Switching Protocols);
- the first frame arrives and is drawn;
- a mouse drag on the image turns the camera (focal point kept, view up orthonormal) and changes
  the image;
- dragging an opacity point of the transfer-function editor changes the opacity and the image;
- a ParaView colour-map JSON loaded through the file input changes the colours (a green map:
  the image turns green) and keeps the opacity; one dropped on the editor too (red);
- a malformed message and one of an unknown type each get an `error` and the page keeps working
  (the +X view button still gives a new view);
- a flood of 2000 camera `set`s from the page's socket is limited (an `error` for the excess,
  far fewer frames than messages, the connection open), and a final camera afterwards shows the
  same image as before the flood (no queue of stale frames after it);
- a clip plane from the Clip row cuts the volume, flip and Alt+drag in the view move it; the
  Shade box and its sliders light it; an isosurface added by Shift+click on the histogram, its
  marker dragged, a second from the list made translucent and green, then removed;
- Save PNG downloads a PNG of the state's size; Export TF and Export camera download the files
  the exported `uvr render` command names; that command, run here, gives an image with SSIM >=
  0.99 against the saved PNG (`uvr compare --min-ssim 0.99`);
- a page opened with a wrong token has no viewer;
- of a time series (a second server on `uvr generate --steps 3`), the time row shows, its slider
  and play button change the step and the image, and the exported command names the step;
- of a mesh with a prepared cache (a third server, after `uvr prepare`), the mesh is not read,
  the field list holds the cache's one field and the method list the methods it holds.

Screenshots of the whole window go to --screenshots DIR when given. --docs-screenshot PATH instead
only renders a good-looking view (Blunt Fin) for docs/images/viewer.png.

With --launcher 'mpirun -n 2 ...' the servers run data-parallel (issue 31) and the checks that
render run: frames, camera, opacity, clip, shading, isosurfaces, the saved PNG against the
exported one-process command, and the series.

Usage: view_page_test.py --uvr PATH/TO/uvr --data SHARED_DATA_DIR [--mesh bluntfin_tets.vtk]
                         [--screenshots DIR] [--keep DIR] [--docs-screenshot PATH]
                         [--launcher 'mpirun -n 2 ...']

Exit status: 0 every check passed, 1 one failed, 77 skipped (no Selenium for this Python, no
chromium or chromedriver, the mesh missing, or a uvr without `view`).
"""
import argparse
import json
import os
import queue
import re
import shlex
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

SKIP = 77


def skip(message):
    print(f"SKIPPED: {message}")
    sys.exit(SKIP)


class Failure(Exception):
    pass


def check(condition, message):
    """A real assertion that survives python -O and names what went wrong."""
    if not condition:
        raise Failure(message)


def step(title):
    print(f"[{time.monotonic() - T0:6.2f} s] {title}", flush=True)


T0 = time.monotonic()

# ---- The server ------------------------------------------------------------------------------


class Server:
    """`uvr view` in a child process; its first stdout line names the URL."""

    launcher = []  # e.g. mpirun's words: the server runs data-parallel (--launcher)

    def __init__(self, uvr, mesh, extra, log_path):
        self.log = open(log_path, "w")
        self.proc = subprocess.Popen(
            Server.launcher + [uvr, "view", mesh, "--port", "0"] + extra,
            stdout=subprocess.PIPE, stderr=self.log, text=True)
        lines = queue.Queue()

        def pump():
            for line in self.proc.stdout:
                lines.put(line)
                self.log.write("[stdout] " + line)
                self.log.flush()
            lines.put(None)  # the server closed its output (it exited)
        threading.Thread(target=pump, daemon=True).start()
        try:
            first = lines.get(timeout=90)
        except queue.Empty:
            raise Failure("uvr view printed no URL within 90 s")
        if first is None:
            self.proc.wait()
            self.log.flush()
            with open(log_path) as f:
                raise Failure(f"uvr view exited ({self.proc.returncode}) before serving: "
                              f"{f.read().strip()}")
        m = re.match(r"uvr: serving (http://[^\s/]+)/\?token=([A-Za-z0-9_-]+)", first)
        check(m, "uvr view's first line is not 'uvr: serving http://HOST:PORT/?token=T': "
                 f"{first!r}")
        self.origin, self.token = m.group(1), m.group(2)
        check(not self.origin.endswith(":0"), f"--port 0: the line names port 0: {first!r}")
        self.url = f"{self.origin}/?token={self.token}"
        host, port = self.origin[len("http://"):].rsplit(":", 1)
        self.host, self.port = host, int(port)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()


def http_get(url, cookie=None):
    """(status, headers, body) of a GET, also for 4xx answers."""
    req = urllib.request.Request(url, headers={"Cookie": cookie} if cookie else {})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.headers, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read()


def ws_handshake_status(server, path, cookie=None):
    """Status code of a WebSocket upgrade request for `path` (101 when the server accepts)."""
    with socket.create_connection((server.host, server.port), timeout=10) as s:
        lines = [f"GET {path} HTTP/1.1", f"Host: {server.host}:{server.port}",
                 "Upgrade: websocket", "Connection: Upgrade",
                 "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13",
                 f"Origin: {server.origin}"]
        if cookie:
            lines.append(f"Cookie: {cookie}")
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        reply = b""
        while b"\r\n" not in reply:
            chunk = s.recv(4096)
            if not chunk:
                break
            reply += chunk
    m = re.match(rb"HTTP/1\.[01] (\d{3})", reply)
    return int(m.group(1)) if m else None


def check_http(server):
    step("HTTP: tokens and cookies")
    for url in (f"{server.origin}/?token=wrong-token-0123456789", f"{server.origin}/",
                f"{server.origin}/?token="):
        status, _, body = http_get(url)
        check(status in (401, 403), f"GET {url} gave HTTP {status}, expected 401 or 403")
        check(b"app.js" not in body, f"GET {url} was refused but its body holds the page")
    status, _, _ = http_get(f"{server.origin}/app.js")
    check(status in (401, 403), f"GET /app.js without the cookie gave HTTP {status}")
    status, headers, body = http_get(server.url)
    check(status == 200, f"GET the page with its token gave HTTP {status}")
    check(b"app.js" in body, "the page does not load app.js")
    set_cookie = headers.get("Set-Cookie", "")
    # docs/VIEWER.md names the cookie uvr_token; a server may add its port (uvr_token_PORT), as
    # cookies do not tell ports apart and two viewers on one host would overwrite each other's.
    m = re.search(r"(uvr_token(?:_\d+)?)=([^;]+)", set_cookie)
    check(m, f"the page sets no uvr_token cookie (Set-Cookie: {set_cookie!r})")
    check("httponly" in set_cookie.lower(), f"the cookie is not HttpOnly: {set_cookie!r}")
    check("samesite=strict" in set_cookie.lower(),
          f"the cookie is not SameSite=Strict: {set_cookie!r}")
    cookie = f"{m.group(1)}={m.group(2)}"
    for name, kind in (("app.js", "javascript"), ("style.css", "css")):
        status, headers, _ = http_get(f"{server.origin}/{name}", cookie)
        check(status == 200, f"GET /{name} with the cookie gave HTTP {status}")
        # A module script served as anything but JavaScript is refused by the browser.
        check(kind in headers.get("Content-Type", ""),
              f"/{name} is served as {headers.get('Content-Type')!r}")
    step("WebSocket: tokens")
    status = ws_handshake_status(server, "/ws?token=wrong-token-0123456789")
    check(status != 101, "the socket accepted a wrong token")
    status = ws_handshake_status(server, "/ws", cookie)
    check(status != 101, "the socket accepted the cookie without ?token=")
    status = ws_handshake_status(server, f"/ws?token={server.token}")
    check(status == 101, f"the socket refused its token (HTTP {status})")


# ---- The browser -----------------------------------------------------------------------------


def start_browser(downloads, profile):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or shutil.which("chromium-browser")
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                "--window-size=1280,800", f"--user-data-dir={profile}", "--no-first-run",
                "--disable-extensions", "--password-store=basic"):
        options.add_argument(arg)
    options.add_experimental_option("prefs", {
        "download.default_directory": downloads,
        "download.prompt_for_download": False,
        "profile.default_content_setting_values.automatic_downloads": 1,
    })
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)
    # The page's viewport itself 1280 x 800 (the window's size includes no page area for tabs
    # in headless mode, but its height is not the viewport's).
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                           {"width": 1280, "height": 800, "deviceScaleFactor": 1, "mobile": False})
    driver.execute_cdp_cmd("Browser.setDownloadBehavior",
                           {"behavior": "allow", "downloadPath": downloads})
    driver.set_script_timeout(30)
    return driver


class Page:
    """The page in the browser, seen through its test hook window.uvrView."""

    def __init__(self, driver, shots):
        self.d = driver
        self.shots = shots
        self.shot_number = 0

    def js(self, script, *args):
        return self.d.execute_script(script, *args)

    def hook(self, expr):
        return self.js(f"return window.uvrView ? (window.uvrView.{expr}) : null;")

    def wait(self, condition_js, timeout, what):
        """Polls a JS expression (with `v` bound to window.uvrView) until it is truthy."""
        deadline = time.monotonic() + timeout
        script = f"const v = window.uvrView; return !!(v && ({condition_js}));"
        while time.monotonic() < deadline:
            if self.js(script):
                return
            time.sleep(0.05)
        raise Failure(f"timed out after {timeout} s waiting for {what} ({condition_js}); "
                      f"last frame {self.hook('lastFrame')}, last error {self.hook('lastError')}")

    def wait_settled(self, seq, timeout=30, what="the frame of the last change"):
        """Waits for the full-resolution frame of `seq` (or a later one), decoded and drawn."""
        self.wait(f"v.lastFrame && v.lastFrame.full && (v.lastFrame.seq ?? 0) >= {seq} && "
                  "v.framesDecoded === v.frameCount", timeout, what)
        return self.hook("lastFrame")

    def quiet(self, seconds=0.4, timeout=20):
        """Waits until no frame has arrived for `seconds` (the server has finished)."""
        deadline = time.monotonic() + timeout
        last = self.hook("frameCount")
        since = time.monotonic()
        while time.monotonic() < deadline:
            time.sleep(0.05)
            now = self.hook("frameCount")
            if now != last:
                last, since = now, time.monotonic()
            elif time.monotonic() - since >= seconds:
                return
        raise Failure("frames kept arriving")

    def pixels(self):
        """The canvas scaled to 64 x 64: a list of RGBA bytes."""
        return self.js("""
            const c = document.getElementById('view');
            const o = document.createElement('canvas'); o.width = 64; o.height = 64;
            const g = o.getContext('2d'); g.drawImage(c, 0, 0, 64, 64);
            return Array.from(g.getImageData(0, 0, 64, 64).data);""")

    def screenshot(self, name):
        if not self.shots:
            return
        self.shot_number += 1
        path = os.path.join(self.shots, f"{self.shot_number:02d}-{name}.png")
        self.d.save_screenshot(path)


def difference(a, b):
    """Mean absolute difference of two pixel lists' RGB bytes (0..255)."""
    total = sum(abs(a[i] - b[i]) for i in range(len(a)) if i % 4 != 3)
    return total / (len(a) * 3 / 4)


def changed_pixels(a, b, by=8):
    """Pixels of two pixel lists whose red, green or blue byte differs by more than `by`."""
    return sum(1 for i in range(0, len(a), 4)
               if max(abs(a[i + c] - b[i + c]) for c in range(3)) > by)


def mean_rgb(pixels):
    """Mean colour of the pixels that are not (nearly) black."""
    sums, n = [0, 0, 0], 0
    for i in range(0, len(pixels), 4):
        r, g, b = pixels[i:i + 3]
        if r + g + b > 30:
            sums = [sums[0] + r, sums[1] + g, sums[2] + b]
            n += 1
    return [s / max(1, n) for s in sums], n


def vec_close(a, b, tol):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def drag(driver, element, start, moves):
    """Left-drags from `start` (offset from the element's centre) through `moves` (dx, dy)."""
    from selenium.webdriver.common.action_chains import ActionChains
    chain = ActionChains(driver, duration=30)
    chain.move_to_element_with_offset(element, *start).click_and_hold()
    for dx, dy in moves:
        chain.move_by_offset(dx, dy).pause(0.03)
    chain.release().perform()


# ---- The checks ------------------------------------------------------------------------------


def first_frame(page):
    step("first frame")
    page.d.get(page.server.url)
    page.wait("v.info && v.state", 60, "the info message")
    frame = page.wait_settled(0, 60, "the first full frame")
    state = page.hook("state")
    check(frame["width"] == state["size"][0] and frame["height"] == state["size"][1],
          f"the first full frame is {frame['width']}x{frame['height']}, the state's size "
          f"{state['size']}")
    check(frame["format"] == "png", f"a full frame in {frame['format']}, not png")
    for key in ("render_seconds", "mean_samples_per_pixel", "frame_seconds", "method"):
        check(key in frame.get("stats", {}), f"the frame's stats have no {key}")
    mean, n = mean_rgb(page.pixels())
    check(n > 40, f"the first frame is (nearly) all black: {n} of 4096 pixels lit")
    check(page.js("return document.getElementById('stat-render-ms').textContent") != "–",
          "the status panel shows no frame time")
    # The default method is auto, listed first; the status says what it picked and, on hover,
    # why (the frame's stats).
    methods = page.js("return [...document.getElementById('method').options].map(o => o.value)")
    check(methods == ["auto", "adaptive", "reference", "exact"], f"the method list is {methods}")
    check(state["method"] == "auto", f"the starting method is {state['method']}, not auto")
    picked = frame["stats"].get("method")
    device = page.js("return document.getElementById('stat-device').textContent")
    check(picked in ("exact", "adaptive") and f"auto → {picked}" in device,
          f"the status shows '{device}' for a frame rendered by {picked}")
    reason = page.js("return document.getElementById('stat-device').title")
    check(reason.startswith("auto: " + picked), f"the status's hover text is '{reason}'")
    page.screenshot("first-frame")
    # Every method renders from the page (the server prepares for all of them), then auto again.
    for m in ("adaptive", "reference", "exact", "auto"):
        page.js("const s = document.getElementById('method'); s.value = arguments[0];"
                " s.dispatchEvent(new Event('change'));", m)
        rendered = picked if m == "auto" else m
        page.wait(f"v.state.method === '{m}' && v.lastFrame && v.lastFrame.full && "
                  f"v.lastFrame.stats && v.lastFrame.stats.method === '{rendered}'", 30,
                  f"a full frame of the {m} method")
        check(not page.hook("lastError"), f"the {m} method gave an error: {page.hook('lastError')}")


def rotate(page):
    step("drag on the image rotates the camera")
    from selenium.webdriver.common.by import By
    before_state, before_px = page.hook("state"), page.pixels()
    before_hash = page.hook("lastFrame")["hash"]
    seq0 = page.hook("lastSeq")
    canvas = page.d.find_element(By.ID, "view")
    drag(page.d, canvas, (0, 0), [(20, 6)] * 6)
    seq = page.hook("lastSeq")
    check(seq >= seq0 + 2, f"the drag sent {seq - seq0} camera messages (at least one "
                           "interactive and the final one expected)")
    frame = page.wait_settled(seq, what="the frame of the rotated camera")
    after_state, after_px = page.hook("state"), page.pixels()
    c0, c1 = before_state["camera"], after_state["camera"]
    check(not vec_close(c0["position"], c1["position"], 1e-6),
          "the camera position did not change")
    check(vec_close(c0["focal_point"], c1["focal_point"], 1e-6),
          "rotation moved the focal point")
    d = [c1["focal_point"][i] - c1["position"][i] for i in range(3)]
    up = c1["view_up"]
    dl = sum(x * x for x in d) ** 0.5
    d0 = [c0["focal_point"][i] - c0["position"][i] for i in range(3)]
    check(abs(dl - sum(x * x for x in d0) ** 0.5) < 1e-6 * dl, "rotation changed the distance")
    check(abs(sum(x * y for x, y in zip(d, up))) / dl < 1e-6, "view up is not orthogonal")
    check(abs(sum(x * x for x in up) - 1) < 1e-6, "view up is not a unit vector")
    check(frame["hash"] != before_hash, "the frame after the drag is the same image")
    diff = difference(before_px, after_px)
    check(diff > 1.0, f"the canvas hardly changed after the drag (mean difference {diff:.2f})")
    page.screenshot("rotated")


def drag_opacity_point(page):
    step("dragging an opacity point")
    from selenium.webdriver.common.by import By
    tf_canvas = page.d.find_element(By.ID, "tf-canvas")
    page.d.execute_script("arguments[0].scrollIntoView({block: 'center'});", tf_canvas)
    state0, px0 = page.hook("state"), page.pixels()
    points = state0["tf"]["opacity"]
    # The highest point: lowering it changes the most visible colours.
    index = max(range(len(points)), key=lambda i: points[i][1])
    at = page.js(f"return window.uvrView.opacityPointClient({index});")
    rect = page.js("const r = arguments[0].getBoundingClientRect(); "
                   "return {x: r.left + r.width / 2, y: r.top + r.height / 2};", tf_canvas)
    start = (round(at["x"] - rect["x"]), round(at["y"] - rect["y"]))
    seq0 = page.hook("lastSeq")
    drag(page.d, tf_canvas, start, [(-8, 12)] * 5)
    seq = page.hook("lastSeq")
    check(seq > seq0, "dragging the opacity point sent nothing")
    page.wait_settled(seq, what="the frame of the new opacity")
    state1, px1 = page.hook("state"), page.pixels()
    p0, p1 = points[index], state1["tf"]["opacity"][index]
    check(p1[1] < p0[1] - 0.1, f"the point's opacity did not go down: {p0} -> {p1}")
    check(p1[0] < p0[0] - 0.05 or p0[0] < 0.05, f"the point did not move left: {p0} -> {p1}")
    diff = difference(px0, px1)
    check(diff > 0.5, f"the image hardly changed after the opacity drag ({diff:.2f})")
    page.screenshot("opacity")


def load_colormap(page, tmp):
    step("a ParaView colour-map JSON through the file input")
    from selenium.webdriver.common.by import By
    state0, px0 = page.hook("state"), page.pixels()
    lo, hi = state0["range"]
    # Greens over the current range, no Points: only the colours change.
    cmap = [{"Name": "Test Greens", "ColorSpace": "RGB",
             "RGBPoints": [lo, 0.0, 0.25, 0.0, hi, 0.3, 1.0, 0.2]}]
    path = os.path.join(tmp, "greens.json")
    with open(path, "w") as f:
        json.dump(cmap, f)
    rgb0, _ = mean_rgb(px0)
    page.d.find_element(By.ID, "cmap-file").send_keys(path)
    page.wait("v.state.tf.name === 'Test Greens'", 20, "the state with the uploaded map")
    seq = page.hook("lastSeq")
    page.wait_settled(seq, what="the frame of the uploaded map")
    page.quiet()
    state1, px1 = page.hook("state"), page.pixels()
    o0, o1 = state0["tf"]["opacity"], state1["tf"]["opacity"]
    check(len(o0) == len(o1) and all(vec_close(a, b, 1e-5) for a, b in zip(o0, o1)),
          f"a colour map without Points changed the opacity: {o0} -> {o1}")
    rgb1, n = mean_rgb(px1)
    check(n > 40, "the image went black with the uploaded map")
    check(rgb1[1] > rgb1[0] + 10 and rgb1[1] > rgb1[2] + 10,
          f"the image is not green after loading a green map: mean RGB {rgb1} (before {rgb0})")
    check(difference(px0, px1) > 1.0, "the image hardly changed with the uploaded map")
    page.screenshot("colormap")
    # The same through a drop on the editor (a synthetic drop event: WebDriver cannot drag files
    # from outside the browser): a red map turns the image red.
    reds = dict(cmap[0], Name="Test Reds", RGBPoints=[lo, 0.3, 0.0, 0.0, hi, 1.0, 0.3, 0.2])
    page.js("""
        const dt = new DataTransfer();
        dt.items.add(new File([arguments[0]], 'reds.json', {type: 'application/json'}));
        document.getElementById('tf-drop').dispatchEvent(
            new DragEvent('drop', {dataTransfer: dt, bubbles: true, cancelable: true}));""",
            json.dumps([reds]))
    page.wait("v.state.tf.name === 'Test Reds'", 20, "the state with the dropped map")
    page.wait_settled(page.hook("lastSeq"), what="the frame of the dropped map")
    page.quiet()
    rgb2, _ = mean_rgb(page.pixels())
    check(rgb2[0] > rgb2[1] + 10 and rgb2[0] > rgb2[2] + 10,
          f"the image is not red after dropping a red map: mean RGB {rgb2}")


def bad_messages(page):
    step("malformed and unknown messages")
    errors0 = page.hook("errorCount")
    check(page.js("return window.uvrView.sendRaw('{\"type\": \"set\", \"camera\": ');"),
          "the socket is not open")
    page.wait(f"v.errorCount >= {errors0 + 1}", 10, "an error for malformed JSON")
    page.js("window.uvrView.sendRaw(JSON.stringify({type: 'no_such_message'}));")
    page.wait(f"v.errorCount >= {errors0 + 2}", 10, "an error for an unknown type")
    check(page.hook("connected"), "the connection closed after a bad message")
    check(page.js("return document.getElementById('error-line').textContent.length > 0"),
          "the error line shows nothing")
    page.screenshot("error")
    # The page keeps working: the +X button gives a new state and a new frame.
    from selenium.webdriver.common.by import By
    states0 = page.hook("messageCounts").get("state", 0)
    frames0 = page.hook("frameCount")
    page.d.find_element(By.ID, "view-px").click()
    page.wait(f"(v.messageCounts.state || 0) > {states0} && v.frameCount > {frames0}", 20,
              "a state and a frame after the +X button")
    page.wait("v.lastFrame.full && v.framesDecoded === v.frameCount", 20, "the +X frame")
    c = page.hook("state")["camera"]
    d = [c["focal_point"][i] - c["position"][i] for i in range(3)]
    check(d[0] > 0 and abs(d[1]) < 1e-6 * d[0] and abs(d[2]) < 1e-6 * d[0],
          f"+X does not look along +x: direction {d}")


def flood(page):
    step("a flood of 2000 camera messages")
    page.quiet()
    time.sleep(1.1)  # a fresh second for the server's message count
    camera0 = page.hook("state")["camera"]
    hash0, px0 = page.hook("lastFrame")["hash"], page.pixels()
    frames0, errors0 = page.hook("frameCount"), page.hook("errorCount")
    sent = page.js("""
        const c = window.uvrView.state.camera;
        let sent = 0;
        for (let i = 0; i < 2000; i++) {
            const k = 1 + 0.5 * (i + 1) / 2000;  // the camera moves away step by step
            const f = c.focal_point;
            const position = c.position.map((p, j) => f[j] + k * (p - f[j]));
            sent += window.uvrView.sendRaw(JSON.stringify(
                {type: 'set', seq: 100000 + i, interactive: true, camera: {...c, position}}));
        }
        return sent;""")
    check(sent == 2000, f"only {sent} of the 2000 messages were sent")
    page.quiet(0.6, 60)
    frames = page.hook("frameCount") - frames0
    step(f"  {frames} frames for 2000 messages; errors {page.hook('errorCount') - errors0}")
    check(page.hook("connected"), "the flood closed the connection")
    check(page.hook("errorCount") > errors0, "no error for the messages over the limit")
    check(frames < 200, f"{frames} frames for 2000 camera messages: frames are queued")
    # The last camera wins: a final camera (the one before the flood) after the limit's second.
    time.sleep(1.1)
    seq = 200000
    page.js("window.uvrView.sendRaw(JSON.stringify({type: 'set', seq: arguments[0], "
            "interactive: false, camera: arguments[1]}));", seq, camera0)
    frame = page.wait_settled(seq, 30, "the frame of the final camera")
    check(frame["seq"] == seq, f"the final frame has seq {frame['seq']}, not {seq}")
    page.quiet(0.6)
    check(page.hook("lastFrame")["seq"] == seq, "a frame of an older camera came after the "
                                                "final one")
    check(vec_close(page.hook("state")["camera"]["position"], camera0["position"], 1e-9),
          "the state's camera is not the final one")
    diff = difference(px0, page.pixels())
    same = page.hook("lastFrame")["hash"] == hash0
    step(f"  final frame vs. before the flood: same bytes {same}, mean pixel difference {diff:.3f}")
    check(diff < 1.0, f"the final frame does not show the final camera (difference {diff:.2f})")


def wait_file(path, timeout=30):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if os.path.exists(path) and not os.path.exists(path + ".crdownload") and \
                os.path.getsize(path) > 0:
            time.sleep(0.1)
            return
        time.sleep(0.05)
    raise Failure(f"no download {os.path.basename(path)} within {timeout} s "
                  f"(folder holds {os.listdir(os.path.dirname(path))})")


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    check(head[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG")
    return struct.unpack(">II", head[16:24])


def settled(page, frames0, what):
    """Waits for the full frame after a change made when frameCount was frames0. Frames are
    counted since the change, not matched by seq: the flood's seqs are above the page's own."""
    page.wait(f"v.frameCount > {frames0}", 60, what)
    page.quiet(0.6, 60)
    page.wait("v.lastFrame.full && v.framesDecoded === v.frameCount", 60, what)


def clip(page):
    step("a clip plane from the page's controls cuts the volume")
    errors0 = page.hook("errorCount")
    page.quiet()
    before = page.pixels()

    def settled(frames0, what):
        globals()["settled"](page, frames0, what)

    bounds = page.hook("info")["bounds"]
    frames0 = page.hook("frameCount")
    page.js("const a = document.getElementById('clip-axis'); a.value = '0';"
            " a.dispatchEvent(new Event('change'));")
    page.js("const p = document.getElementById('clip-pos'); p.value = '0.6';"
            " p.dispatchEvent(new Event('change'));")
    settled(frames0, "the frame of the clipped volume")
    planes = page.hook("state")["clip_planes"]
    x = bounds[0][0] + 0.6 * (bounds[1][0] - bounds[0][0])
    check(len(planes) == 1 and abs(planes[0][0] - x) < 1e-3 * abs(bounds[1][0] - bounds[0][0])
          and planes[0][3:] == [1, 0, 0], f"the state's clip planes are {planes}, not x >= {x}")
    cut = page.pixels()
    page.screenshot("clip-plane")
    check(changed_pixels(before, cut) > 40, "the clipped image looks like the whole volume "
                                            f"({changed_pixels(before, cut)} of 4096 pixels "
                                            "changed)")
    check(not page.js("return document.getElementById('clip-pos').disabled"),
          "the clip slider is disabled with an axis chosen")
    # Flip keeps the other side: another image again.
    frames0 = page.hook("frameCount")
    page.js("const f = document.getElementById('clip-flip'); f.checked = true;"
            " f.dispatchEvent(new Event('change'));")
    settled(frames0, "the frame of the flipped clip")
    check(page.hook("state")["clip_planes"][0][3:] == [-1, 0, 0], "flip kept the same side")
    check(changed_pixels(cut, page.pixels()) > 40, "the flipped clip shows the same image")
    # The "face" box: the cut face, seen through the volume in front of it, as a surface.
    flipped = page.pixels()
    frames0 = page.hook("frameCount")
    page.js("const f = document.getElementById('clip-surface'); f.checked = true;"
            " f.dispatchEvent(new Event('change'));")
    settled(frames0, "the frame with the cut face")
    check(page.hook("state")["clip_surface"] is True, "the face box did not set clip_surface")
    page.screenshot("clip-face")
    check(changed_pixels(flipped, page.pixels()) > 40, "the cut face changed nothing")
    # Alt+drag in the view moves the plane along its axis.
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    # Looking along +y, x across the view: the plane shows edge-on and follows the pointer.
    frames0 = page.hook("frameCount")
    page.d.find_element(By.ID, "view-py").click()
    settled(frames0, "the frame of the +Y view")
    x0 = page.hook("state")["clip_planes"][0][0]
    camera0 = page.hook("state")["camera"]
    flipped = page.pixels()
    frames0 = page.hook("frameCount")
    chain = ActionChains(page.d, duration=30)
    chain.key_down(Keys.ALT).move_to_element_with_offset(
        page.d.find_element(By.ID, "view"), 0, 0).click_and_hold()
    for _ in range(6):
        chain.move_by_offset(-10, 0).pause(0.03)
    chain.release().key_up(Keys.ALT).perform()
    settled(frames0, "the frame of the dragged clip plane")
    plane = page.hook("state")["clip_planes"][0]
    check(page.hook("state")["camera"] == camera0, "Alt+drag moved the camera")
    check(plane[3:] == [-1, 0, 0] and plane[0] < x0 - 0.05 * (bounds[1][0] - bounds[0][0]),
          f"Alt+drag did not move the plane along x: {x0} -> {plane}")
    check(bounds[0][0] <= plane[0] <= bounds[1][0], f"the dragged plane left the mesh: {plane}")
    moved = changed_pixels(flipped, page.pixels())
    check(moved > 20, f"moving the plane {x0} -> {plane[0]} changed {moved} pixels")
    check(page.hook("errorCount") == errors0, f"clipping gave an error: {page.hook('lastError')}")


def isosurfaces(page):
    step("isosurfaces: Shift+click on the histogram, drag the marker, the list's controls")
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    errors0 = page.hook("errorCount")
    page.quiet()
    before = page.pixels()
    tf_canvas = page.d.find_element(By.ID, "tf-canvas")
    page.d.execute_script("arguments[0].scrollIntoView({block: 'center'});", tf_canvas)
    lo, hi = page.hook("state")["range"]
    frames0 = page.hook("frameCount")
    ActionChains(page.d).key_down(Keys.SHIFT).move_to_element_with_offset(
        tf_canvas, -20, 0).click().key_up(Keys.SHIFT).perform()
    page.wait("v.state.iso.length === 1", 10, "the state with the new isosurface")
    settled(page, frames0, "the frame with an isosurface")
    value = float(page.hook("state")["iso"][0])
    check(lo < value < 0.5 * (lo + hi), f"Shift+click left of the middle put the isosurface at "
                                        f"{value}, not in ({lo}, {0.5 * (lo + hi)})")
    with_iso = page.pixels()
    page.screenshot("iso")
    check(changed_pixels(before, with_iso) > 40, "the isosurface changed nothing in the image")
    check(page.js("return document.querySelectorAll('#iso-list .iso-row').length") == 1,
          "the isosurface list does not show one row")
    # Drag its handle to the right: a higher value.
    at = page.js("return window.uvrView.isoHandleClient(0);")
    rect = page.js("const r = arguments[0].getBoundingClientRect(); "
                   "return {x: r.left + r.width / 2, y: r.top + r.height / 2};", tf_canvas)
    frames0 = page.hook("frameCount")
    drag(page.d, tf_canvas, (round(at["x"] - rect["x"]), round(at["y"] - rect["y"])),
         [(6, 0)] * 5)
    page.wait(f"Number(v.state.iso[0]) > {value}", 10, "the dragged isosurface's value")
    settled(page, frames0, "the frame of the dragged isosurface")
    moved = float(page.hook("state")["iso"][0])
    check(moved > value + 0.02 * (hi - lo), f"dragging the marker right moved it {value} -> {moved}")
    check(changed_pixels(with_iso, page.pixels()) > 20, "moving the isosurface changed nothing")
    # A second from the Add button, made translucent with a colour of its own, then removed.
    page.d.find_element(By.ID, "iso-add").click()
    page.wait("v.state.iso.length === 2", 10, "the state with a second isosurface")
    page.js("const r = document.querySelectorAll('#iso-list .iso-row')[1];"
            " const o = r.querySelector('.iso-opacity'); o.value = '0.5';"
            " o.dispatchEvent(new Event('change'));")
    page.wait("v.state.iso[1].split(',')[1] === '0.5'", 10, "the second's opacity")
    frames0 = page.hook("frameCount")
    page.js("const r = document.querySelectorAll('#iso-list .iso-row')[1];"
            " const c = r.querySelector('.iso-color'); c.value = '#00ff00';"
            " const m = r.querySelector('.iso-mapped'); m.checked = false;"
            " m.dispatchEvent(new Event('change'));")
    page.wait("v.state.iso[1].endsWith(',#00ff00')", 10, "the second's own colour")
    settled(page, frames0, "the frame with two isosurfaces")
    green = page.pixels()
    page.screenshot("iso-two")
    check(changed_pixels(with_iso, green) > 20, "the second, green isosurface changed nothing")
    check(not page.js("return document.querySelectorAll('#iso-list .iso-color')[1].disabled"),
          "the second's colour stays disabled with its own colour chosen")
    page.d.find_elements(By.CSS_SELECTOR, "#iso-list .iso-remove")[1].click()  # focuses it
    page.wait("v.state.iso.length === 1", 10, "the state after removing the second")
    check(page.js("return document.querySelectorAll('#iso-list .iso-row').length") == 1,
          "the list still shows the removed isosurface")
    check(page.hook("errorCount") == errors0,
          f"isosurfaces gave an error: {page.hook('lastError')}")


def shade(page):
    step("the Shade box and its sliders light the volume")
    errors0 = page.hook("errorCount")
    page.quiet()
    before = page.pixels()
    # With Shade off the coefficients light only the cut face (on since the clip test) and
    # isosurfaces: the sliders follow.
    face = bool(page.hook("state").get("clip_surface"))
    check(page.js("return document.getElementById('diffuse').disabled") != face,
          f"the lighting sliders' state with Shade off and the cut face {face}")
    frames0 = page.hook("frameCount")
    page.js("const b = document.getElementById('shade'); b.checked = true;"
            " b.dispatchEvent(new Event('change'));")
    settled(page, frames0, "the frame of the shaded volume")
    state = page.hook("state")
    check(state["shade"] is True, f"the state's shade is {state['shade']}")
    lit = page.pixels()
    check(changed_pixels(before, lit) > 40, "the shaded image looks like the unshaded one "
                                            f"({changed_pixels(before, lit)} of 4096 pixels "
                                            "changed)")
    check(not page.js("return document.getElementById('diffuse').disabled"),
          "the lighting sliders stay disabled with Shade on")
    # Some ambient light and less diffuse: brighter where the gradient is across the view.
    for name, value in (("ambient", "0.3"), ("diffuse", "0.6"), ("specular", "0.2")):
        frames0 = page.hook("frameCount")
        page.js(f"const e = document.getElementById('{name}'); e.value = '{value}';"
                " e.dispatchEvent(new Event('change'));")
        settled(page, frames0, f"the frame with {name} {value}")
    state = page.hook("state")
    check(vec_close([state["ambient"], state["diffuse"], state["specular"]], [0.3, 0.6, 0.2],
                    1e-6),
          f"the state's coefficients are {state['ambient']}, {state['diffuse']}, "
          f"{state['specular']}")
    page.screenshot("shade")
    check(changed_pixels(lit, page.pixels()) > 40, "the coefficients changed nothing")
    check(page.hook("errorCount") == errors0, f"shading gave an error: {page.hook('lastError')}")


def gradient_opacity(page):
    step("the Gradient opacity box scales the opacity; a bad text is refused")
    errors0 = page.hook("errorCount")
    page.quiet()
    before = page.pixels()
    check(not page.js("return document.getElementById('normals').disabled"),
          "the Normals menu is disabled with Shade on")

    def enter(text):
        page.js("const b = document.getElementById('gradient-opacity');"
                f" b.value = {json.dumps(text)}; b.dispatchEvent(new Event('change'));")

    frames0 = page.hook("frameCount")
    enter("0:0.3")  # a constant: the whole volume at 0.3 of its opacity
    settled(page, frames0, "the frame with a gradient opacity")
    state = page.hook("state")
    check(state["gradient_opacity"] == "0:0.3",
          f"the state's gradient_opacity is {state['gradient_opacity']!r}")
    check(changed_pixels(before, page.pixels()) > 40,
          "a gradient opacity of 0.3 changed nothing")
    page.screenshot("gradient-opacity")
    enter("2:1,1:0")
    page.wait(f"v.errorCount > {errors0}", 10, "the error for a decreasing gradient opacity")
    error = page.hook("lastError")
    check("gradient_opacity" in error["message"] and "non-decreasing" in error["message"],
          f"the error names neither the key nor the rule: {error}")
    frames0 = page.hook("frameCount")
    enter("")
    settled(page, frames0, "the frame without a gradient opacity")
    check(page.hook("state")["gradient_opacity"] == "", "the gradient opacity did not go off")
    check(changed_pixels(before, page.pixels()) <= 2,
          "the frame without a gradient opacity is not the one before it")


def overlay_painted(page):
    """Pixels the annotations' canvas paints (alpha above 0), in all and in its right quarter."""
    return page.js("""
        const c = document.getElementById('overlay');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let all = 0, right = 0;
        for (let i = 3; i < d.length; i += 4) {
            if (d[i] === 0) continue;
            all++;
            if (((i - 3) / 4) % c.width >= 0.75 * c.width) right++;
        }
        return {all, right};""")


def view_section(page):
    step("the View section: background, annotations, projection, opacity presets")
    errors0 = page.hook("errorCount")
    page.quiet()

    def set_input(element_id, value, event="change"):
        page.js(f"const e = document.getElementById('{element_id}'); e.value = '{value}';"
                f" e.dispatchEvent(new Event('{event}'));")

    def toggle(element_id, on):
        page.js(f"const e = document.getElementById('{element_id}'); e.checked = {str(on).lower()};"
                " e.dispatchEvent(new Event('change'));")

    # The annotations: drawn over the image on a canvas of their own, each turned off by its box.
    shown = overlay_painted(page)
    check(shown["all"] > 500, f"the scalar bar and axes paint only {shown['all']} pixels")
    check(shown["right"] > 200, f"no scalar bar at the right of the view ({shown})")
    for box in ("show-scalar-bar", "show-axes"):
        toggle(box, False)
    blank = overlay_painted(page)
    check(blank["all"] == 0, f"annotations remain with the scalar bar and axes off ({blank})")
    toggle("show-outline", True)
    outline = overlay_painted(page)
    check(outline["all"] > 200, f"the outline draws only {outline['all']} pixels")
    page.screenshot("outline")
    toggle("show-outline", False)
    for box in ("show-scalar-bar", "show-axes"):
        toggle(box, True)

    # The heat map's scale gets its numbers from the page (the image's bar has none).
    frames0 = page.hook("frameCount")
    page.hook("set({heatmap: true})")
    settled(page, frames0, "the heat map")
    top = page.hook("lastFrame")["stats"]["max_samples_per_pixel"]
    labels = overlay_painted(page)
    check(labels["right"] > 100, f"no numbers beside the heat map's scale ({labels}, top {top})")
    page.screenshot("heatmap-scale")
    frames0 = page.hook("frameCount")
    page.hook("set({heatmap: false})")
    settled(page, frames0, "the volume again")

    # The background: the frames, and the saved PNG, composite over it.
    frames0 = page.hook("frameCount")
    set_input("background", "#ff0000")
    settled(page, frames0, "the frame over a red background")
    state = page.hook("state")
    check(vec_close(state["background"], [1, 0, 0], 1e-6),
          f"the state's background is {state['background']}")
    px = page.pixels()
    check(px[0] > 200 and px[1] < 40 and px[2] < 40, f"the corner pixel is {px[:3]}, not red")
    frames0 = page.hook("frameCount")
    set_input("background", "#000000")
    settled(page, frames0, "the frame over black again")

    # Parallel projection: the camera's, keeping the size seen at the focal point.
    camera0 = page.hook("state")["camera"]
    frames0 = page.hook("frameCount")
    toggle("parallel", True)
    settled(page, frames0, "the frame in parallel projection")
    camera1 = page.hook("state")["camera"]
    check(camera1["parallel"] is True, "the camera is not parallel")
    check(camera1["parallel_scale"] > 0, f"parallel scale {camera1['parallel_scale']}")
    frames0 = page.hook("frameCount")
    toggle("parallel", False)
    settled(page, frames0, "the frame in perspective again")
    check(page.hook("state")["camera"]["parallel"] is False, "the camera stays parallel")
    check(vec_close(page.hook("state")["camera"]["position"], camera0["position"], 1e-9),
          "the projection toggle moved the camera")

    # Fit the view: the image takes the size of its area on the screen (device pixels).
    size0 = page.hook("state")["size"]
    check(page.hook("info")["fit_size"] is False, "info's fit_size with --size given")
    frames0 = page.hook("frameCount")
    set_input("size", "fit")
    settled(page, frames0, "the frame at the view's size")
    want = page.js("""
        const w = document.getElementById('view-wrap'), s = getComputedStyle(w);
        const d = window.devicePixelRatio || 1, p = (v) => parseFloat(v) || 0;
        return [Math.floor((w.clientWidth - p(s.paddingLeft) - p(s.paddingRight)) * d),
                Math.floor((w.clientHeight - p(s.paddingTop) - p(s.paddingBottom)) * d)];""")
    size = page.hook("state")["size"]
    check(all(abs(a - b) <= 2 for a, b in zip(size, want)),
          f"the fitted size is {size}, the view's area {want}")
    frames0 = page.hook("frameCount")
    set_input("size", f"{size0[0]}x{size0[1]}")
    settled(page, frames0, "the frame at the earlier size")
    check(page.hook("state")["size"] == size0, "the size did not come back")

    # An opacity preset replaces the curve.
    tf0 = page.hook("state")["tf"]
    frames0 = page.hook("frameCount")
    set_input("opacity-preset", "constant")
    settled(page, frames0, "the frame of the constant opacity")
    opacity = page.hook("state")["tf"]["opacity"]
    check(opacity == [[0, 0.2], [1, 0.2]], f"the opacity preset gave {opacity}")
    frames0 = page.hook("frameCount")
    page.hook(f"set({{tf: {json.dumps(tf0)}}})")
    settled(page, frames0, "the frame of the earlier opacity")
    check(page.hook("errorCount") == errors0, f"the View section gave an error: "
                                              f"{page.hook('lastError')}")


def save_and_reproduce(page, uvr, downloads, tmp):
    step("Save PNG, Export TF and camera, and the exported command")
    from selenium.webdriver.common.by import By
    for name in os.listdir(downloads):
        os.remove(os.path.join(downloads, name))
    # The other opacity law: the saved PNG and the exported command both follow it.
    page.js("const s = document.getElementById('opacity-law'); s.value = 'transmittance';"
            " s.dispatchEvent(new Event('change'));")
    page.wait("v.state.opacity_law === 'transmittance'", 10, "the state with the other law")
    state = page.hook("state")
    page.d.find_element(By.ID, "save-png").click()
    wait_file(os.path.join(downloads, "uvr-view.png"))
    w, h = png_size(os.path.join(downloads, "uvr-view.png"))
    check([w, h] == state["size"], f"the saved PNG is {w}x{h}, the state's size {state['size']}")
    exports0 = page.hook("messageCounts").get("export", 0)
    page.d.find_element(By.ID, "export-tf").click()
    page.d.find_element(By.ID, "export-camera").click()
    page.wait(f"(v.messageCounts.export || 0) >= {exports0 + 2}", 20, "two export replies")
    exported = page.hook("lastExport")
    tf_file, camera_file = exported.get("tf_file", "uvr-tf.json"), exported.get("camera_file",
                                                                                "uvr-camera.pvcc")
    wait_file(os.path.join(downloads, tf_file))
    wait_file(os.path.join(downloads, camera_file))
    with open(os.path.join(downloads, tf_file)) as f:
        json.load(f)  # valid JSON
    command = page.js("return document.getElementById('command').value;")
    check(command == exported["command"], "the command field does not show the export's command")
    step(f"  {command}")
    args = shlex.split(command)
    check(args[:2] == ["uvr", "render"], f"the command does not start with 'uvr render': {command}")
    check(tf_file in args and camera_file in args, "the command does not name the exported files")
    check("--opacity-law" in args and args[args.index("--opacity-law") + 1] == "transmittance",
          f"the command does not carry the opacity law: {command}")
    check("--clip-plane" in args, f"the command does not carry the page's clip plane: {command}")
    check("--iso" in args, f"the command does not carry the page's isosurface: {command}")
    check("--clip-surface" in args, f"the command does not carry the cut face: {command}")
    # Run it here: our uvr, the output in tmp, on the CPU like the server.
    args[0] = uvr
    out = os.path.join(tmp, "reproduced.png")
    for flag in ("-o", "--output"):
        if flag in args:
            args[args.index(flag) + 1] = out
    if "--device" in args:
        args[args.index("--device") + 1] = "cpu"
    else:
        args += ["--device", "cpu"]
    run = subprocess.run(args + ["-q"], cwd=downloads, capture_output=True, text=True, timeout=120)
    check(run.returncode == 0, f"the exported command failed ({run.returncode}): {run.stderr}")
    compare = subprocess.run([uvr, "compare", "--min-ssim", "0.99",
                              os.path.join(downloads, "uvr-view.png"), out],
                             capture_output=True, text=True, timeout=60)
    step(f"  uvr compare: {compare.stdout.strip()}")
    check(compare.returncode == 0, f"the exported command's image differs from the saved PNG: "
                                   f"{compare.stdout} {compare.stderr}")


def wrong_token_page(page):
    step("a page opened with a wrong token")
    # Before leaving: the socket refuses a wrong token from inside the browser too.
    result = page.d.execute_async_script("""
        const done = arguments[arguments.length - 1];
        const ws = new WebSocket(`ws://${location.host}/ws?token=wrong-token-0123456789`);
        let opened = false;
        ws.onopen = () => { opened = true; };
        ws.onclose = () => done({opened});
        setTimeout(() => done({opened, timeout: true}), 10000);""")
    check(not result["opened"], "the browser opened a socket with a wrong token")
    page.d.get(f"{page.server.origin}/?token=wrong-token-0123456789")
    time.sleep(0.3)
    check(not page.js("return !!window.uvrView;"), "a wrong token got the viewer")
    check(not page.d.find_elements("id", "view"), "a wrong token got the page")
    page.screenshot("wrong-token")


# ---- The docs screenshot ---------------------------------------------------------------------


def docs_screenshot(page, path):
    """Blunt Fin in an oblique view, Turbo over density 0.2-3 with a rising opacity:
    docs/images/viewer.png."""
    page.d.get(page.server.url)
    page.wait("v.info && v.state", 120, "the info message")
    page.wait_settled(0, 120, "the first frame")
    page.js("window.uvrView.set({preset: 'Turbo'});")
    page.wait("v.state.tf.name === 'Turbo'", 30, "the preset")
    # ParaView's reset camera orbited by azimuth 35 and elevation 25 with the page's own
    # trackball math.
    seq = page.d.execute_async_script("""
        const done = arguments[arguments.length - 1];
        import('./camera.js').then((cam) => {
            const v = window.uvrView;
            const camera = cam.orbit(v.state.camera, 35, 25);
            const tf = {...v.state.tf, opacity: [[0, 0], [0.12, 0], [0.3, 0.03], [0.5, 0.2],
                                                 [0.75, 0.6], [1, 1]]};
            done(v.set({camera, tf, range: [0.2, 3]}));
        });""")
    page.wait_settled(seq, 120, "the docs view")
    page.quiet(1.0, 120)
    page.d.save_screenshot(path)
    print(f"wrote {path}")


# ---- Main ------------------------------------------------------------------------------------


def time_series(uvr, driver, shots, work, tmp):
    """A series (uvr generate --steps 3) in a second server: the time row, its slider and play
    button change the step and the image, and the exported command names the step."""
    step("a time series: the time slider and play")
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    series = os.path.join(tmp, "series")
    os.makedirs(series, exist_ok=True)
    subprocess.run([uvr, "-q", "generate", "box", "--cells", "20000", "--fields", "jet",
                    "--steps", "3", "--dt", "0.8", "-o", os.path.join(series, "t.uvrm")],
                   check=True)
    server = Server(uvr, os.path.join(series, "t.pvd"),
                    ["--size", "128x128", "--device", "cpu", "--opacity", "0:0,1:0.8"],
                    os.path.join(work, "server-series.log"))
    try:
        page = Page(driver, shots)
        page.server = server
        page.d.get(server.url)
        page.wait("v.info && v.state", 60, "the series' info message")
        page.wait_settled(0, 60, "the first full frame of the series")
        check(page.hook("info")["times"] == [0, 0.8, 1.6],
              f"info's times: {page.hook('info')['times']}")
        row = page.d.find_element(By.ID, "time-row")
        check(row.is_displayed(), "no time row for a series of 3 steps")
        before = page.pixels()
        slider = page.d.find_element(By.ID, "time")
        slider.send_keys(Keys.END)  # the last step, as a user's keyboard moves it
        page.wait("v.state && v.state.step === 2", 10, "the state's step 2")
        page.wait_settled(page.hook("lastSeq"), 60, "the frame of step 2")
        text = page.js("return document.getElementById('time-value').textContent")
        check("1.6" in text and "(3/3)" in text, f"the time label reads {text!r}")
        check(difference(before, page.pixels()) > 0.5, "step 2 looks like step 0")
        page.screenshot("time-step-2")
        command = page.js("return document.getElementById('command').value")
        page.wait("document.getElementById('command').value.includes('--step-index 2')", 10,
                  f"the exported command naming --step-index 2 (it reads {command!r})")
        # Play steps on from 2 and wraps to 0; pause stops it.
        page.d.find_element(By.ID, "time-play").click()
        glyph = page.js("return document.getElementById('time-play').textContent")
        check(glyph == "\u275a\u275a", f"the pause button reads {glyph!r}")
        page.wait("v.state && v.state.step === 0", 10, "play to wrap to step 0")
        page.d.find_element(By.ID, "time-play").click()
        shown = page.hook("state")["step"]
        time.sleep(0.6)
        check(page.hook("state")["step"] == shown, "pause did not stop the steps")
        check(server.proc.poll() is None, f"uvr view exited ({server.proc.returncode})")
    finally:
        server.stop()


def prepared_cache(uvr, driver, shots, work, tmp):
    """A mesh with a prepared cache (uvr prepare) in a second server: served without reading
    the mesh, the page lists the cache's one field and the methods it holds, and draws."""
    step("a prepared cache: one field, its methods")
    from selenium.webdriver.common.by import By
    folder = os.path.join(tmp, "cached")
    os.makedirs(folder, exist_ok=True)
    mesh = os.path.join(folder, "m.uvrm")
    subprocess.run([uvr, "-q", "generate", "box", "--cells", "20000", "--fields", "jet,linear",
                    "-o", mesh], check=True)
    subprocess.run([uvr, "-q", "prepare", mesh, "--field", "linear", "--device", "cpu"],
                   check=True)
    log = os.path.join(work, "server-cache.log")
    server = Server(uvr, mesh, ["--size", "128x128", "--device", "cpu", "--field", "linear"], log)
    try:
        page = Page(driver, shots)
        page.server = server
        page.d.get(server.url)
        page.wait("v.info && v.state", 60, "the cached mesh's info message")
        page.wait_settled(0, 60, "the first full frame from the cache")
        fields = page.js("return [...document.getElementById('field').options].map(o => o.text)")
        check(len(fields) == 1 and "linear" in fields[0], f"the field list reads {fields!r}")
        methods = page.js(
            "return [...document.getElementById('method').options].map(o => o.value)")
        info_methods = page.hook("info")["methods"]
        check(methods == info_methods and "auto" in methods and len(methods) < 4,
              f"the method list reads {methods!r} (info: {info_methods!r})")
        notes = " ".join(page.hook("info")["notes"])
        check("prepared cache" in notes, f"no note of the cache in {notes!r}")
        _, lit = mean_rgb(page.pixels())
        check(lit > 100, f"the frame from the cache has {lit} lit pixels")
        page.screenshot("prepared-cache")
        with open(log) as f:
            text = f.read()
        check("using the prepared cache" in text and "uvr: read " not in text,
              "the server read the mesh instead of its cache")
        check(server.proc.poll() is None, f"uvr view exited ({server.proc.returncode})")
    finally:
        server.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--uvr", required=True, help="the uvr binary")
    parser.add_argument("--data", required=True, help="the shared data folder")
    parser.add_argument("--mesh", default="bluntfin_tets.vtk", help="mesh in the data folder")
    parser.add_argument("--screenshots", help="save screenshots of the page here")
    parser.add_argument("--keep", help="keep downloads, images and the server's log here")
    parser.add_argument("--docs-screenshot", help="only write the docs screenshot to this path")
    parser.add_argument("--launcher", default="",
                        help="start the servers with this before uvr (e.g. 'mpirun -n 2'): the "
                             "checks that render (frames, camera, opacity, clip, shading, "
                             "isosurfaces, the saved PNG against the exported command, a series) "
                             "on a data-parallel server")
    args = parser.parse_args()
    Server.launcher = shlex.split(args.launcher)
    if Server.launcher and not shutil.which(Server.launcher[0]):
        skip(f"no {Server.launcher[0]} for --launcher")

    try:
        import selenium  # noqa: F401
    except ImportError:
        skip(f"no selenium for {sys.executable} (Debian package python3-selenium)")
    if not (shutil.which("chromium") or shutil.which("chromium-browser")):
        skip("no chromium (Debian package chromium)")
    if not shutil.which("chromedriver"):
        skip("no chromedriver (Debian package chromium-driver)")
    mesh = os.path.join(args.data, args.mesh)
    if not os.path.isfile(mesh):
        skip(f"no {mesh}")
    args.uvr = os.path.abspath(args.uvr)  # the exported command runs in the downloads folder
    if not os.access(args.uvr, os.X_OK):
        print(f"FAILED: no uvr binary at {args.uvr}")
        return 1
    # `uvr view --help` of a uvr without `view` prints the top-level help: look for --port.
    has_view = subprocess.run([args.uvr, "view", "--help"], capture_output=True, text=True)
    if has_view.returncode != 0 or "--port" not in has_view.stdout:
        skip("this uvr has no `view` subcommand (built without the server)")

    tmp = tempfile.mkdtemp(prefix="uvr-view-test-")
    work = args.keep or tmp
    downloads = os.path.join(work, "downloads")
    os.makedirs(downloads, exist_ok=True)
    if args.screenshots:
        os.makedirs(args.screenshots, exist_ok=True)
    size = "1024x1024" if args.docs_screenshot else "256x256"
    server = driver = None
    status = 1
    try:
        step(f"uvr view {mesh} --size {size} --device cpu")
        server = Server(args.uvr, mesh, ["--size", size, "--device", "cpu"],
                        os.path.join(work, "server.log"))
        driver = start_browser(downloads, os.path.join(tmp, "profile"))
        page = Page(driver, args.screenshots)
        page.server = server
        if args.docs_screenshot:
            docs_screenshot(page, args.docs_screenshot)
        elif Server.launcher:  # data-parallel: what the ranks render (the protocol is rank 0's)
            first_frame(page)
            rotate(page)
            drag_opacity_point(page)
            clip(page)
            shade(page)
            isosurfaces(page)
            save_and_reproduce(page, args.uvr, downloads, tmp)
            time_series(args.uvr, driver, args.screenshots, work, tmp)
        else:
            check_http(server)
            first_frame(page)
            rotate(page)
            drag_opacity_point(page)
            load_colormap(page, tmp)
            bad_messages(page)
            flood(page)
            clip(page)
            shade(page)
            gradient_opacity(page)
            isosurfaces(page)
            view_section(page)
            save_and_reproduce(page, args.uvr, downloads, tmp)
            page.screenshot("final")
            wrong_token_page(page)
            time_series(args.uvr, driver, args.screenshots, work, tmp)
            prepared_cache(args.uvr, driver, args.screenshots, work, tmp)
        check(server.proc.poll() is None, f"uvr view exited ({server.proc.returncode})")
        status = 0
        step("PASSED")
    except Failure as e:
        step(f"FAILED: {e}")
        if driver and args.screenshots:
            driver.save_screenshot(os.path.join(args.screenshots, "failure.png"))
    finally:
        if driver:
            if status != 0:
                for entry in driver.get_log("browser")[-20:]:
                    print(f"  browser: {entry.get('level')} {entry.get('message')}")
            driver.quit()
        if server:
            server.stop()
            if status != 0:
                with open(os.path.join(work, "server.log")) as f:
                    print("  server log (last lines):\n    " +
                          "\n    ".join(f.read().splitlines()[-20:]))
        if not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
