"""The viewer in a real browser: headless Chromium (Debian's package) driven by Playwright.

Both the live server (on an ephemeral loopback port, stopped by the test) and the
static export (a file:// page) must render a picture that is not blank, change it
when the timeline moves, log no console error and load nothing from anywhere but
themselves.  Screenshots are kept in the session's pytest folder
(``.../view-screens/``).  WebGL has no GPU here: ``--enable-unsafe-swiftshader``.
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
    "--disable-quic", "--no-first-run", "--disable-background-networking",
    "--disable-component-update", "--disable-sync",
]  # fmt: skip
VIEWPORT = {"width": 1000, "height": 640}
#: seconds between looks at the canvas while waiting for it to draw or change
POLL = 0.3


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    if not Path(CHROMIUM).exists():
        pytest.skip("no Chromium here: install Debian's package 'chromium' (apt-get install "
                    "chromium; .ci/run does) to run the browser tests")  # fmt: skip
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright (the test extra)")
    profile = tmp_path_factory.mktemp("chromium-profile")  # a fresh --user-data-dir
    with sync_api.sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(profile), executable_path=CHROMIUM, headless=True, args=FLAGS,
            viewport=VIEWPORT, timeout=60_000,
        )  # fmt: skip
        try:
            yield context
        finally:
            context.close()


@pytest.fixture(scope="module")
def screens(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("view-screens")


class Page:
    """A page with its console errors and requests recorded."""

    def __init__(self, context, url: str) -> None:
        self.page = context.new_page()
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error"
                     else None)  # fmt: skip
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.goto(url, timeout=60_000)
        self.page.wait_for_selector("canvas", timeout=60_000)

    def canvas(self) -> np.ndarray:
        """The 3-D view as an (H, W, 3) image."""
        import imageio.v3 as iio

        png = self.page.locator("canvas").first.screenshot()
        return iio.imread(png)[..., :3].astype(np.int16)

    def wait_drawn(self, timeout: float = 40.0) -> np.ndarray:
        """The canvas once it shows a scene: many colours, not one flat fill."""
        end = time.monotonic() + timeout
        while True:
            time.sleep(POLL)
            img = self.canvas()
            colours = np.unique(img.reshape(-1, 3) // 8, axis=0).shape[0]
            if (img.std() > 20 and colours > 100) or time.monotonic() > end:
                return img

    def wait_changed(self, before: np.ndarray, timeout: float = 20.0) -> np.ndarray:
        end = time.monotonic() + timeout
        while True:
            time.sleep(POLL)
            img = self.canvas()
            if _changed(before, img) > 0.01 or time.monotonic() > end:
                return img

    def save(self, path: Path) -> Path:
        self.page.screenshot(path=str(path))
        return path


def _changed(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of pixels that differ by more than 24 levels in some channel."""
    return float((np.abs(a - b).max(axis=-1) > 24).mean())


def _drawn(img: np.ndarray) -> bool:
    return img.std() > 20 and np.unique(img.reshape(-1, 3) // 8, axis=0).shape[0] > 100


def test_static_export_renders_and_scrubs_offline(browser, scene, tmp_path, screens):
    from ruledrobot.view import export_html

    path = export_html(scene, tmp_path / "scene.html")
    assert path.stat().st_size < 20e6
    page = Page(browser, path.as_uri())
    first = page.wait_drawn()
    assert _drawn(first), "the exported scene stays blank"
    page.page.keyboard.press("Space")  # viser's playback bar: space pauses
    box = page.page.locator(".mantine-Slider-root").first.bounding_box()
    y = box["y"] + 0.5 * box["height"]
    page.page.mouse.click(box["x"] + 2, y)  # the start: the arm away from the block
    start = page.wait_changed(first, timeout=5.0)
    page.save(screens / "export-start.png")
    page.page.mouse.click(box["x"] + box["width"] - 2, y)  # the end: the cut done
    end = page.wait_changed(start)
    page.save(screens / "export-end.png")
    assert _changed(start, end) > 0.01, "moving the timeline did not change the picture"
    assert page.errors == [], page.errors
    assert {u.split(":", 1)[0] for u in page.requests} <= {"file", "data", "blob"}, page.requests


def test_live_server_renders_and_follows_the_timeline(browser, scene, screens):
    from ruledrobot.view import ViewServer

    with ViewServer(scene, "127.0.0.1", 0, play=False) as srv:
        assert srv.url.startswith("http://127.0.0.1:")
        page = Page(browser, srv.url)
        first = page.wait_drawn()
        assert _drawn(first), "the served scene stays blank"
        page.save(screens / "live-start.png")
        # the panel's time slider, moved in the browser: the server poses the scene there
        thumb = page.page.locator("[role=slider]").first
        thumb.focus()
        thumb.press("End")
        end = page.wait_changed(first)
        page.save(screens / "live-end.png")
        assert _changed(first, end) > 0.01, "moving the timeline did not change the picture"
        assert srv.slider.value == pytest.approx(float(scene.timeline.t[-1]))
        page.page.get_by_text("lead_out").first.wait_for(timeout=10_000)
        assert page.errors == [], page.errors
        host = srv.url.rstrip("/")
        for u in page.requests:
            assert u.startswith((host, host.replace("http", "ws"), "data:", "blob:")), u
