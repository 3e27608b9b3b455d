"""`granchain reproduce` in a DIR someone else may have prepared: no link planted at a file it writes
(report.md, report.html, rows.json, figures/*.png, the figures/ directory) makes it write outside
DIR, a link at its cache (ws/) is one error line, and text from the workspace (a failed point's
message, a title) cannot add markup, links or terminal escapes to the report.

The sections here are stand-ins drawing the report's figures by their real names through the
real Context: the write paths are `reproduce`'s own, and nothing runs a campaign."""

from __future__ import annotations

import json
import os
import sys
import types
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st
from markdown_it import MarkdownIt

import granchain.reproduce as rp
from granchain.reproduce.sections import Figure, Row, SectionResult

#: every figure the real sections draw (their Figure(...) names)
FIGURES = ("fig1", "fig2", "fig3", "fig5", "fig6", "fig7", "fig8", "fig9", "laws")
CRAFTED = (
    "<script>alert(1)</script> <img src=x onerror=alert(2)> [click](https://evil.example/x) "
    "![pixel](https://evil.example/p.png) www.evil.example <https://evil.example> a@evil.example "
    "\x1b]8;;https://evil.example\x07link\x1b]8;;\x07 \x1b[2J \u202etxt.exe\n# injected heading\n"
    "[ref]: https://evil.example\n```\n</pre><b>out</b>\n```"
)


def _stand_in(tmp_name: str, message: str):
    """A section module drawing every figure, with `message` in a note, a row's reason, a title,
    a caption and a traceback (as a workspace's failed point would put it there)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def run(ctx):
        res = SectionResult(tmp_name, f"Stand-in {message}")
        for name in FIGURES:
            fig, ax = plt.subplots()
            ax.plot([0, 1], [1, 0])
            ctx.figure(fig, name)
            res.figures.append(Figure(name, f"caption {message}"))
        res.notes += [f"The run failed: {message}", "```\nTraceback: " + message + "\n```"]
        res.rows.append(Row(f"{tmp_name}.x", message, "N", 1.0, "1.0", ours=1.0, reason=f"failed: {message}"))
        return res

    return types.SimpleNamespace(run=run, campaign_specs=lambda quick: {})


@pytest.fixture
def stand_in(monkeypatch):
    def install(message: str = "fine"):
        monkeypatch.setitem(sys.modules, "granchain.reproduce.stand_in", _stand_in("stand_in", message))
        monkeypatch.setattr(rp, "SECTIONS", (("stand_in", "Stand-in"),))

    return install


def written(out: Path) -> list[Path]:
    """Every file `reproduce` writes in DIR, named from what a call wrote (not listed here)."""
    return sorted(p for p in out.rglob("*") if p.is_file() and "ws" not in p.relative_to(out).parts)


def test_links_planted_at_every_file_reproduce_writes_are_replaced_not_written_through(tmp_path, stand_in):
    stand_in()
    out = tmp_path / "DIR"
    rp.reproduce(out, quick=True)
    names = [p.relative_to(out) for p in written(out)]
    assert {"report.md", "report.html", "rows.json"} <= {str(n) for n in names}
    assert {f"figures/{f}.png" for f in FIGURES} <= {str(n) for n in names}
    outside = tmp_path / "victim"
    outside.mkdir()
    for n in names:  # a link at each, to a file of the victim's
        target = outside / str(n).replace("/", "_")
        target.write_text("the victim's")
        (out / n).unlink()
        os.symlink(target, out / n)
    assert rp.main(["--quick", "--out", str(out), "-q"]) == 0  # the call that only redraws
    assert {p.name: p.read_bytes() for p in outside.iterdir()} == {p.name: b"the victim's" for p in outside.iterdir()}
    for n in names:
        assert not (out / n).is_symlink(), n
    assert (out / "report.html").read_text().rstrip().endswith("</body></html>")
    assert "## Cost" in (out / "report.md").read_text()
    assert json.loads((out / "rows.json").read_text())["rows"]
    assert not [p for p in out.rglob(".*tmp*")]  # no temporary file left behind


def test_a_link_at_figures_is_replaced_and_one_at_the_cache_is_one_error_line(tmp_path, stand_in, capsys):
    stand_in()
    out, elsewhere = tmp_path / "DIR", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    os.symlink(elsewhere, out / "figures")
    assert rp.main(["--quick", "--out", str(out), "-q"]) == 0
    assert list(elsewhere.iterdir()) == []
    assert (out / "figures").is_dir()
    assert not (out / "figures").is_symlink()
    capsys.readouterr()
    (out / "ws").rmdir()  # (empty: the stand-in runs no campaign)
    os.symlink(elsewhere, out / "ws")
    assert rp.main(["--quick", "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("granchain: error:") == 1, err
    assert "Traceback" not in err
    assert f"{out / 'ws'}: is a symbolic link" in err
    assert "remove the link" in err
    assert list(elsewhere.iterdir()) == []


def _markup(md: str) -> list[str]:
    """The HTML, links and images a Markdown renderer makes of ``md`` (CommonMark with tables)."""
    tokens = MarkdownIt("commonmark").enable("table").parse(md)
    found = []
    for t in tokens:
        for c in [t, *(t.children or [])]:
            if c.type in ("html_inline", "html_block", "link_open", "image"):
                found.append(c.type + " " + (c.attrGet("src") or c.attrGet("href") or c.content))
    return found


def test_a_crafted_workspace_message_adds_no_markup_links_or_escapes_to_the_report(tmp_path, stand_in):
    stand_in(CRAFTED)
    out = tmp_path / "DIR"
    rp.reproduce(out, quick=True)
    md, page = (out / "report.md").read_text(), (out / "report.html").read_text()
    # the only markup of report.md: the figures, at their own files
    assert sorted(_markup(md)) == sorted(f"image figures/{f}.png" for f in FIGURES)
    assert "evil.example" in md  # shown, as text
    for text in (md, page):
        assert "\x1b" not in text
        assert "\x07" not in text
        assert "\u202e" not in text
    assert "<script" not in page
    assert "<img src=x" not in page
    assert "<b>out" not in page
    assert "&lt;script&gt;" in page
    assert page.count("<img ") == len(FIGURES)


@given(st.text(max_size=40))
def test_escaped_text_renders_as_itself_and_as_nothing_else(text):
    """md_text: CommonMark renders the escaped text as one paragraph of literal text (control
    characters as escapes); html_text: no tag, and the same text back."""
    import html

    from granchain.reproduce.report import html_text, md_text, plain

    shown = md_text(text)
    tokens = MarkdownIt("commonmark").parse(shown.replace("\n", " ").replace("\r", " ") or "x")
    kinds = {c.type for t in tokens for c in (t.children or [])}
    assert kinds <= {"text", "softbreak", "hardbreak"}, (text, shown, kinds)
    assert "<" not in html_text(text)
    assert "\x1b" not in html_text(text)
    assert html.unescape(html_text(text)) == plain(text)
