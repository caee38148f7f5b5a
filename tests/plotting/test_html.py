"""The HTML pieces of the report and the notebook (plotting/html.py): escaped text,
tables with numbers, folds, and figures embedded as PNG that decode to the figure."""

import base64

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from blockid.plotting.html import details, encode_png, figure, image, paragraph, table


def test_text_is_escaped_everywhere_it_is_written():
    assert paragraph("a < b & c", "note") == '<p class="note">a &lt; b &amp; c</p>'
    assert paragraph("x") == "<p>x</p>"
    assert image("QUJD", 'say "hi"', "width: 50%") == (
        '<img src="data:image/png;base64,QUJD" alt="say &quot;hi&quot;" style="width: 50%">'
    )
    assert figure("QUJD", "alt", "<b>") == (
        '<figure>\n<img src="data:image/png;base64,QUJD" alt="alt">\n'
        "<figcaption>&lt;b&gt;</figcaption>\n</figure>"
    )
    assert details("more <", ["<p>1</p>", "<p>2</p>"]) == (
        "<details>\n<summary>more &lt;</summary>\n<p>1</p>\n<p>2</p>\n</details>"
    )


def test_a_table_rounds_floats_keeps_integers_and_classes_its_rows():
    html = table(
        ["a", "b", "c"],
        [[1 / 3, 7, None], [True, "x/y/z", 2.0]],
        ["best"],
        digits=2,
        wrap=[1],
    )
    assert '<tr class="best"><td class="num">0.33</td><td class="num">7</td><td></td></tr>' in html
    # a boolean is text, not a number; only column 1 may break anywhere
    assert '<tr><td>True</td><td class="wrap">x/y/z</td><td class="num">2</td></tr>' in html


def test_an_embedded_png_decodes_to_the_figure_and_a_pyplot_figure_is_closed():
    fig = plt.figure(figsize=(2, 1))
    raw = base64.b64decode(encode_png(fig, dpi=50))
    assert raw[:8] == b"\x89PNG\r\n\x1a\n"
    assert int.from_bytes(raw[16:20], "big") == 100 and int.from_bytes(raw[20:24], "big") == 50
    assert not plt.fignum_exists(fig.number)
    assert b"matplotlib" not in raw.lower()  # no metadata naming a web site
    plain = Figure(figsize=(1, 1))  # not made by pyplot: nothing to close
    assert base64.b64decode(encode_png(plain, dpi=np.int64(20)))[16:24] == (20).to_bytes(
        4, "big"
    ) + (20).to_bytes(4, "big")
