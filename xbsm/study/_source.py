"""The text of a study file: its TOML document, the line of every key, the errors.

Every problem found in a study becomes one :class:`StudyError` built by
:meth:`Source.error`, which names the file, the line, the key and what is
allowed, on one line. The helpers below spell values and suggestions the same
way in every message.
"""

from __future__ import annotations

import datetime
import difflib
import re

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["Source", "StudyError", "one_line", "read_toml", "reject_unknown_keys", "section",
           "shown", "suggestion", "unknown_name"]


class StudyError(ValueError):
    """A study file or study table that cannot be run, with the key and line at fault."""


_TOKENS = re.compile(r'''
    (?P<mstring>"""(?:\\.|[^\\])*?"""|'{3}.*?'{3})
  | (?P<string>"(?:\\.|[^"\\\n])*"|'[^'\n]*')
  | (?P<skip>\#[^\n]*|[ \t\r]+)
  | (?P<newline>\n)
  | (?P<punct>\[\[|\]\]|[\[\]{}=,.])
  | (?P<word>[^\s\[\]{}=,.\#"']+)
''', re.S | re.X)


def _unquote(token: str) -> str:
    return token[1:-1] if token[:1] in "\"'" else token


class _KeyLines:
    """Line of the first mention of every key path in valid TOML text.

    A small scanner over tokens: table headers (``[a.b]``, ``[[a.b]]``), dotted
    keys and the keys of inline tables (nested too) are recorded; strings,
    comments and values are skipped. ``lines`` maps a key path (a tuple) to its line.
    """

    def __init__(self, text: str):
        self.lines = {}
        self.table = ()  # the current [table]
        self.stack = []  # "[" for each open array, the key path of each open inline table
        self.keys = []  # the (dotted) key being read
        self.key_line = self.line = 1
        self.value_path = ()  # the key whose value is being read
        self.header = None  # the parts of a [table] header being read
        self.expect_key = True
        for match in _TOKENS.finditer(text):
            self._token(match.lastgroup, match.group())

    def _token(self, kind: str, token: str) -> None:
        if kind in ("newline", "mstring"):
            self.line += token.count("\n")
            if kind == "newline" and not self.stack:
                self.expect_key, self.keys = True, []
        elif kind == "skip":
            return
        elif self.header is not None:
            self._header(token)
        elif self.expect_key:
            self._key(token)
        else:
            self._value(token)

    def _header(self, token: str) -> None:
        if token in ("]", "]]"):
            self.table, self.header = tuple(self.header), None
            for i in range(1, len(self.table) + 1):
                self.lines.setdefault(self.table[:i], self.line)
        elif token != ".":
            self.header.append(_unquote(token))

    def _key(self, token: str) -> None:
        if token in ("[", "[[") and not self.stack and not self.keys:
            self.header = []
        elif token == "=":
            base = self.stack[-1] if self.stack else self.table
            for i in range(1, len(self.keys) + 1):
                self.lines.setdefault((*base, *self.keys[:i]), self.key_line)
            self.value_path, self.keys, self.expect_key = (*base, *self.keys), [], False
        elif token == "}" and self.stack:  # an empty inline table
            self.stack.pop()
            self.expect_key = False
        elif token != ".":
            if not self.keys:
                self.key_line = self.line
            self.keys.append(_unquote(token))

    def _value(self, token: str) -> None:
        if token == "{":
            self.stack.append(self.value_path)
            self.expect_key = True
        elif token in ("[", "[["):
            self.stack.extend("[" * len(token))
        elif token in ("]", "]]"):
            del self.stack[-len(token):]
        elif token == "}":
            self.stack.pop()
        elif token == "," and self.stack and self.stack[-1] != "[":
            self.expect_key = True


