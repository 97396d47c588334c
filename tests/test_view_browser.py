"""The inspector in a real browser: Debian's headless chromium opens the page,
the scene is drawn (software WebGL), a click on a region highlights it.

Needs the ``chromium`` Debian package (``apt-get install -y chromium``);
without it these tests FAIL and say so: a skipped browser test would hide a
broken inspector. chromium is driven over the DevTools protocol by
:mod:`mapkit_harness.browser` (only the ``websockets`` package, a viser
dependency, is needed on the Python side).
"""

from __future__ import annotations


import cv2
import numpy as np
import pytest

from mapkit.view.server import Inspector
from mapkit_harness.browser import BrowserMissing, Chromium, find_chromium, wait_for
from mapkit_harness.inspector import HEIGHT, VIEW, WIDTH, hue_histogram, open_and_wait, scene_drawn
from mapkit_harness.plans import grid_flat

pytestmark = pytest.mark.browser

@pytest.fixture(scope="module")
def browser():
    try:
        find_chromium()
    except BrowserMissing as exc:
        pytest.fail(str(exc), pytrace=False)
    with Chromium(WIDTH, HEIGHT) as b:
        yield b


def settled_view(browser: Chromium, timeout: float = 20.0) -> np.ndarray:
    """A screenshot once the view has stopped changing (the client may still
    be placing its camera or streaming nodes after its first frame): a pixel
    picked from an earlier frame could be a different region by click time."""
    last = browser.screenshot()

    def same_as_last():
        nonlocal last
        now = browser.screenshot()
        still = (np.abs(now.astype(int) - last).sum(axis=2) > 30).mean() < 1e-4
        last = now
        return now if still else None

    return wait_for(same_as_last, timeout, interval=0.3, what="the view to settle")


def interior_pixel(img: np.ndarray) -> tuple[int, int]:
    """(x, y) of a pixel inside a region fill: coloured, with a uniform 11 x 11
    neighbourhood (no outline or segment nearby), nearest the view's middle."""
    view = img[VIEW].astype(np.int16)
    hsv = cv2.cvtColor(np.ascontiguousarray(img[VIEW]), cv2.COLOR_RGB2HSV)
    k = np.ones((11, 11), np.uint8)
    spread = np.zeros(view.shape[:2], np.int16)
    for c in range(3):
        ch = view[..., c].astype(np.uint8)
        spread = np.maximum(spread, cv2.dilate(ch, k).astype(np.int16) - cv2.erode(ch, k).astype(np.int16))
    ok = (spread < 6) & (hsv[..., 1] > 40) & (hsv[..., 2] > 60)
    ys, xs = np.nonzero(ok)
    assert len(xs), "no region fill large enough to click on"
    my, mx = np.mean(ys), np.mean(xs)
    i = int(np.argmin((ys - my) ** 2 + (xs - mx) ** 2))
    return int(xs[i]) + VIEW[1].start, int(ys[i]) + VIEW[0].start


def is_highlight(patch: np.ndarray) -> bool:
    """Mostly magenta (the selection colour, shaded): red and blue well above green."""
    p = patch.reshape(-1, 3).astype(int)
    magenta = (p[:, 0] - p[:, 1] > 60) & (p[:, 2] - p[:, 1] > 60)
    return magenta.mean() > 0.8


@pytest.mark.slow
def test_page_draws_the_map_and_a_click_highlights_a_region(browser):
    m = grid_flat()
    with Inspector(m, port=0) as ins:
        img, seconds = open_and_wait(browser, ins)
        view = img[VIEW]
        # Not blank: much of the view is neither background white nor one flat colour.
        assert (view.min(axis=2) < 235).mean() > 0.15
        hist = hue_histogram(view)
        assert (hist > 300).sum() >= 5, f"region colours missing: hue histogram {hist.tolist()}"

        # The walls are semi-transparent: a floor pixel seen through one blends
        # the highlight with grey. This test is about the floor, so hide them.
        ins.layers.set_visible("walls", False)
        img = settled_view(browser)
        x, y = interior_pixel(img)
        before = img[y - 2 : y + 3, x - 2 : x + 3]
        assert not is_highlight(before)
        browser.click(x, y)
        wait_for(lambda: ins.selection_count >= 1, 20, what="the server to receive the click")
        assert ins.selected_region is not None, ins.panel.selection.content
        assert ins.panel.selection.content.startswith(f"**Region {ins.selected_region}**")
        after = wait_for(lambda: (lambda s: s if is_highlight(s[y - 2 : y + 3, x - 2 : x + 3]) else None)(
            browser.screenshot()), 20, interval=0.2, what="the clicked region to turn magenta")
        changed = (np.abs(after[VIEW].astype(int) - img[VIEW]).sum(axis=2) > 60).sum()
        assert changed > 200  # the region and its visible segments are redrawn

        # A click off the map clears the highlight.
        count = ins.selection_count
        browser.click(40, HEIGHT - 120)
        wait_for(lambda: ins.selection_count > count, 20, what="the second click")
        assert ins.selected_region is None


@pytest.mark.slow
def test_a_large_map_renders(browser):
    """About 1500 segments and 4600 regions: chromium draws the map (the
    seconds it takes are tools/bench_view.py's table, not a test)."""
    big = grid_flat(rooms=(7, 5), room_size=(5.0, 4.5), cell=0.4)
    with Inspector(big, port=0) as ins:
        img, _ = open_and_wait(browser, ins)
    assert scene_drawn(img)
    assert (img[VIEW].min(axis=2) < 235).mean() > 0.15


@pytest.mark.slow
def test_html_snapshot_draws_from_file_without_a_server(browser, tmp_path):
    from mapkit.view.snapshot import write_snapshot

    path = tmp_path / "flat.html"
    write_snapshot(grid_flat(), path)  # the server it used is stopped again
    browser.navigate(path.as_uri())
    img = wait_for(lambda: (lambda s: s if scene_drawn(s) else None)(browser.screenshot()), 60, interval=0.1,
                   what="the snapshot to draw the map")
    assert (img[VIEW].min(axis=2) < 235).mean() > 0.15
    # Everything came from the file itself: no http(s) request was made.
    urls = browser.evaluate("performance.getEntriesByType('resource').map(e => e.name)")
    assert not [u for u in urls if u.startswith(("http:", "https:", "ws:"))], urls
