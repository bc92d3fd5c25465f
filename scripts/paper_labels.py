"""Number the LaTeX labels of the paper as the journal's class prints them.

Usage::

    python scripts/paper_labels.py [PAPER.tex] > table.md

Rules (the paper uses ``\\documentclass{jfm}``, the Journal of Fluid Mechanics class):

- sections are numbered 1, 2, …; after ``\\appendix`` they are lettered A, B, …;
  subsections ``n.m``;
- equations are numbered within sections, printed ``(2.1)``; in an appendix ``(A 1)``;
- every row of ``equation``/``eqnarray``/``align`` is numbered unless it carries
  ``\\nonumber``/``\\notag``; starred environments are not numbered;
- figures and tables are numbered consecutively through the paper.

Prints a markdown table ``| label | kind | printed |`` in the order of the LaTeX source.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

# The paper's LaTeX source lives outside the repository, in ``shared/`` beside the clone.
DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "paper" / "000_27ec9876b06dcf14.txt"
NUMBERED = ("equation", "eqnarray", "align", "gather", "multline")
TOKEN = re.compile(
    r"\\(section|subsection|subsubsection)\*?\s*\{|\\appendix\b|"
    r"\\begin\{(\w+\*?)\}|\\end\{(\w+\*?)\}|\\label\{([^}]*)\}|"
    r"\\\\|\\nonumber\b|\\notag\b"
)


def _strip_comments(text: str) -> str:
    return re.sub(r"(?<!\\)%.*", "", text)


def number_labels(text: str) -> list[tuple[str, str, str]]:
    """``[(label, kind, printed number)]`` in source order."""
    text = _strip_comments(text)
    out: list[tuple[str, str, str]] = []
    sec = sub = 0
    appendix = False
    eq = fig = tab = 0
    env: list[str] = []  # open environments
    row_labels: list[str] = []  # labels of the current equation row
    row_numbered = True
    float_kind: str | None = None
    float_labels: list[str] = []

    def sec_name() -> str:
        return chr(ord("A") + sec - 1) if appendix else str(sec)

    def eq_name(n: int) -> str:
        return f"{sec_name()} {n}" if appendix else f"{sec_name()}.{n}"

    def close_row() -> None:
        nonlocal eq, row_labels, row_numbered
        if row_numbered:
            eq += 1
            num = eq_name(eq)
        else:
            num = "(not numbered)"
        out.extend((lab, "equation", num) for lab in row_labels)
        row_labels, row_numbered = [], True

    def in_math() -> str | None:
        for e in reversed(env):
            if e.rstrip("*") in NUMBERED:
                return e
        return None

    for m in TOKEN.finditer(text):
        tok = m.group(0)
        if m.group(1):
            level = m.group(1)
            if level == "section":
                sec, sub, eq = sec + 1, 0, 0
                pending = ("section", sec_name())
            elif level == "subsection":
                sub += 1
                pending = ("subsection", f"{sec_name()}.{sub}")
            else:
                pending = None
            if pending:
                # the label that follows the heading (before other text) names it
                rest = text[m.end() : m.end() + 400]
                depth, i = 1, 0
                while i < len(rest) and depth:
                    depth += {"{": 1, "}": -1}.get(rest[i], 0)
                    i += 1
                lab = re.match(r"\s*\\label\{([^}]*)\}", rest[i:])
                if lab:
                    out.append((lab.group(1), pending[0], pending[1]))
        elif tok.startswith("\\appendix"):
            appendix, sec = True, 0
        elif m.group(2):
            name = m.group(2)
            env.append(name)
            if name.rstrip("*") in ("figure", "table"):
                float_kind, float_labels = name.rstrip("*"), []
            if name.rstrip("*") in NUMBERED:
                row_labels, row_numbered = [], not name.endswith("*")
        elif m.group(3):
            name = m.group(3)
            if name.rstrip("*") in NUMBERED and in_math() == name:
                close_row()
            if name.rstrip("*") in ("figure", "table") and float_kind:
                if float_kind == "figure":
                    fig += 1
                    num = str(fig)
                else:
                    tab += 1
                    num = str(tab)
                out.extend((lab, float_kind, num) for lab in float_labels)
                float_kind = None
            if env and env[-1] == name:
                env.pop()
        elif m.group(4):
            lab = m.group(4)
            if in_math():
                row_labels.append(lab)
            elif float_kind:
                float_labels.append(lab)
            elif not any(lab == o[0] for o in out):
                out.append((lab, "other", "?"))
        elif tok == "\\\\":
            if in_math() and not in_math().endswith("*") and env[-1] == in_math():
                close_row()
            elif in_math() and env[-1] == in_math():
                row_labels = []
        else:  # \nonumber, \notag
            if in_math():
                row_numbered = False
    return out


def markdown(rows: list[tuple[str, str, str]]) -> str:
    """The rows as a markdown table (equation numbers in parentheses, as printed)."""
    lines = ["| LaTeX label | kind | printed as |", "|---|---|---|"]
    for lab, kind, num in rows:
        if kind == "equation" and not num.startswith("("):
            shown = f"({num})"
        elif kind == "section":
            shown = f"§{num}" if num[0].isdigit() else f"appendix {num}"
        elif kind == "subsection":
            shown = f"§{num}"
        elif kind in ("figure", "table"):
            shown = f"{kind} {num}"
        else:
            shown = num
        lines.append(f"| `{lab}` | {kind} | {shown} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    sys.stdout.write(markdown(number_labels(path.read_text(encoding="utf-8"))))
