"""Tables of the benchmark's report and printouts, written once for :mod:`benchmarks.report` and
:mod:`benchmarks.batch.report`: Markdown for REPORT.md, aligned plain text for stdout.  ``cell`` turns an entry
into its text (each report formats its numbers its own way)."""
from __future__ import annotations


def markdown_table(header, rows, align: str, cell=str) -> str:
    """A Markdown table; ``align`` holds 'l' or 'r' per column."""
    sep = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(map(str, header)) + " |", "| " + " | ".join(sep) + " |"]
    return "\n".join(lines + ["| " + " | ".join(cell(c) for c in r) + " |" for r in rows])


def text_table(header, rows, cell=str) -> str:
    """A plain-text table: columns padded to their widest entry, a rule of dashes under the header."""
    cells = [list(map(str, header))] + [[cell(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    out = []
    for k, r in enumerate(cells):
        out.append("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
        if k == 0:
            out.append("  ".join("-" * w for w in widths))
    return "\n".join(out)
