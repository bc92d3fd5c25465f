"""Replace the paper's LaTeX labels in user-facing text by the numbers as printed.

Usage::

    python scripts/relabel.py [--dry-run] [PATH ...]     # default: src/ and README.md

Reads the table of docs/paper-labels.md (label → printed number) and rewrites citations:

- ``eq:pmuetc``, ``label eq:T00``, ``labels eq:bc1, eq:bc2`` → ``eq. (2.7)``, ``eq. (3.10)``,
  ``eqs (2.9), (2.10)``; ``(eq:vp0)`` → ``(eq. B 2)``;
- bare equation labels (``disp-oned``, ``etastar``, ``oneaandu``, …) likewise; labels that
  are English words (``condition``, ``criterion``) only where they are cited: after
  ``label``/``labels``/``eq``, in a list with other labels, in parentheses or in
  ``source="…"``;
- figure labels after ``fig``/``figs``/``figure``/``figures`` (``figs disp, dispmag`` →
  ``figures 7, 8``), and the distinctive ones (``phase005``, ``dispmag``, …) anywhere in
  prose → ``figure 6``;
- ``ERRATA item 4`` / ``ERRATA 4`` → ``docs/errata.md, item 4``, other mentions of
  the outside ERRATA file → ``docs/errata.md``.

A label that is a whole quoted string (``"disp"``: a key or file name in code) is left
alone. References to issue numbers are listed (``issue N: …``) but not changed: reword
them by hand. Prints every change as ``path:line: old → new``; running it twice changes
nothing the second time.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "docs" / "paper-labels.md"
#: Labels that are also English words: replaced only where cited (see the module doc).
WORDS = {
    "condition",
    "criterion",
    "table",
    "steady",
    "slope",
    "sum",
    "trans",
    "intro",
    "disp",
    "discussion",
    "mechanism",
}
#: Of these, the ones also recognised alone in parentheses or in ``source="…"``.
CITED_WORDS = {"condition", "criterion"}
SEP = r"(?:\s*(?:,|;|/|…|–|--|\band\b|\bor\b)\s*)"
_ROW = re.compile(r"^\|\s*`([^`]+)`\s*\|\s*(\w+)\s*\|\s*([^|]+?)\s*\|")


def read_table(path: Path = TABLE) -> dict[str, tuple[str, str]]:
    """label → (kind, printed number without parentheses) for equations and figures."""
    out = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        m = _ROW.match(line)
        if not m:
            continue
        label, kind, shown = m.groups()
        if kind == "equation" and shown.startswith("("):
            out[label] = ("equation", shown.strip("()"))
        elif kind in ("figure", "table"):
            out[label] = (kind, shown.split()[-1])
    return out


def _token_pattern(labels) -> str:
    alts = "|".join(re.escape(lab) for lab in sorted(labels, key=len, reverse=True))
    return rf"(?<![\w.:-])(?:{alts})(?![\w-]|[.:]\w)"


class Relabeler:
    """Rewrites one text at a time; see the module docstring for the rules."""

    def __init__(self, table: dict[str, tuple[str, str]]):
        self.table = table
        tok = _token_pattern(table)
        self.run = re.compile(
            rf"(?P<pre>\b(?i:labels?|eqs?\.?|equations?|figs?\.?|figures?)\s+)?"
            rf"(?P<run>{tok}(?:\(\w\))?(?:{SEP}{tok}(?:\(\w\))?)*)"
        )
        self.tok = re.compile(tok)

    def _cited(self, text: str, m: re.Match, labels: list[str]) -> bool:
        if m.group("pre") or any(lab not in WORDS for lab in labels) or len(labels) > 1:
            return True
        before, after = text[: m.start()], text[m.end() :]
        if labels[0] not in CITED_WORDS:
            return False
        if before.endswith('"') and after.startswith('"'):
            return before.endswith('source="')  # else a whole string: a key or file name
        return (
            (before.endswith("(") and after[:1] in (")", ";", ","))
            or before.endswith('source="')
            or after.startswith(" (ERRATA")
        )

    def _replace(self, text: str, m: re.Match) -> str:
        run, pre = m.group("run"), (m.group("pre") or "")
        labels = [t.group(0) for t in self.tok.finditer(run)]
        before, after = text[: m.start()], text[m.end() :]
        if not self._cited(text, m, labels):
            return m.group(0)
        if (
            before.endswith('"')
            and after.startswith('"')
            and len(labels) == 1
            and not pre
            and not before.endswith('source="')
        ):
            return m.group(0)  # a whole string: a key or file name
        kinds = {self.table[lab][0] for lab in labels}
        in_parens = before.endswith("(") and after.startswith(")") and not pre
        body = self.tok.sub(lambda t: self._number(t.group(0), in_parens, len(kinds) > 1), run)
        if len(kinds) > 1:
            return body
        kind, plural = kinds.pop(), len(labels) > 1
        if in_parens and kind == "equation":
            return ("eqs " if plural else "eq. ") + body
        word = {"equation": ("eq.", "eqs"), "figure": ("figure", "figures"), "table": ("table", "tables")}[
            kind
        ][plural]
        keep = pre.strip().lower().rstrip(".")
        if keep in ("equation", "equations", "figure", "figures", "eqs"):
            word = pre.strip()
        return f"{word} {body}"

    def _number(self, label: str, bare: bool, mixed: bool) -> str:
        kind, num = self.table[label]
        if kind == "equation":
            text = num if bare else f"({num})"
            return f"eq. {text}" if mixed else text
        return f"{kind} {num}" if mixed else num

    def __call__(self, text: str) -> str:
        text = re.sub(r"\b(steadyphase|phase)005/010\b", r"\g<1>005/\g<1>010", text)
        text = re.sub(r"\b(eq:[A-Za-z]+)(\d)–(\d)\b", r"\1\2–\1\3", text)
        text = self.run.sub(lambda m: self._replace(m.string, m), text)
        # "figures 7, 9, 13 (7, 9, 13)": the numbers were already given
        text = re.sub(r"(figures? ([\d, and]+?)) \(\2\)", r"\1", text)
        text = re.sub(r"\bERRATA,? numerical notes", "docs/errata.md, numerical notes", text)
        text = re.sub(r"\(ERRATA(?:\.md)?,? (?:item )?(\d)\)", r"(docs/errata.md, item \1)", text)
        text = re.sub(r"\bERRATA(?:\.md)?,? (?:item )?(\d)\b", r"docs/errata.md, item \1", text)
        text = re.sub(r"\(see also ERRATA\.md\)", "(see also docs/errata.md)", text)
        return re.sub(r"\bERRATA(?:\.md)?\b", "docs/errata.md", text)


def relabel_file(path: Path, relabel: Relabeler, dry_run: bool = False) -> int:
    """Rewrite one file; print and return the number of changed lines."""
    old = path.read_text(encoding="utf-8")
    new = relabel(old)
    changed = 0
    for i, (a, b) in enumerate(zip(old.splitlines(), new.splitlines()), 1):
        if a != b:
            changed += 1
            print(f"{path}:{i}: {a.strip()}\n{' ' * len(str(path))}  → {b.strip()}")
    for i, line in enumerate(new.splitlines(), 1):
        for m in re.finditer(r"\bissues? \d+\b", line, flags=re.IGNORECASE):
            print(f"{path}:{i}: {m.group(0)}: reword by hand: {line.strip()}")
    if changed and not dry_run:
        path.write_text(new, encoding="utf-8")
    return changed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="*", type=Path)
    ap.add_argument("--dry-run", action="store_true", help="Print, do not write.")
    args = ap.parse_args(argv)
    paths = args.paths or [ROOT / "src", ROOT / "README.md"]
    relabel = Relabeler(read_table())
    files = [f for p in paths for f in (sorted(p.rglob("*.py")) if p.is_dir() else [p])]
    total = sum(relabel_file(f, relabel, args.dry_run) for f in files)
    print(f"{total} line(s) {'would change' if args.dry_run else 'changed'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
