"""The example's report in headless Chromium: every figure displayed, nothing fetched.

Skipped when no ``chromium`` / ``chromium-browser`` is installed (CI installs Debian's
package). The browser runs with name resolution mapped to nowhere and a proxy that does
not exist, so a reference to anything outside the file could not load; a script added
to a copy of the report records, after the page has loaded, every image's natural width
and every resource the page requested.
"""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

BROWSER = shutil.which("chromium") or shutil.which("chromium-browser")

pytestmark = pytest.mark.skipif(BROWSER is None, reason="no chromium binary on PATH")

OFFLINE = [
    "--headless",
    "--disable-gpu",
    "--no-sandbox",
    "--no-first-run",
    "--disable-extensions",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--host-resolver-rules=MAP * ~NOTFOUND",
    "--proxy-server=127.0.0.1:9",
]

CHECK = """<script>
window.addEventListener("load", function () {
  var images = Array.prototype.map.call(document.images, function (img) {
    return [img.complete, img.naturalWidth, img.naturalHeight];
  });
  var fetched = performance.getEntriesByType("resource").map(function (e) { return e.name; });
  var out = document.createElement("pre");
  out.id = "blockid-check";
  out.textContent = JSON.stringify({images: images, fetched: fetched});
  document.body.appendChild(out);
});
</script>
"""


