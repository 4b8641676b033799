#!/usr/bin/env python3
"""End to end: the web page in headless Chromium, driven through WebDriver.

Serves web/ on loopback, opens the page on a built-in scene, waits until it
has rendered SPP sample passes, takes a screenshot of the canvas and reads its
pixels, and checks that they are a rendered scene (not blank) and close to
`dirt render` of the same camera, samples and size. Writes the screenshot,
the page's pixels and the reference under OUT_DIR. Only the standard library.

    web_e2e.py DIRT_BINARY OUT_DIR [--scene cornell] [--spp 4] [--backend gpu]
"""

import argparse
import base64
import http.server
import json
import os
import shlex
import socket
import subprocess
import sys
import threading
import time
import urllib.request
import zlib
from functools import partial


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wd(base, method, path, body=None, timeout=600):
    req = urllib.request.Request(
        base + path,
        data=None if body is None else json.dumps(body).encode(),
        method=method,
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(req, timeout=timeout) as r:
        return json.load(r)["value"]


def png_rgb(data):
    """Decodes an 8-bit, non-interlaced RGB or RGBA PNG into rows of RGB bytes."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n = int.from_bytes(data[pos : pos + 4], "big")
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + n]
        if kind == b"IHDR":
            w, h = int.from_bytes(body[0:4], "big"), int.from_bytes(body[4:8], "big")
            depth, color, interlace = body[8], body[9], body[12]
            assert depth == 8 and color in (2, 6) and interlace == 0, "unsupported PNG"
            bpp = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        prev = line
        rows.append(bytes(v for k, v in enumerate(line) if k % bpp < 3))
    return w, h, b"".join(rows)


# SwiftShader's WebGPU presenting on a canvas: with Chromium's default GL
# compositor the GPU process drops the device at the first present ("Device
# was destroyed"); with its Vulkan compositor the canvas is shown (the
# screenshot has it) while `toDataURL` of a WebGPU canvas stays blank, so the
# image of a page that presents is read from the screenshot.
CANVAS_FLAGS = ["--enable-features=Vulkan", "--use-vulkan=swiftshader", "--use-angle=swiftshader"]


def downsample(w, h, px, iw, ih):
    """The image pixels of a screenshot showing an iw x ih image scaled by an
    integer factor with nearest texels (image-rendering: pixelated): each
    block's centre."""
    if w % iw or h % ih or w // iw != h // ih:
        sys.exit(f"FAIL: the screenshot is {w}x{h}, not a whole multiple of the {iw}x{ih} image")
    k = w // iw
    centres = (3 * ((y * k + k // 2) * w + x * k + k // 2) for y in range(ih) for x in range(iw))
    return b"".join(px[i : i + 3] for i in centres)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dirt")
    ap.add_argument("out")
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--size", default="96x72")
    ap.add_argument("--backend", default="gpu")
    ap.add_argument("--timeout", type=float, default=900)
    ap.add_argument("--profile", help="Chromium's user data directory (default: OUT_DIR/chromium-profile)")
    ap.add_argument("--check", action="store_true",
                    help="also measure DIRT on the page's WebGPU against the CPU reference (dirt.check)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "web")
    if not os.path.exists(os.path.join(root, "pkg", "dirt_web.js")):
        sys.exit("web/pkg is missing: run scripts/web first")

    class Quiet(http.server.SimpleHTTPRequestHandler):
        extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                          ".wasm": "application/wasm", ".js": "text/javascript"}

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", free_port()), partial(Quiet, directory=root))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    site = f"http://127.0.0.1:{server.server_address[1]}/"

    port = free_port()
    driver = subprocess.Popen(
        ["chromedriver", f"--port={port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    base = f"http://127.0.0.1:{port}"
    for _ in range(100):
        try:
            wd(base, "GET", "/status")
            break
        except OSError:
            time.sleep(0.1)
    # A profile shared with an earlier run keeps Chromium's cache of compiled shaders.
    profile = a.profile or os.path.join(a.out, "chromium-profile")
    caps = {
        "capabilities": {
            "alwaysMatch": {
                "goog:chromeOptions": {
                    "binary": "/usr/bin/chromium",
                    "args": [
                        "--headless=new",
                        "--no-sandbox",
                        "--enable-unsafe-webgpu",
                        "--disable-dev-shm-usage",
                        "--disable-background-networking",
                        "--disable-component-update",
                        "--disable-sync",
                        "--no-first-run",
                        f"--user-data-dir={profile}",
                        "--window-size=800,900",
                    ] + CANVAS_FLAGS,
                }
            }
        }
    }
    session = None
    try:
        session = wd(base, "POST", "/session", caps)["sessionId"]
        s = f"/session/{session}"
        wd(base, "POST", s + "/timeouts", {"script": int(a.timeout * 1000)})
        url = f"{site}?scene={a.scene}&spp={a.spp}&size={a.size}&backend={a.backend}"
        wd(base, "POST", s + "/url", {"url": url})
        js = lambda script: wd(base, "POST", s + "/execute/sync", {"script": script, "args": []})
        start = time.time()
        state = {}
        while time.time() - start < a.timeout:
            state = js(
                "const st = document.getElementById('stats'), s = document.getElementById('status');"
                "return {samples: Number(st.dataset.samples || 0), camera: st.dataset.camera || '',"
                " status: s.textContent, error: s.dataset.state === 'error',"
                " warning: document.getElementById('warning').hidden ? '' : document.getElementById('warning').textContent};"
            )
            if state["error"] or state["samples"] >= a.spp:
                break
            time.sleep(1)
        print(f"page: {state['status']}")
        if state.get("warning"):
            print(f"page warning: {state['warning']}")
        took = time.time() - start
        if state["error"]:
            sys.exit(f"FAIL: the page reports an error: {state['status']}")
        if state["samples"] < a.spp:
            sys.exit(f"FAIL: {state['samples']} of {a.spp} samples after {took:.0f} s")
        if a.backend == "gpu" and "on WebGPU" not in state["status"]:
            sys.exit(f"FAIL: asked for the GPU, the page says: {state['status']}")
        if a.backend == "gpu" and "shaded on the GPU" not in state["status"]:
            sys.exit(f"FAIL: the page does not shade on the GPU: {state['status']}")
        if a.backend == "gpu" and "no image read back" not in state["status"]:
            sys.exit(f"FAIL: the page does not present on its canvas: {state['status']}")
        print(f"page: {state['samples']} samples in {took:.1f} s (page load, device, build and passes)")
        canvas = wd(base, "POST", s + "/element", {"using": "css selector", "value": "#view"})
        eid = next(iter(canvas.values()))
        shot = base64.b64decode(wd(base, "GET", f"{s}/element/{eid}/screenshot"))
        with open(os.path.join(a.out, "screenshot.png"), "wb") as f:
            f.write(shot)
        presents = "no image read back" in state["status"]
        page_png = None
        if not presents:
            # A 2D canvas: its bytes, exactly.
            url = js("return document.getElementById('view').toDataURL('image/png');")
            page_png = base64.b64decode(url.split(",", 1)[1])
            with open(os.path.join(a.out, "page.png"), "wb") as f:
                f.write(page_png)
        if presents:
            # The backend switched on the page: the CPU's 2D canvas replaces
            # the WebGPU one (a canvas keeps its first kind of context).
            js("const b = document.getElementById('backend'); b.value = 'cpu';"
               " b.dispatchEvent(new Event('change'));")
            switched = {}
            for _ in range(120):
                switched = js(
                    "const s = document.getElementById('status');"
                    "return {status: s.textContent, error: s.dataset.state === 'error',"
                    " samples: Number(document.getElementById('stats').dataset.samples || 0)};"
                )
                if switched["error"] or ("on the CPU" in switched["status"] and switched["samples"] >= 1):
                    break
                time.sleep(0.5)
            if switched["error"] or "on the CPU" not in switched["status"] or switched["samples"] < 1:
                sys.exit(f"FAIL: switching the page to the CPU: {switched}")
            print(f"page: switched to the CPU: {switched['status']}")
        if a.check:
            report = wd(base, "POST", s + "/execute/async", {
                "script": "const done = arguments[arguments.length - 1];"
                          "dirt.check(arguments[0], 32, 4, 1500).then(done, e => done('error: ' + (e.message || e)));",
                "args": [a.scene]}, timeout=a.timeout)
            print("check:", report)
            with open(os.path.join(a.out, "check.txt"), "w") as f:
                f.write(report + "\n")
    finally:
        if session:
            try:
                wd(base, "DELETE", f"/session/{session}")
            except OSError:
                pass
        driver.terminate()
        server.shutdown()

    w, h = (int(v) for v in a.size.split("x"))
    ref = os.path.join(a.out, "reference.png")
    cmd = [a.dirt, "render", a.scene, "--backend", "cpu", "--spp", str(a.spp),
           "--width", str(w), "--height", str(h), "--out", ref] + shlex.split(state["camera"])
    print("reference:", " ".join(shlex.quote(c) for c in cmd))
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    rw, rh, ref_px = png_rgb(open(ref, "rb").read())
    sw, sh, shot_px = png_rgb(shot)
    if page_png is None:
        # Presented on a WebGPU canvas: the image as the screenshot shows it.
        pw, ph, page_px = w, h, downsample(sw, sh, shot_px, w, h)
        with open(os.path.join(a.out, "page.ppm"), "wb") as f:
            f.write(b"P6 %d %d 255\n" % (w, h) + page_px)
        print(f"page: read from the {sw}x{sh} screenshot (a WebGPU canvas is not read back)")
    else:
        pw, ph, page_px = png_rgb(page_png)
    if (pw, ph) != (rw, rh):
        sys.exit(f"FAIL: the page's image is {pw}x{ph}, the reference {rw}x{rh}")
    n = len(ref_px)
    distinct = len({page_px[i : i + 3] for i in range(0, n, 3)})
    mean_abs = sum(abs(x - y) for x, y in zip(page_px, ref_px)) / n
    same = sum(1 for i in range(0, n, 3) if page_px[i : i + 3] == ref_px[i : i + 3]) / (n // 3)
    shot_distinct = len({shot_px[i : i + 3] for i in range(0, len(shot_px), 3)})
    print(f"page against dirt render: mean |difference| {mean_abs:.3f} of 255, "
          f"{100 * same:.2f} % of pixels identical; {distinct} distinct colours "
          f"({shot_distinct} in the screenshot)")
    if distinct < 16 or shot_distinct < 16:
        sys.exit("FAIL: the page's image is (nearly) blank")
    # Bound: the page's passes are `dirt render`'s samples (the same seed,
    # camera and shading); only hits that differ could move pixels.
    if mean_abs > 2.0:
        sys.exit(f"FAIL: the page differs from dirt render by {mean_abs:.3f} of 255 on average")
    print("PASS")


if __name__ == "__main__":
    main()