class Source:
    """The study text, to say on which line a key was written."""

    def __init__(self, text: str, name: str):
        self.text = text
        self.name = name
        self._lines = None

    def line(self, table: str, key: str | None = None) -> int | None:
        """1-based line of ``table.key`` (or of the nearest enclosing key or table)."""
        if self._lines is None:
            self._lines = _KeyLines(self.text).lines
        path = tuple(part for part in table.split(".") if part) + ((key,) if key else ())
        while path:
            if path in self._lines:
                return self._lines[path]
            path = path[:-1]
        return None

    def error(self, table: str, key: str | None, message: str) -> StudyError:
        """A StudyError naming the file, line and key, on one line."""
        line = self.line(table, key)
        where = ".".join(part for part in (table, key) if part)
        at = f"{self.name}" + (f", line {line}" if line else "")
        return StudyError(one_line(f"{at}: {where or 'study'}: {message}"))


def read_toml(text: str, name: str) -> dict:
    """The TOML document; a syntax error names the line, the column and the line's text."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        message = str(err)
    found = re.search(r"\s*\(at (?:line (\d+), column (\d+)|end of document)\)$", message)
    reason = re.sub(r"\(((?:'[^']*',?\s*)+)\)",  # tomllib's ('a', 'b') is the table [a.b]
                    lambda m: "[" + ".".join(re.findall(r"'([^']*)'", m.group(1))) + "]",
                    message[:found.start()] if found else message)
    lines = text.splitlines()
    line = int(found.group(1)) if found and found.group(1) else len(lines)
    column = f", column {found.group(2)}" if found and found.group(2) else ""
    shown_line = re.sub(r"[\x00-\x08\x0b-\x1f\x7f]", lambda m: f"\\x{ord(m.group()):02x}",
                        lines[line - 1].strip() if 0 < line <= len(lines) else "")
    raise StudyError(one_line(
        f"{name}, line {line}{column}: not valid TOML ({reason}) in: {shown_line[:80]} "
        "(the syntax is TOML 1.0, https://toml.io; see docs/study.md)"))


def section(src: Source, doc: dict, name: str, allowed=None) -> dict:
    """The table ``doc[name]`` as a dict (empty if absent); keys not in ``allowed`` are errors."""
    value = doc.get(name, {})
    if not isinstance(value, dict):
        raise src.error("", name, f"must be a table ([{name}]); got {shown(value)}")
    if allowed is not None:
        reject_unknown_keys(src, name, value, allowed)
    return value


def reject_unknown_keys(src: Source, table: str, given: dict, allowed) -> None:
    """An error for the first key of ``given`` that is not in ``allowed``."""
    for key in given:
        if key not in allowed:
            raise src.error(table, key, f"unknown key; {suggestion(key, allowed)}")


def one_line(message: str) -> str:
    """A message on one line, numbers printed as numbers (never ``np.float64(...)``)."""
    message = re.sub(r"np\.(?:float|int|uint|bool_?)\d*\(([^()]*)\)", r"\1", message)
    return " ".join(message.split())


def suggestion(given: str, known) -> str:
    """The closest names of ``known`` to a misspelt ``given``, or all of them."""
    close = difflib.get_close_matches(given, list(known), n=3)
    return (f"did you mean {' or '.join(map(repr, close))}?" if close
            else f"allowed: {', '.join(sorted(known))}")


def unknown_name(what: str, given, known) -> str:
    """The message for a name that is not one of ``known`` (or not a name at all)."""
    if not isinstance(given, str):
        names = ", ".join(sorted(known))
        return f"must be the name of a {what} in quotes, one of {names}; got {shown(given)}"
    return f"unknown {what} {shown(given)}; {suggestion(given, known)}"


def shown(value) -> str:
    """A value spelled roughly as TOML writes it, at most 60 characters."""
    if isinstance(value, bool):
        text = str(value).lower()
    elif isinstance(value, str):
        text = '"' + value.replace('"', '\\"') + '"'
    elif isinstance(value, (datetime.date, datetime.time)):
        text = f"{value.isoformat()} (a date or time)"
    elif isinstance(value, list):
        text = "[" + ", ".join(shown(item) for item in value[:20]) + "]"
    elif isinstance(value, dict):
        text = "{" + ", ".join(f"{k} = {shown(v)}" for k, v in list(value.items())[:20]) + "}"
    else:
        text = repr(value)
    return text if len(text) <= 60 else text[:56] + " ..."
