"""report.md and a self-contained report.html (figures embedded as base64 PNG) from the sections.

Text in them may come from the campaign workspaces (a failed point's message, a scene's title), which
anyone who can write the workspace controls: every piece of text is escaped where it is placed (HTML
in report.html; Markdown's and HTML's characters in report.md) and its control characters are shown
as escapes, so a crafted message reads as what it is and cannot add markup, a link or a terminal
escape. Both files are written atomically, replacing a link planted at their names (sections.output_file).
"""

from __future__ import annotations

import base64
import html
import math
import re
from pathlib import Path

from granchain import safe_files
from granchain.reproduce.sections import SectionResult, output_file

ROW_HEADER = ["key", "quantity", "unit", "paper", "ours", "+-", "model", "verdict", "tolerance", "reason"]


def fmt(x, digits: int = 4) -> str:
    """A table cell: a number to `digits` significant digits, "" for None and non-finite, else str."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    if isinstance(x, (int, float)):
        return f"{x:.{digits}g}"
    return str(x)


def row_cells(r) -> list[str]:
    """A Row's cells, in ROW_HEADER's order."""
    if r.paper is None:
        tol = ""
    else:
        tol = f"{r.tol:.3g} ({r.tol_source})" if r.tol is not None else "printed precision"
    paper = r.paper_text or fmt(r.paper)
    return [r.key, r.quantity, r.unit, paper, fmt(r.ours), fmt(r.ours_error, 2), fmt(r.model), r.verdict, tol, r.reason]


def cost_cells(s: SectionResult) -> list[str]:
    """A section's line of the cost table, in COST_HEADER's order: our runs, wall time and
    bead-steps beside the paper's setup and the bead-steps it implies."""
    c = s.cost or {}
    return [
        s.title,
        str(c.get("runs", "")),
        fmt(c.get("wall_time"), 3),
        fmt(c.get("bead_steps"), 3),
        s.paper_cost,
        fmt(s.paper_bead_steps, 3),
    ]


COST_NOTE = (
    "Our wall time is each run's with its 2 dt and 4 dt companions (the error bars), summed over the campaign "
    "points, whichever call computed them (a cached point keeps its cost). The paper's bead-steps are what its "
    "stated setup implies (RK4 at 5e-9 s over the chain and time each figure needs); it reports no timings."
)
COST_HEADER = ["section", "our runs", "our wall time (s)", "our bead-steps", "the paper's setup", "paper bead-steps"]


def cost_rows(sections: list[SectionResult]) -> list[list[str]]:
    """The cost table: a line per section with a cost (ours or the paper's), and the total."""
    rows = [cost_cells(s) for s in sections if s.cost or s.paper_cost]
    total = {k: sum((s.cost or {}).get(k, 0) for s in sections) for k in ("runs", "wall_time", "bead_steps")}
    paper = sum(s.paper_bead_steps or 0 for s in sections)
    rows.append(["total", str(total["runs"]), fmt(total["wall_time"], 3), fmt(total["bead_steps"], 3),
                 "RK4 (4 force evaluations a step) at 5e-9 s", fmt(paper, 3)])  # fmt: skip
    return rows


#: control characters (C0 but newline and tab, DEL, C1) and the bidirectional overrides that make
#: text display other than it reads
_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069]")
#: what Markdown (CommonMark and GitHub's) or inline HTML gives a meaning to, inside a line
_MD_SPECIAL = re.compile(r"([\\`*_\[\]<>&|~!#@])")
#: GitHub's bare-URL autolinks ("https://...", "www....")
_AUTOLINK = re.compile(r"(?i)(:)(//)|(www)(\.)")


def plain(text) -> str:
    r"""``text`` with its control characters shown as escapes (``\\x1b``), never sent."""
    return _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), str(text))


def md_text(text, one_line: bool = False) -> str:
    """``text`` as literal Markdown: every character Markdown or HTML would read as markup
    backslash-escaped (rendered as itself), bare URLs broken up so none becomes a link;
    ``one_line``: its line breaks as spaces (a heading, a caption, a table cell)."""
    out = _MD_SPECIAL.sub(r"\\\1", plain(text))
    out = _AUTOLINK.sub(lambda m: "\\".join(g for g in m.groups() if g), out)
    return " ".join(out.splitlines()) if one_line else out


def html_text(text) -> str:
    """``text`` as literal HTML (quotes too: safe in an attribute)."""
    return html.escape(plain(text), quote=True)


def _code_block(note: str) -> str | None:
    """A note written as a fenced block (a failed section's traceback): its text, else None."""
    if note.startswith("```\n") and note.endswith("```"):
        return note[4:-3]
    return None


