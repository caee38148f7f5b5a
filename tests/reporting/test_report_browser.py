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