def _chromium(tmp_path, *args: str) -> subprocess.CompletedProcess:
    profile = tmp_path / "profile"
    return subprocess.run(
        [BROWSER, *OFFLINE, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_every_figure_is_displayed_and_nothing_is_fetched(example_report, tmp_path):
    page = example_report.html
    n_images = page.count("<img ")
    assert n_images >= 4
    probe = tmp_path / "probe.html"
    probe.write_text(page.replace("</body>", CHECK + "</body>"), encoding="utf-8")
    run = _chromium(tmp_path, "--virtual-time-budget=10000", "--dump-dom", probe.as_uri())
    found = re.search(r'<pre id="blockid-check">(.*?)</pre>', run.stdout, re.S)
    assert found, f"no result from the page; chromium said: {run.stderr[-2000:]}"
    result = json.loads(html.unescape(found.group(1)))
    assert len(result["images"]) == n_images
    for complete, width, height in result["images"]:
        assert complete and width > 0 and height > 0
    outside = [u for u in result["fetched"] if not u.startswith(("data:", "file:"))]
    assert not outside, outside


def test_the_screenshot_is_not_blank(example_report, tmp_path):
    from matplotlib.image import imread

    shot = tmp_path / "shot.png"
    run = _chromium(
        tmp_path,
        "--hide-scrollbars",
        "--window-size=1200,2400",
        f"--screenshot={shot}",
        example_report.path.as_uri(),
    )
    assert shot.exists(), run.stderr[-2000:]
    pixels = imread(shot)[..., :3]
    not_white = np.any(pixels < 0.9, axis=-1)
    assert not_white.mean() > 0.03  # text, tables and figures, not an empty page
    levels = (pixels * 31).astype(int)  # 32 levels per channel
    colours = np.unique(levels[..., 0] * 1024 + levels[..., 1] * 32 + levels[..., 2])
    assert colours.size > 50  # figures in colour, not only black text


# ------------------------------------------------------------------ layout, new sections
LAYOUT = """<script>
window.addEventListener("load", function () {
  var broken = [];
  document.querySelectorAll("td:not(.wrap), th, p, figcaption, h3").forEach(function (el) {
    var walker = document.createTreeWalker(el, NodeFilter.SHOW_TEXT);
    var node;
    while ((node = walker.nextNode())) {
      var words = /[^\\s\\-]+/g, m;
      while ((m = words.exec(node.data))) {
        var range = document.createRange();
        range.setStart(node, m.index);
        range.setEnd(node, m.index + m[0].length);
        var tops = new Set(Array.prototype.filter.call(range.getClientRects(), function (r) {
          return r.width > 0;
        }).map(function (r) { return Math.round(r.top); }));
        if (tops.size > 1) { broken.push(m[0]); }
      }
    }
  });
  var scrolled = [];
  document.querySelectorAll("table").forEach(function (t) {
    if (t.scrollWidth > t.clientWidth + 1) { scrolled.push(t.rows[0].innerText); }
  });
  var out = document.createElement("pre");
  out.id = "blockid-layout";
  out.textContent = JSON.stringify({broken: broken, scrolled: scrolled,
    page: document.documentElement.scrollWidth, window: window.innerWidth});
  document.body.appendChild(out);
});
</script>
"""


def _layout(page: str, tmp_path, width: int) -> dict:
    probe = tmp_path / f"layout{width}.html"
    probe.write_text(page.replace("</body>", LAYOUT + "</body>"), encoding="utf-8")
    run = _chromium(tmp_path, "--virtual-time-budget=10000", f"--window-size={width},2000",
                    "--dump-dom", probe.as_uri())  # fmt: skip
    found = re.search(r'<pre id="blockid-layout">(.*?)</pre>', run.stdout, re.S)
    assert found, f"no result from the page; chromium said: {run.stderr[-2000:]}"
    return json.loads(html.unescape(found.group(1)))


def test_no_word_is_broken_and_nothing_overflows(example_report, tmp_path):
    """At a desktop width every word stays whole and every table fits the column; in a
    narrow window the page still does not overflow (a wide table scrolls in its box)."""
    wide = _layout(example_report.html, tmp_path, 1280)
    assert wide["broken"] == [] and wide["scrolled"] == []
    assert wide["page"] <= wide["window"]
    narrow = _layout(example_report.html, tmp_path, 640)
    assert narrow["broken"] == []  # a table too wide scrolls: its words are not split
    assert narrow["page"] <= narrow["window"]


def _only(page: str, anchors: tuple[str, ...]) -> str:
    """The report with only the sections ``anchors`` (same head and style sheet)."""
    head = page[: page.index("<body>") + len("<body>")]
    parts = [re.search(rf'<section id="{a}">.*?</section>', page, re.S).group(0) for a in anchors]
    return head + "\n" + "\n".join(parts) + "\n</body>\n</html>\n"


@pytest.mark.parametrize(
    "anchors, figures",
    [(("parameters",), False), (("linear",), True), (("outputs", "blocks"), True)],
)
def test_the_new_sections_are_drawn(example_report, tmp_path, anchors, figures):
    """Screenshots of the parameter tables, the linear dynamics, and the outputs (zoom
    and all) with the blocks: not blank, and in colour where they hold figures."""
    from matplotlib.image import imread

    view = tmp_path / f"{'-'.join(anchors)}.html"
    view.write_text(_only(example_report.html, anchors), encoding="utf-8")
    shot = tmp_path / f"{'-'.join(anchors)}.png"
    run = _chromium(tmp_path, "--hide-scrollbars", "--window-size=1200,1800",
                    f"--screenshot={shot}", view.as_uri())  # fmt: skip
    assert shot.exists(), run.stderr[-2000:]
    pixels = imread(shot)[..., :3]
    assert np.any(pixels < 0.9, axis=-1).mean() > 0.02  # tables or figures, not blank
    if figures:
        levels = (pixels * 31).astype(int)
        colours = np.unique(levels[..., 0] * 1024 + levels[..., 1] * 32 + levels[..., 2])
        assert colours.size > 50


def test_a_state_space_report_reads_at_1280_and_640_px(state_space_report, tmp_path):
    """The state-space sections (the Nyquist pole named in the table, '= free run' in
    the one-step cells, the basis-free quantities and the folded matrices, opened) laid
    out in Chromium: at 1280 px no word split and every table fits; at 640 px still no
    word split and no overflow of the page; the sections drawn, in colour."""
    from matplotlib.image import imread

    _, _, page = state_space_report
    opened = page.replace("<details>", "<details open>")
    wide = _layout(opened, tmp_path, 1280)
    assert wide["broken"] == [] and wide["scrolled"] == []
    assert wide["page"] <= wide["window"]
    narrow = _layout(opened, tmp_path, 640)
    assert narrow["broken"] == [] and narrow["page"] <= narrow["window"]
    for width in (1280, 640):
        view = tmp_path / f"state-space-{width}.html"
        view.write_text(_only(opened, ("comparison", "parameters", "linear")), encoding="utf-8")
        shot = tmp_path / f"state-space-{width}.png"
        run = _chromium(tmp_path, "--hide-scrollbars", f"--window-size={width},3000",
                        f"--screenshot={shot}", view.as_uri())  # fmt: skip
        assert shot.exists(), run.stderr[-2000:]
        pixels = imread(shot)[..., :3]
        assert np.any(pixels < 0.9, axis=-1).mean() > 0.02
        levels = (pixels * 31).astype(int)
        colours = np.unique(levels[..., 0] * 1024 + levels[..., 1] * 32 + levels[..., 2])
        assert colours.size > 50