def _md_note(note: str) -> list[str]:
    code = _code_block(note)
    if code is None:
        return [md_text(note), ""]
    # indented, not fenced: no line of the text (a message with ``` in it) can end the block
    return [*("    " + plain(line) for line in code.rstrip("\n").split("\n")), ""]


def _md_table(header, rows) -> list[str]:
    esc = [[md_text(c, one_line=True) for c in r] for r in rows]
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header), *("| " + " | ".join(r) + " |" for r in esc)]


def write_markdown(out: Path, sections: list[SectionResult], meta: dict) -> Path:
    """Write OUT/report.md: every printed number in one table, then each section (notes, rows,
    figures) and the cost table; returns its path."""
    lines = [
        "# Reproducing Pal & Geubelle, *Wave propagation in elastic and elastoplastic granular chains*",
        "",
        f"Mode: **{md_text(meta['mode'])}**; granchain {md_text(meta['version'])}; {md_text(meta['when'])}. "
        f"Runs this call: {meta['ran']} (cached: {meta['cached']}). Wall time of this call: {meta['elapsed']:.1f} s.",
        "",
        "A verdict compares our value with the printed one within the paper's own stated error where it states "
        "one (the tolerance column says which), else within the precision of the printed number, plus our "
        "error bar. Nothing here is tuned to a printed value. Models are the paper's equations as derived "
        "(granchain.physics.models; docs/paper-discrepancies.md).",
        "",
        "## Every printed number",
        "",
        *_md_table(ROW_HEADER, [row_cells(r) for s in sections for r in s.rows]),
        "",
    ]
    for s in sections:
        lines += [f"## {md_text(s.title, one_line=True)}", ""]
        if not s.reproduced:
            lines += ["**Not yet reproduced.**", ""]
        for n in s.notes:
            lines += _md_note(n)
        if s.rows:
            lines += [*_md_table(ROW_HEADER, [row_cells(r) for r in s.rows]), ""]
        for f in s.figures:
            lines += [f"![{md_text(f.name)}](figures/{f.name}.png)", "", f"*{md_text(f.caption, one_line=True)}*", ""]
    lines += ["## Cost", "", COST_NOTE, "", *_md_table(COST_HEADER, cost_rows(sections)), ""]
    path = output_file(out / "report.md")
    safe_files.write_text(path, "\n".join(lines))
    return path


def _html_table(header, rows) -> str:
    h = "".join(f"<th>{html_text(c)}</th>" for c in header)
    body = "".join("<tr>" + "".join(f"<td class='{_cls(c)}'>{html_text(c)}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def _cls(c) -> str:
    return {"agrees": "ok", "disagrees": "bad", "not yet reproduced": "todo"}.get(str(c), "")


def write_html(out: Path, sections: list[SectionResult], meta: dict) -> Path:
    """Write OUT/report.html, the same report in one self-contained page (figures embedded as base64
    PNG, verdicts coloured); returns its path."""
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>granchain reproduce</title><style>",
        "body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse;font-size:12px}"
        "td,th{border:1px solid #ccc;padding:2px 4px;vertical-align:top}.ok{background:#dfd}.bad{background:#fdd}"
        ".todo{background:#eee}img{max-width:100%}",
        "</style></head><body>",
        "<h1>Reproducing Pal &amp; Geubelle, wave propagation in granular chains</h1>",
        f"<p>Mode: <b>{html_text(meta['mode'])}</b>; granchain {html_text(meta['version'])}; "
        f"{html_text(meta['when'])}. "
        f"Runs this call: {meta['ran']} (cached: {meta['cached']}). Wall time: {meta['elapsed']:.1f} s.</p>",
        "<h2>Every printed number</h2>",
        _html_table(ROW_HEADER, [row_cells(r) for s in sections for r in s.rows]),
    ]
    for s in sections:
        parts.append(f"<h2>{html_text(s.title)}</h2>")
        if not s.reproduced:
            parts.append("<p><b>Not yet reproduced.</b></p>")
        parts += [_html_note(n) for n in s.notes]
        for f in s.figures:
            data = base64.b64encode(safe_files.read_bytes(out / "figures" / f"{f.name}.png")).decode()
            parts.append(
                f"<figure><img alt='{html_text(f.name)}' src='data:image/png;base64,{data}'>"
                f"<figcaption>{html_text(f.caption)}</figcaption></figure>"
            )
    parts += ["<h2>Cost</h2>", f"<p>{html_text(COST_NOTE)}</p>", _html_table(COST_HEADER, cost_rows(sections))]
    parts.append("</body></html>")
    path = output_file(out / "report.html")
    safe_files.write_text(path, "\n".join(parts))
    return path


def _html_note(note: str) -> str:
    code = _code_block(note)
    return f"<p>{html_text(note)}</p>" if code is None else f"<pre>{html_text(code)}</pre>"
