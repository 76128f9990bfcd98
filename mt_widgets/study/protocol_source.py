"""Where a field of a protocol file is: the 1-based line of a table or key in TOML or JSON text.

``tomllib`` and ``json`` keep no line numbers, so a validation error (``ProtocolError``) would
otherwise say only which field is wrong. The TOML side scans the text table by table; the
JSON side finds a field's first occurrence inside its phase.
"""

from __future__ import annotations

import re


class SourceLocator:
    """Finds the line of a table or a key in TOML/JSON text (1-based), or None."""

    def __init__(self, text: str, kind: str):
        self.lines = text.splitlines()
        self.kind = kind

    def _table_spans(self, table: str, array: bool):
        """(start, end) line indices of each ``[table]`` / ``[[table]]`` section."""
        header = re.compile(r"^\s*\[\[\s*" + re.escape(table) + r"\s*\]\]" if array
                            else r"^\s*\[\s*" + re.escape(table) + r"\s*\]")
        any_header = re.compile(r"^\s*\[")
        spans, start = [], None
        for i, line in enumerate(self.lines):
            if any_header.match(line):
                if start is not None:
                    spans.append((start, i))
                    start = None
                if header.match(line):
                    start = i
        if start is not None:
            spans.append((start, len(self.lines)))
        return spans

    def _top_span(self):
        for i, line in enumerate(self.lines):
            if re.match(r"^\s*\[", line):
                return 0, i
        return 0, len(self.lines)

    def _json_phase_spans(self):
        # The n-th "{" after the '"phases"' key opens phase n when phases are written one per
        # object, as the shipped files and any hand-written JSON protocol are.
        spans, inside = [], False
        depth, start = 0, None
        for i, line in enumerate(self.lines):
            if not inside and re.search(r'"phases"\s*:', line):
                inside = True
            if inside:
                for ch in line:
                    if ch == "{":
                        if depth == 0:
                            start = i
                        depth += 1
                    elif ch == "}":
                        depth -= 1
                        if depth == 0 and start is not None:
                            spans.append((start, i + 1))
                    elif ch == "]" and depth == 0 and spans:
                        return spans
        return spans

    def _step_line(self, path: tuple) -> int | None:
        """Line of a field of a ``[[before]]`` / ``[[after]]`` step or of one of its ``items``."""
        table, index = path[0], path[1]
        header = re.compile(r"^\s*\[")
        own = re.compile(r"^\s*\[\[\s*" + table + r"\s*\]\]")
        nested = re.compile(r"^\s*\[\[\s*" + table + r"\.items\s*\]\]")
        starts = [i for i, line in enumerate(self.lines) if own.match(line)]
        if index >= len(starts):
            return None
        start = starts[index]
        end = next((i for i in range(start + 1, len(self.lines))
                    if header.match(self.lines[i]) and not nested.match(self.lines[i])), len(self.lines))
        key = path[2] if len(path) > 2 else None
        if key == "items" and len(path) > 3 and isinstance(path[3], int):
            items = [i for i in range(start, end) if nested.match(self.lines[i])]
            if path[3] < len(items):
                item_end = next((i for i in range(items[path[3]] + 1, end) if header.match(self.lines[i])), end)
                start, end = items[path[3]], item_end
                key = path[4] if len(path) > 4 else None
        if isinstance(key, str):
            pattern = re.compile(r'^\s*"?' + re.escape(key) + r'"?\s*=')
            for i in range(start, end):
                if pattern.match(self.lines[i]):
                    return i + 1
        return start + 1

    def line(self, path: tuple) -> int | None:
        """Line of ``path`` (e.g. ("phases", 2, "episodes")); falls back to its table."""
        if self.kind == "toml" and len(path) > 1 and path[0] in ("before", "after") and isinstance(path[1], int):
            return self._step_line(path)
        if self.kind == "json":
            span = (0, len(self.lines))
            if path and path[0] == "phases" and len(path) > 1 and isinstance(path[1], int):
                spans = self._json_phase_spans()
                if path[1] < len(spans):
                    span = spans[path[1]]
            key = path[-1] if path and isinstance(path[-1], str) else None
            if key:
                for i in range(*span):
                    if re.search(r'"' + re.escape(key) + r'"\s*:', self.lines[i]):
                        return i + 1
            return span[0] + 1 if span[0] or len(path) > 1 else None
        if not path:
            return None
        if path[0] == "phases" and len(path) > 1 and isinstance(path[1], int):
            spans = self._table_spans("phases", array=True)
            if path[1] >= len(spans):
                return None
            span, key = spans[path[1]], (path[2] if len(path) > 2 else None)
        elif len(path) > 1 and isinstance(path[1], str):
            spans = self._table_spans(path[0], array=False)
            if not spans:
                return None
            span, key = spans[0], path[1]
        else:
            span, key = self._top_span(), path[0]
            spans = self._table_spans(path[0], array=False) or self._table_spans(path[0], array=True)
            if spans and len(path) == 1:
                return spans[0][0] + 1
        if key is not None:
            pattern = re.compile(r'^\s*"?' + re.escape(str(key)) + r'"?\s*=')
            for i in range(*span):
                if pattern.match(self.lines[i]):
                    return i + 1
        return span[0] + 1 if span[0] or path[0] == "phases" else None


def path_name(path: tuple) -> str:
    name = ""
    for part in path:
        name += f"[{part}]" if isinstance(part, int) else ("." if name else "") + part
    return name
