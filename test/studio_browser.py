"""Helpers for the studio's browser tests: Debian's chromium driven by Playwright, the page's camera, screenshots."""
from __future__ import annotations

import shutil
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

CHROMIUM = '/usr/bin/chromium'
# Flags that work headless on this kind of machine (no GPU, no display, no network but loopback).
CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update', '--disable-sync']
VIEWPORT = {'width': 1024, 'height': 640}
SHOTS = Path(__file__).resolve().parents[1] / 'out' / 'studio_test'
TIMEOUT = 60.0  # [s] deadline of any single wait


def chromium_path() -> str:
    """The browser, or a clear failure naming the fix."""
    if not Path(CHROMIUM).is_file():
        found = shutil.which('chromium')
        if found is None:
            raise RuntimeError('no chromium: run `make setup` as root (it installs Debian\'s chromium) or '
                               '`sudo apt-get install chromium`')
        return found
    return CHROMIUM


@contextmanager
def launched_chromium() -> Iterator:
    """Debian's chromium, headless, driven by Playwright for the block (it cannot download browsers here)."""
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


def wait_until(condition, what: str, timeout: float = TIMEOUT, poll: float = 0.02):
    """Poll ``condition()`` until it returns a truthy value (returned) or the deadline passes (TimeoutError)."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            raise TimeoutError(f'timed out after {timeout:.0f} s waiting for {what}')
        time.sleep(poll)


def set_camera(client, position, look_at, up=(0.0, 0.0, 1.0), timeout: float = TIMEOUT) -> None:
    """Put the page's camera at ``position`` looking at ``look_at`` and wait until the page reports it back."""
    seen = []
    client.camera.on_update(lambda cam: seen.append((np.array(cam.position), np.array(cam.look_at))))
    client.camera.up_direction = up
    client.camera.position = position
    client.camera.look_at = look_at
    wait_until(lambda: any(np.allclose(p, position, atol=1e-6) and np.allclose(a, look_at, atol=1e-6)
                           for p, a in list(seen)), 'the page to take the camera pose', timeout)


def pixel_ray(client, x: float, y: float, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """World ray (origin, unit direction) through pixel (x, y) of a ``width`` x ``height`` canvas, from the
    camera's pose and vertical field of view (a pinhole camera, as three.js renders)."""
    cam = client.camera
    position, look_at = np.array(cam.position), np.array(cam.look_at)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, cam.up_direction)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    half = np.tan(cam.fov / 2.0)
    ndc_x, ndc_y = 2.0 * x / width - 1.0, 1.0 - 2.0 * y / height
    d = forward + ndc_x * half * (width / height) * right + ndc_y * half * up
    return position, d / np.linalg.norm(d)


def project(client, point, width: int, height: int) -> tuple[float, float]:
    """Pixel (x, y) of a world point in the page's camera (inverse of :func:`pixel_ray`)."""
    cam = client.camera
    position, look_at = np.array(cam.position), np.array(cam.look_at)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, cam.up_direction)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    v = np.asarray(point, dtype=float) - position
    half = np.tan(cam.fov / 2.0)
    ndc_x = (v @ right) / (v @ forward) / (half * width / height)
    ndc_y = (v @ up) / (v @ forward) / half
    return (ndc_x + 1.0) * width / 2.0, (1.0 - ndc_y) * height / 2.0


def screenshot(page, name: str) -> Path:
    """Write out/studio_test/<name>.png and check that it is not blank (a drawn page has many colours)."""
    SHOTS.mkdir(parents=True, exist_ok=True)
    path = SHOTS / f'{name}.png'
    # Two animation frames: whatever the page has received is drawn.
    page.evaluate('new Promise(done => requestAnimationFrame(() => requestAnimationFrame(done)))')
    page.screenshot(path=str(path))
    from PIL import Image
    image = np.asarray(Image.open(path).convert('RGB')).astype(float)
    colours = len(np.unique(image.reshape(-1, 3)[::7], axis=0))
    assert image.std() > 10.0 and colours > 200, f'{path} is blank (pixel std {image.std():.1f}, {colours} colours)'
    return path


def dismiss_toasts(page, timeout: float = 10.0) -> None:
    """Close the page's 'software WebGL rendering' notice (shown without a GPU) so that it covers nothing."""
    notice = page.locator('#webgl-software-rendering')
    try:
        notice.wait_for(state='visible', timeout=timeout * 1e3)
    except Exception:  # not shown (a GPU) within the deadline
        return
    notice.locator('button').first.click()
    notice.wait_for(state='hidden', timeout=timeout * 1e3)


def free_port() -> int:
    """A TCP port free on the loopback interface now."""
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def open_page(browser, studio, viewport: dict = VIEWPORT):
    """A new page on the studio: (page, the studio's handle of that page's client); page.ws_frames collects the
    arrival times of its websocket messages."""
    page = browser.new_page(viewport=viewport)
    # Arrival times of the page's websocket messages (viser's socket lives in a web worker, which the DevTools
    # network domain of the page does not see; Playwright reports its frames as the test pumps events).
    page.ws_frames = []
    page.on('websocket', lambda ws: ws.on('framereceived', lambda _: page.ws_frames.append(time.monotonic())))
    before = set(studio.server.get_clients())
    page.goto(f'http://127.0.0.1:{studio.server.get_port()}')
    new = wait_until(lambda: sorted(set(studio.server.get_clients()) - before), 'the page to connect')  # ids from 0
    client = studio.server.get_clients()[new[0]]
    wait_until(lambda: page.get_by_text('Connected').count() > 0 or page.locator('canvas').count() > 0,
               'the page to draw')
    dismiss_toasts(page)
    return page, client


def pump_until(page, condition, what: str, timeout: float) -> None:
    """Wait with the browser's event loop turning, so that websocket events are timed as they arrive."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f'timed out after {timeout:.0f} s waiting for {what}')
        page.wait_for_timeout(50)
